"""One entry point for every blade source: the built-in sample, a geometry table, or a mesh.

SOURCE strings (the CLI's --blade and the GUI's project files):
- ``sample``: the built-in sample blade (resources/sample_blade.csv), the default everywhere;
- a path ending in .csv or .txt: a propeller geometry table (core.blade.table);
- a path ending in .stl, .obj or .ply: one closed blade mesh;
- two mesh paths separated by a comma: face and back surfaces (core.blade.mesh); a file whose name holds
  a comma is read as one file when it exists (``source_parts``).
"""

from __future__ import annotations

from pathlib import Path

from core.blade.mesh import load_mesh_blade
from core.blade.model import Blade
from core.blade.table import load_table_blade
from core.errors import BladeInputError
from core.util.resources import resources_dir

SAMPLE = "sample"
MESH_SUFFIXES = (".stl", ".obj", ".ply")
TABLE_SUFFIXES = (".csv", ".txt")
AXES = ("x", "y", "z")


def source_parts(source: str, base: str | Path | None = None) -> list[str]:
    """The file paths a SOURCE string names (stripped; relative ones checked against ``base``, default
    the current folder): the whole string when it names an existing file (a file name may hold a
    comma), else two existing files at the first comma that splits it into two, else its
    comma-separated parts."""
    text = (source or "").strip()

    def exists(part: str) -> bool:
        p = Path(part)
        return (p if p.is_absolute() or base is None else Path(base) / p).is_file()

    if "," not in text or exists(text):
        return [text] if text else []
    for i, c in enumerate(text):
        if c == "," and exists(text[:i].strip()) and exists(text[i + 1:].strip()):
            return [text[:i].strip(), text[i + 1:].strip()]
    return [p.strip() for p in text.split(",") if p.strip()]


def sample_table_path() -> Path:
    return resources_dir() / "sample_blade.csv"


def load_blade(source: str = SAMPLE, axis: str = "z") -> Blade:
    """Build the blade named by a SOURCE string (see the module docstring).

    axis : 'x', 'y' or 'z', the propeller axis of a mesh (ignored for tables and the sample).
    Raises BladeInputError with the file and what to do for every bad source.
    """
    source = (source or SAMPLE).strip()
    axis = (axis or "z").strip().lower()
    if axis not in AXES:
        raise BladeInputError(f"axis {axis!r} is not one of x, y, z")
    if source.lower() == SAMPLE:
        blade = load_table_blade(sample_table_path())
        blade.source = SAMPLE
        return blade
    parts = source_parts(source)
    if not parts:
        raise BladeInputError("empty blade source: give 'sample', a geometry table or mesh file(s)")
    suffixes = {Path(p).suffix.lower() for p in parts}
    if len(parts) == 1 and suffixes <= set(TABLE_SUFFIXES):
        return load_table_blade(parts[0])
    if suffixes <= set(MESH_SUFFIXES):
        return load_mesh_blade(parts if len(parts) > 1 else parts[0], axis=axis)
    raise BladeInputError(
        f"{source}: unknown blade source; give 'sample', a geometry table (.csv), one mesh file "
        f"(.stl, .obj, .ply) or two mesh files separated by a comma (face,back)"
    )
