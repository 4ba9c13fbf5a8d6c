"""One entry point for every blade source: the built-in sample, a geometry table, or a mesh.

SOURCE strings (the CLI's --blade and the GUI's project files):
- ``sample``: the built-in sample blade (resources/sample_blade.csv), the default everywhere;
- a path ending in .csv or .txt: a propeller geometry table (core.blade.table);
- a path ending in .stl, .obj or .ply: one closed blade mesh;
- two mesh paths separated by a comma: face and back surfaces (core.blade.mesh);
- a path ending in .step, .stp, .igs or .iges: one closed blade as exact CAD surfaces, or two such
  paths separated by a comma: face and back (core.blade.cad, read through OpenCASCADE only then).
"""

from __future__ import annotations

from pathlib import Path

from core.blade.cad import CAD_SUFFIXES, load_cad_blade
from core.blade.mesh import load_mesh_blade
from core.blade.model import Blade
from core.blade.placement import parse_axis, unit_factor, unit_hint
from core.blade.table import load_table_blade
from core.errors import BladeInputError
from core.util.resources import resources_dir

SAMPLE = "sample"
MESH_SUFFIXES = (".stl", ".obj", ".ply")
TABLE_SUFFIXES = (".csv", ".txt")
AXES = ("x", "y", "z")


def sample_table_path() -> Path:
    return resources_dir() / "sample_blade.csv"


def load_blade(source: str = SAMPLE, axis: str = "z", units: str = "mm") -> Blade:
    """Build the blade named by a SOURCE string (see the module docstring).

    axis : an AXIS string (core.blade.placement: 'x', 'y', 'z' or a direction, optionally through a
    point), the propeller axis of a mesh or CAD file (ignored for tables and the sample); units : what
    a mesh's numbers mean (mm, cm, m, in; tables and CAD files state their own: mm only). A mesh or CAD
    blade whose size is no propeller's in the unit given carries a warning naming the unit that fits.
    Raises BladeInputError with the file and what to do for every bad source.
    """
    source = (source or SAMPLE).strip()
    axis = (axis or "z").strip().lower()
    parse_axis(axis)  # (a bad axis is refused before any file is read)
    scale = unit_factor(units)
    if scale != 1.0 and not (suffixes_of(source) <= set(MESH_SUFFIXES)):
        raise BladeInputError(f"{source}: --units {units} applies to meshes (an STL states no unit); a geometry "
                              "table gives its sizes in mm (diameter_mm) and a CAD file states its own unit")
    if source.lower() == SAMPLE:
        blade = load_table_blade(sample_table_path())
        blade.source = SAMPLE
        return blade
    parts = [p.strip() for p in source.split(",") if p.strip()]
    if not parts:
        raise BladeInputError("empty blade source: give 'sample', a geometry table or mesh file(s)")
    suffixes = {Path(p).suffix.lower() for p in parts}
    if len(parts) == 1 and suffixes <= set(TABLE_SUFFIXES):
        return load_table_blade(parts[0])
    if suffixes <= set(MESH_SUFFIXES):
        return _hinted(load_mesh_blade(parts if len(parts) > 1 else parts[0], axis=axis, scale=scale), units)
    if suffixes <= set(CAD_SUFFIXES):
        return _hinted(load_cad_blade(parts if len(parts) > 1 else parts[0], axis=axis), units)
    raise BladeInputError(
        f"{source}: unknown blade source; give 'sample', a geometry table (.csv), one mesh file "
        f"(.stl, .obj, .ply) or two mesh files separated by a comma (face,back), or the same as CAD files "
        f"(.step, .stp, .igs, .iges)"
    )


def suffixes_of(source: str) -> set[str]:
    """The file suffixes (lower case) of a SOURCE string's parts ('sample' has none)."""
    return {Path(p.strip()).suffix.lower() for p in source.split(",") if p.strip()}


def _hinted(blade: Blade, units: str) -> Blade:
    """The blade, with a warning when its size is no propeller's in the unit given (placement.unit_hint)."""
    hint = unit_hint(blade.tip_radius, units)
    if hint is not None:
        blade.warnings.append(f"{blade.name}: {hint}")
    return blade
