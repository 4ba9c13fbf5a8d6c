"""Project files: the blade source and every planning input in one small, human-readable TOML file.

    # bladecam project
    format = 1

    [blade]
    source = "sample"          # 'sample', a table (.csv), a mesh, "face.stl,back.stl", or CAD (.step, .igs)
    axis = "z"
    index = 2                  # optional: blade 2 of a whole propeller, one mesh or CAD file (core.blade.propeller)
    r_min = 38.5               # optional: cut its hub off at r = 38.5 mm (absent: found from the geometry)
    units = "mm"               # optional: what a mesh's numbers mean (mm, cm, m, in; absent: mm)

    [parameters]               # every PlanParameters field; "auto" = the default from the tool radius
    tool_radius = 1.5
    dr = "auto"
    ...
    mode = "collaborative"

    [schedule]
    profile = "sigmoid"
    period_ms = "auto"         # "auto" = dd at the feed
    axes = false               # plan for the two machines and write their axis tables

    [tool]                     # optional: the tool assembly (core.machine.tool); absent = the shipped one
    file = "my_tool.toml"      # its tool_radius and tool_length above must be the file's ball and stick-out

The optional [blade] keys index, r_min and units become the blade SOURCE string's reading options
(core.blade.source: ``Project.source`` is "propeller.stl?blade=2&r_min=38.5"), written back as the keys.
Relative blade and tool paths are relative to the project file's folder (written relative when the blade lies
next to or below it). Loading validates every key (unknown, missing or mistyped keys and impossible
values) and raises ProjectError naming the file and the key.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from core.blade.placement import parse_axis
from core.blade.source import SAMPLE, make_options, source_parts, split_options, with_options
from core.errors import BladeInputError, OutputError, PlanningError, ProjectError
from core.records import PlanParameters
from core.util.files import parse_toml, write_text_whole

FORMAT = 1
PROFILES = ("sigmoid", "smooth")
AUTO = "auto"
#: PlanParameters fields that may be "auto" (None: derived from the tool radius or the feed)
AUTO_FIELDS = ("dr", "h_safe", "min_feed")
#: parameters a project file may leave out (files written before they existed): the default
OPTIONAL_FIELDS = ("min_feed",)


@dataclass(frozen=True)
class Project:
    """What a project file holds: blade source and axis, planning parameters, schedule options.

    source : blade SOURCE string (paths absolute once loaded); axis : 'x' | 'y' | 'z';
    params : PlanParameters (None fields = defaults); profile : 'sigmoid' | 'smooth';
    period : ms or None (dd at the feed); axes : plan for the machines, with axis tables (optional key);
    tool : the tool file's path (absolute once loaded) or None (the shipped assembly)
    """

    source: str = SAMPLE
    axis: str = "z"
    params: PlanParameters = field(default_factory=PlanParameters)
    profile: str = "sigmoid"
    period: float | None = None
    axes: bool = False
    tool: str | None = None


def _toml_value(v) -> str:
    if v is None:
        return f'"{AUTO}"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise OutputError(f"cannot write the non-finite number {v} into a project file")
        return repr(v)
    s = str(v).replace("\\", "\\\\").replace('"', '\\"')
    return f'"{s}"'


def _reading_options(blade: dict, where: str):
    """The [blade] table's optional index, r_min and units as SourceOptions (ProjectError naming a bad one)."""
    index, r_min, units = blade.get("index"), blade.get("r_min"), blade.get("units")
    if index is not None and (isinstance(index, bool) or not isinstance(index, int) or index < 1):
        raise ProjectError(f"{where}: [blade] index = {index!r} must be a whole number from 1 (the blade of a "
                           "whole propeller)")
    if r_min is not None and (isinstance(r_min, bool) or not isinstance(r_min, (int, float))
                              or not math.isfinite(r_min) or r_min < 0):
        raise ProjectError(f"{where}: [blade] r_min = {r_min!r} must be a number of mm >= 0 (the hub cut)")
    try:
        return make_options(index, r_min, units if units is None else str(units))
    except BladeInputError:
        raise ProjectError(f"{where}: [blade] units = {units!r} must be one of mm, cm, m, in") from None


def _relative_source(source: str, folder: Path) -> str:
    if source.strip().lower() == SAMPLE:
        return SAMPLE
    out = []
    for part in source_parts(source):
        p = Path(part)
        if p.is_absolute():
            try:
                part = os.path.relpath(p, folder)
                if part.startswith(".."):
                    part = str(p)
            except ValueError:  # another drive
                part = str(p)
        out.append(part)
    return ",".join(out)


def project_text(project: Project, folder: str | Path | None = None) -> str:
    """The TOML text of a project; blade paths relative to ``folder`` when they lie inside it."""
    source, opts = split_options(project.source)
    if folder is not None:
        source = _relative_source(source, Path(folder).resolve())
    lines = ["# bladecam project: blade source and planning inputs (edit freely; \"auto\" = default)",
             f"format = {FORMAT}", "", "[blade]", f"source = {_toml_value(source)}",
             f"axis = {_toml_value(project.axis)}"]
    lines += [f"{key} = {_toml_value(value)}" for key, value in
              (("index", opts.blade), ("r_min", opts.r_min), ("units", opts.units)) if value is not None]
    lines += ["", "[parameters]"]
    for f in fields(PlanParameters):
        lines.append(f"{f.name} = {_toml_value(getattr(project.params, f.name))}")
    lines += ["", "[schedule]", f"profile = {_toml_value(project.profile)}",
              f"period_ms = {_toml_value(project.period)}", f"axes = {_toml_value(bool(project.axes))}", ""]
    if project.tool is not None:
        tool = project.tool if folder is None else _relative_source(project.tool, Path(folder).resolve())
        lines += ["[tool]", f"file = {_toml_value(tool)}", ""]
    return "\n".join(lines)


def save_project(project: Project, path: str | Path) -> Path:
    """Write a project file atomically (a temporary file renamed into place). OutputError on failure."""
    path = Path(path)
    text = project_text(project, path.resolve().parent)
    return write_text_whole(path, text, "the project file")


def _table(data: dict, name: str, where: str, keys: set[str]) -> dict:
    t = data.get(name)
    if not isinstance(t, dict):
        raise ProjectError(f"{where}: missing table [{name}]")
    unknown = sorted(set(t) - keys)
    if unknown:
        raise ProjectError(f"{where}: unknown key [{name}] {unknown[0]}; allowed: {', '.join(sorted(keys))}")
    return t


def _finite(v: int | float) -> bool:
    """A finite number a float holds (an integer of 400 digits is not one)."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _number(t: dict, table: str, key: str, where: str, auto: bool) -> float | None:
    if key not in t:
        raise ProjectError(f"{where}: missing key [{table}] {key}")
    v = t[key]
    if auto and v == AUTO:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not _finite(v):
        expect = f'a number or "{AUTO}"' if auto else "a number"
        shown = repr(v) if len(repr(v)) <= 40 else repr(v)[:37] + f"... ({len(repr(v))} digits)"
        raise ProjectError(f"{where}: [{table}] {key} = {shown} must be {expect} (finite, within a float's "
                           "range)")
    return float(v)


def _choice(t: dict, table: str, key: str, where: str, choices: tuple[str, ...]) -> str:
    if key not in t:
        raise ProjectError(f"{where}: missing key [{table}] {key}")
    v = t[key]
    if v not in choices:
        raise ProjectError(f"{where}: [{table}] {key} = {v!r} must be one of {', '.join(choices)}")
    return v


def load_project(path: str | Path) -> Project:
    """Read and validate a project file; blade paths come back absolute. ProjectError names the key."""
    path = Path(path)
    where = str(path)
    try:
        data = parse_toml(path.read_text(encoding="utf-8-sig"))  # (a byte order mark is accepted)
    except OSError as exc:
        raise ProjectError(f"cannot read the project file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ProjectError(f"{where}: not a text file; a project file is TOML text") from None
    except tomllib.TOMLDecodeError as exc:
        raise ProjectError(f"{where}: not a valid TOML project file ({exc}); fix the line it names") from None
    unknown = sorted(set(data) - {"format", "blade", "parameters", "schedule", "tool"})
    if unknown:
        raise ProjectError(f"{where}: unknown key or table {unknown[0]!r}")
    if data.get("format") != FORMAT:
        raise ProjectError(f"{where}: format = {data.get('format')!r}; this bladecam reads format = {FORMAT}")
    blade = _table(data, "blade", where, {"source", "axis", "index", "r_min", "units"})
    source = blade.get("source")
    if not isinstance(source, str) or not source.strip():
        raise ProjectError(f"{where}: [blade] source must be 'sample' or a blade file path, got {source!r}")
    if "axis" not in blade:
        raise ProjectError(f"{where}: missing key [blade] axis")
    axis = blade["axis"]
    try:
        parse_axis(axis if isinstance(axis, str) else "?")
    except BladeInputError:
        raise ProjectError(f"{where}: [blade] axis = {axis!r} must be x, y, z or a direction DX,DY,DZ, optionally "
                           "followed by @PX,PY,PZ (a point of the axis)") from None
    try:
        inline = split_options(source)[1]
    except BladeInputError as exc:
        raise ProjectError(f"{where}: [blade] source: {exc}") from None
    keys = _reading_options(blade, where)
    options = make_options(*(inline_v if key_v is None else key_v for key_v, inline_v in
                             ((keys.blade, inline.blade), (keys.r_min, inline.r_min), (keys.units, inline.units))))
    if split_options(source)[0].lower() != SAMPLE:
        parts = [Path(p) for p in source_parts(source, path.resolve().parent)]
        source = ",".join(str(p if p.is_absolute() else (path.resolve().parent / p).resolve()) for p in parts)
    source = with_options(source, options)
    names = [f.name for f in fields(PlanParameters)]
    ptab = _table(data, "parameters", where, set(names))
    values: dict = {}
    for name in names:
        if name == "mode":
            values[name] = _choice(ptab, "parameters", name, where, ("collaborative", "symmetric", "single"))
        elif name in OPTIONAL_FIELDS and name not in ptab:
            values[name] = None
        else:
            values[name] = _number(ptab, "parameters", name, where, auto=name in AUTO_FIELDS)
    for name in ("tool_radius", "dr", "dd", "tool_length", "feed", "a_max"):
        if values[name] is not None and values[name] <= 0:
            raise ProjectError(f"{where}: [parameters] {name} = {values[name]:g} must be a positive number")
    params = PlanParameters(**values)
    try:
        params.resolved()
    except PlanningError as exc:
        raise ProjectError(f"{where}: [parameters]: {exc}") from None
    stab = _table(data, "schedule", where, {"profile", "period_ms", "axes"})
    profile = _choice(stab, "schedule", "profile", where, PROFILES)
    period = _number(stab, "schedule", "period_ms", where, auto=True)
    if period is not None and not 0 < period < 1e6:
        raise ProjectError(f"{where}: [schedule] period_ms = {period} must be a positive number of ms "
                           "or \"auto\"")
    axes = stab.get("axes", False)  # optional: projects written before the axis tables lack it
    if not isinstance(axes, bool):
        raise ProjectError(f"{where}: [schedule] axes = {axes!r} must be true or false")
    tool = None
    if "tool" in data:  # optional: the shipped tool assembly without it
        tool = _table(data, "tool", where, {"file"}).get("file")
        if not isinstance(tool, str) or not tool.strip():
            raise ProjectError(f"{where}: [tool] file must be a tool file's path (tool.toml), got {tool!r}")
        tool = str((path.resolve().parent / tool).resolve()) if not Path(tool).is_absolute() else tool
    return Project(source=source, axis=axis, params=params, profile=profile, period=period, axes=axes, tool=tool)
