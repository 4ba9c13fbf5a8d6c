"""One entry point for every blade source: the built-in sample, a geometry table, or a mesh.

SOURCE strings (the CLI's --blade and the GUI's project files):
- ``sample``: the built-in sample blade (resources/sample_blade.csv), the default everywhere;
- a path ending in .csv or .txt: a propeller geometry table (core.geometry_table);
- a path ending in .stl, .obj or .ply: one closed blade mesh;
- two mesh paths separated by a comma: face and back surfaces (core.mesh_blade).
"""

from __future__ import annotations

from pathlib import Path

from .blade import Blade
from .errors import BladeInputError

SAMPLE = "sample"
MESH_SUFFIXES = (".stl", ".obj", ".ply")
TABLE_SUFFIXES = (".csv", ".txt")
AXES = ("x", "y", "z")


def resources_dir() -> Path:
    """The folder of shipped resources (sample blade, default machine)."""
    return Path(__file__).resolve().parent.parent / "resources"


def sample_table_path() -> Path:
    return resources_dir() / "sample_blade.csv"


def load_blade(source: str = SAMPLE, axis: str = "z") -> Blade:
    """Build the blade named by a SOURCE string (see the module docstring).

    axis : 'x', 'y' or 'z', the propeller axis of a mesh (ignored for tables and the sample).
    Raises BladeInputError with the file and what to do for every bad source.
    """
    from .geometry_table import load_table_blade

    source = (source or SAMPLE).strip()
    axis = (axis or "z").strip().lower()
    if axis not in AXES:
        raise BladeInputError(f"axis {axis!r} is not one of x, y, z")
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
        from .mesh_blade import load_mesh_blade

        return load_mesh_blade(parts if len(parts) > 1 else parts[0], axis=axis)
    raise BladeInputError(
        f"{source}: unknown blade source; give 'sample', a geometry table (.csv), one mesh file "
        f"(.stl, .obj, .ply) or two mesh files separated by a comma (face,back)"
    )
