"""One entry point for every blade source: the built-in sample, a geometry table, or a mesh.

SOURCE strings (the CLI's --blade and the GUI's project files):
- ``sample``: the built-in sample blade (resources/sample_blade.csv), the default everywhere;
- a path ending in .csv or .txt: a propeller geometry table (core.blade.table);
- a path ending in .stl, .obj or .ply: one closed blade mesh;
- two mesh paths separated by a comma: face and back surfaces (core.blade.mesh); a file whose name holds
  a comma is read as one file when it exists (``source_parts``);
- a path ending in .step, .stp, .igs or .iges: one closed blade as exact CAD surfaces, or two such
  paths separated by a comma: face and back (core.blade.cad, read through OpenCASCADE only then).

Any of them may end in reading options after a ``?``, ``key=value`` pairs joined by ``&``
(``SourceOptions``; the CLI's --blade-index, --r-min and --units and the project file's [blade] keys
write them): ``blade=K`` picks blade K of a whole propeller given as one mesh or CAD file and
``r_min=MM`` cuts its hub there (core.blade.propeller, core.blade.cad_propeller), ``units=U`` says what
a mesh's numbers mean (core.blade.placement.UNITS).
So the one SOURCE string that plan.json records names the blade exactly, and verify reloads it.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core.blade.cad import CAD_SUFFIXES, FaceGroup, read_cad
from core.blade.cad_propeller import load_cad_blade
from core.blade.mesh import axis_problem, load_mesh_blade, read_mesh
from core.blade.model import Blade
from core.blade.placement import parse_axis, unit_factor, unit_hint
from core.blade.propeller import Propeller, listing, split_propeller
from core.blade.table import load_table_blade
from core.errors import BladeInputError
from core.util.resources import resources_dir

SAMPLE = "sample"
MESH_SUFFIXES = (".stl", ".obj", ".ply")
TABLE_SUFFIXES = (".csv", ".txt")
AXES = ("x", "y", "z")


@dataclass(frozen=True)
class SourceOptions:
    """A SOURCE string's reading options (see the module): blade, the number (from 1) of the blade of
    a whole propeller (None: the file is one blade, or blade 1 of a propeller with a warning); r_min,
    the hub cut in mm (None: found from the geometry); units of a mesh's numbers (None: mm)."""

    blade: int | None = None
    r_min: float | None = None
    units: str | None = None

    def text(self) -> str:
        """The options as they follow the ``?`` ('' when there are none)."""
        pairs = [("blade", self.blade), ("r_min", None if self.r_min is None else f"{self.r_min:g}"),
                 ("units", self.units)]
        return "&".join(f"{k}={v}" for k, v in pairs if v is not None)


OPTION_KEYS = ("blade", "r_min", "units")


def split_options(source: str) -> tuple[str, SourceOptions]:
    """(the SOURCE string without its options, its SourceOptions). BladeInputError naming a bad option."""
    text = (source or "").strip()
    files, mark, query = text.rpartition("?")
    if not mark:
        return text, SourceOptions()
    values: dict = {}
    for pair in filter(None, (q.strip() for q in query.split("&"))):
        key, eq, value = (x.strip() for x in pair.partition("="))
        if not eq or key not in OPTION_KEYS:
            raise BladeInputError(f"{text}: the reading option {pair!r} is not one of "
                                  f"{', '.join(k + '=...' for k in OPTION_KEYS)}")
        values[key] = value
    return files.strip(), make_options(values.get("blade"), values.get("r_min"), values.get("units"))


def make_options(blade=None, r_min=None, units=None) -> SourceOptions:
    """SourceOptions from numbers or their texts (None: not given), checked: blade a whole number from
    1, r_min a finite number of mm >= 0, units one of UNITS. BladeInputError naming the bad one."""
    if blade is not None:
        try:
            blade = int(str(blade).strip())
        except ValueError:
            blade = 0
        if blade < 1:
            raise BladeInputError(f"the blade index must be a whole number from 1 (blade 1, 2, ... of the "
                                  f"propeller), got {blade!r}")
    if r_min is not None:
        try:
            r_min = float(str(r_min).strip())
        except ValueError:
            r_min = math.nan
        if not (math.isfinite(r_min) and r_min >= 0):
            raise BladeInputError(f"the hub cut r_min must be a number of mm >= 0, got {r_min!r}")
    if units is not None:
        units = str(units).strip().lower()
        unit_factor(units)
        units = None if units == "mm" else units
    return SourceOptions(blade, r_min, units)


def with_options(source: str, options: SourceOptions) -> str:
    """The SOURCE string with ``options`` in place of its own ('sample' and no options: as it is)."""
    files, _ = split_options(source)
    text = options.text()
    return f"{files}?{text}" if text else files


def merged_options(source: str, blade=None, r_min=None, units=None) -> str:
    """The SOURCE string with these reading options in place of its own where they are not None."""
    own = split_options(source)[1]
    return with_options(source, make_options(own.blade if blade is None else blade,
                                             own.r_min if r_min is None else r_min,
                                             own.units if units is None else units))


def absolute_source(source: str) -> str:
    """The SOURCE string with each of its files made absolute ('sample' as it is): plan.json records the
    source, and ``bladecam verify`` reloads the blade from it, from whatever folder it is run in."""
    files, opts = split_options(source)
    if files.lower() == SAMPLE:
        return source
    return with_options(",".join(os.path.abspath(part) for part in source_parts(source)), opts)


def source_parts(source: str, base: str | Path | None = None) -> list[str]:
    """The file paths a SOURCE string names, without its options (stripped; relative ones checked
    against ``base``, default the current folder): the whole string when it names an existing file (a
    file name may hold a comma), else two existing files at the first comma that splits it into two,
    else its comma-separated parts."""
    text = split_options(source)[0]

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


def load_blade(source: str = SAMPLE, axis: str = "z", units: str = "mm") -> Blade:
    """Build the blade named by a SOURCE string (see the module docstring).

    axis : an AXIS string (core.blade.placement: 'x', 'y', 'z' or a direction, optionally through a
    point), the propeller axis of a mesh or CAD file (ignored for tables and the sample); units : what
    a mesh's numbers mean (mm, cm, m, in; tables and CAD files state their own: mm only). A mesh or CAD
    blade whose size is no propeller's in the unit given carries a warning naming the unit that fits.
    Raises BladeInputError with the file and what to do for every bad source.
    """
    full = (source or SAMPLE).strip()
    source, opts = split_options(full)
    axis = (axis or "z").strip().lower()
    parse_axis(axis)  # (a bad axis is refused before any file is read)
    if opts.units is not None:
        if unit_factor(units) != 1.0 and units != opts.units:
            raise BladeInputError(f"{full}: units given twice ({units} and {opts.units}); give one")
        units = opts.units
    scale = unit_factor(units)
    meshes = suffixes_of(source) <= set(MESH_SUFFIXES) and source.lower() != SAMPLE
    if scale != 1.0 and not meshes:
        raise BladeInputError(f"{source}: --units {units} applies to meshes (an STL states no unit); a geometry "
                              "table gives its sizes in mm (diameter_mm) and a CAD file states its own unit")
    one_file = len(source_parts(source)) == 1 and source.lower() != SAMPLE
    if (opts.blade is not None or opts.r_min is not None) and not (
            one_file and suffixes_of(source) <= set(MESH_SUFFIXES + CAD_SUFFIXES)):
        raise BladeInputError(f"{full}: the blade index and the hub cut (--blade-index, --r-min) pick one blade "
                              "of a whole propeller given as one mesh file (.stl, .obj, .ply) or one CAD file "
                              "(.step, .stp, .igs, .iges)")
    if source.lower() == SAMPLE:
        sample = load_table_blade(sample_table_path())
        sample.source = SAMPLE
        return sample
    parts = source_parts(source)
    if not parts:
        raise BladeInputError("empty blade source: give 'sample', a geometry table or mesh file(s)")
    suffixes = {Path(p).suffix.lower() for p in parts}
    if len(parts) == 1 and suffixes <= set(TABLE_SUFFIXES):
        return load_table_blade(parts[0])
    if suffixes <= set(MESH_SUFFIXES):
        blade = load_mesh_blade(parts if len(parts) > 1 else parts[0], axis=axis, scale=scale,
                                pick=(opts.blade, opts.r_min))
        if blade.propeller is not None:
            blade.source = with_options(",".join(parts), opts)
        return _hinted(blade, units)
    if suffixes <= set(CAD_SUFFIXES):
        blade = load_cad_blade(parts if len(parts) > 1 else parts[0], axis=axis, pick=(opts.blade, opts.r_min))
        if blade.propeller is not None:
            blade.source = with_options(",".join(parts), opts)
        return _hinted(blade, units)
    raise BladeInputError(
        f"{source}: unknown blade source; give 'sample', a geometry table (.csv), one mesh file "
        f"(.stl, .obj, .ply) or two mesh files separated by a comma (face,back), or the same as CAD files "
        f"(.step, .stp, .igs, .iges)"
    )


def whole_propeller(source: str, axis: str = "z") -> Propeller | None:
    """The blades of the whole propeller a SOURCE string names: one mesh or CAD file that does not lie
    beside ``axis`` as one blade does and holds two blades or more outside its hub, found as load_blade
    finds them (its own hub cut r_min when it gives one, its units); None for any other source.
    BladeInputError for a file that cannot be read or a bad axis."""
    files, opts = split_options(source)
    parts = source_parts(source)
    if files.lower() == SAMPLE or len(parts) != 1:
        return None
    suffix = Path(parts[0]).suffix.lower()
    _, rot, point = parse_axis(axis)
    if suffix in MESH_SUFFIXES:
        mesh, scale = read_mesh(parts[0]), unit_factor(opts.units or "mm")
        v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    elif suffix in CAD_SUFFIXES:
        group, scale = FaceGroup.of_shape(read_cad(parts[0])), 1.0
        v, f = np.asarray(group.mesh.vertices), group.triangles
    else:
        return None
    if axis_problem(v * scale, rot, point * scale) is None:
        return None
    try:
        prop = split_propeller(v, f, rot, point * scale, scale, r_min=opts.r_min)
    except BladeInputError:
        return None
    return prop if len(prop.blades) > 1 else None


def info_lines(info: dict, unpicked: bool = True) -> list[str]:
    """The text of ``bladecam blade info`` from Blade.info(): the blade, the blades of a whole propeller
    (``unpicked``: none was asked for, blade 1 is measured), the radii, chords and thicknesses."""
    lines = [f"blade {info['name']!r} from {info['source']}"]
    if "propeller" in info:
        lines += listing(info["propeller"], unpicked)
    lines += [f"  tip radius  {info['tip_radius_mm']:10.3f} mm", f"  hub radius  {info['hub_radius_mm']:10.3f} mm",
              "  r/R      chord mm   max thickness mm"]
    for key, chord in info["chord_mm"].items():
        thick = info["max_thickness_mm"][key]
        lines.append(f"  {key:<6}   (inside the hub)" if chord is None else f"  {key:<6} {chord:10.3f} {thick:12.3f}")
    errors = info.get("section_error_estimate_mm")
    if errors:
        shown = ", ".join(f"{e:.3f} mm at {k}" for k, e in errors.items() if e is not None)
        lines.append(f"  sections from the facets may lie up to about {shown} R off the smooth blade (an estimate "
                     "from the facets' size and the turn between them; exact CAD surfaces have no such error)")
    return lines


def suffixes_of(source: str) -> set[str]:
    """The file suffixes (lower case) of a SOURCE string's parts ('sample' has none)."""
    return {Path(p.strip()).suffix.lower() for p in split_options(source)[0].split(",") if p.strip()}


def _hinted(blade: Blade, units: str) -> Blade:
    """The blade, with a warning when its size is no propeller's in the unit given (placement.unit_hint)."""
    hint = unit_hint(blade.tip_radius, units)
    if hint is not None:
        blade.warnings = [*blade.warnings, f"{blade.name}: {hint}"]
    return blade
