"""The tool assembly: the cutter, its holder and the spindle nose, from a tool file (tool.toml).

A tool.toml describes the assembly both machines carry (resources/tool.toml, documented line by line,
is the shipped default): the ball-nose cutter (ball radius, flute length, neck radius and length,
shank radius, stick-out), the holder as (length, radius) stages from the collet nut's face towards the
spindle, and the spindle nose. Lengths are measured along the tool axis from the tool tip, as a tool
catalogue gives them. ``load_tool`` reads and validates one (every problem raises ToolError naming the
file, the key and the fix); ``tool_to_toml`` writes it back, so that a plan folder carries the tool as
used and ``load_tool`` reads it to the same values.

The collision check sees the assembly as ``Part``s: cylinders about the tool axis, given by their
radius and their ends ``s0``, ``s1`` measured from the ball centre towards the spindle (the convention
of the shared check_assembly.py), each checked as the capsule round its axis segment (which holds
it). The ball itself is the gouge check's (core.paths.gouge); the flutes above it are a part from
FLUTE_START ball radii above the ball centre: the capsule of a part starting lower would hold the
ball's own contact with the blade. ``assembly`` adds the head's spindle housing and moving platform
from machine.toml.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from core.errors import MachineError, ToolError
from core.machine.model import Machine, _fmt, _number
from core.util.files import read_toml
from core.util.resources import resources_dir

CUTTER_KEYS = ("ball_radius_mm", "flute_length_mm", "neck_radius_mm", "neck_length_mm", "shank_radius_mm",
               "stick_out_mm")
#: where the flutes' part begins, in ball radii above the ball centre (module docstring)
FLUTE_START = 0.5
#: at most this many holder stages (a collet nut, a body, an extension, ...)
MAX_HOLDER_STAGES = 8


@dataclass(frozen=True)
class Part:
    """One cylinder of a tool assembly or head: name; radius, mm; s0 < s1, mm, its ends along the tool
    axis measured from the ball centre towards the spindle."""

    name: str
    radius: float
    s0: float
    s1: float


@dataclass(frozen=True)
class Tool:
    """A tool assembly (lengths from the tool tip, mm; see the module).

    ball_radius, flute_length, neck_radius, neck_length, shank_radius, stick_out : float, mm;
    holder : tuple of (length, radius) stages from the collet nut's face; nose_length, nose_radius :
    the spindle nose beyond the holder, mm; source : the file it was read from ('' for one made here)."""

    ball_radius: float
    flute_length: float
    neck_radius: float
    neck_length: float
    shank_radius: float
    stick_out: float
    holder: tuple[tuple[float, float], ...]
    nose_length: float
    nose_radius: float
    source: str = ""

    @property
    def length(self) -> float:
        """mm: tip to the end of the spindle nose."""
        return self.stick_out + sum(h for h, _ in self.holder) + self.nose_length

    def with_ball_radius(self, radius: float) -> Tool:
        """The same assembly with a ball of ``radius`` (mm): the flutes and neck take the ball's radius
        where they had the ball's before or would be wider than it, the shank at least the ball's; the
        lengths stay (the flutes at least as long as the ball)."""
        neck = radius if math.isclose(self.neck_radius, self.ball_radius) else min(self.neck_radius, radius)
        flute = max(self.flute_length, radius)
        return replace(self, ball_radius=radius, neck_radius=neck, flute_length=flute,
                       neck_length=max(self.neck_length, flute), shank_radius=max(self.shank_radius, radius),
                       source="")

    def parts(self) -> tuple[Part, ...]:
        """The assembly's cylinders above the ball (module docstring), from the flutes up."""
        r = self.ball_radius
        start = FLUTE_START * r
        out = []
        flute_end = self.flute_length - r
        if flute_end > start:
            out.append(Part("flute", r, start, flute_end))
        out.append(Part("neck", self.neck_radius, max(flute_end, start), max(self.neck_length - r, start + 1e-6)))
        out.append(Part("shank", self.shank_radius, self.neck_length - r, self.stick_out - r))
        s = self.stick_out - r
        for k, (length, radius) in enumerate(self.holder):
            out.append(Part(f"holder {k + 1}" if len(self.holder) > 1 else "holder", radius, s, s + length))
            s += length
        out.append(Part("spindle nose", self.nose_radius, s, s + self.nose_length))
        return tuple(p for p in out if p.s1 > p.s0)


def assembly(tool: Tool, machine: Machine) -> tuple[Part, ...]:
    """The parts of one side as the collision check sees them: the tool's (``Tool.parts``), then the
    head's spindle housing (from the spindle nose to the platform) and its moving platform (a disc of
    machine.platform_plate_radius, platform_thickness thick, centred gauge_length from the tip).
    ToolError where the assembly does not fit in the head's gauge length."""
    r = tool.ball_radius
    top = machine.gauge_length - r - 0.5 * machine.platform_thickness
    if tool.length >= top + r:
        raise ToolError(f"{tool.source or 'the tool'}: the tool assembly is {tool.length:g} mm long (stick-out, holder "
                        f"and spindle nose), but the head's gauge length is {machine.gauge_length:g} mm from the tip "
                        f"to "
                        f"the platform centre (machine.toml [head] gauge_length_mm, less half the platform "
                        f"thickness): shorten the holder or the spindle nose, or give the machine's gauge length")
    nose_end = tool.length - r
    return tool.parts() + (Part("spindle housing", machine.spindle_radius, nose_end, top),
                           Part("platform", machine.platform_plate_radius, top, top + machine.platform_thickness))


def default_tool_path() -> Path:
    """The shipped default tool.toml (resources/tool.toml)."""
    return resources_dir() / "tool.toml"


def load_tool(path: str | Path | None = None) -> Tool:
    """Read and validate a tool.toml; ``None`` loads the shipped default. ToolError (file missing or
    unreadable, TOML syntax, or a bad key, named in the message with the fix)."""
    p = default_tool_path() if path is None else Path(path)
    data = read_toml(p, ToolError, "tool file")
    return parse_tool(data, source=str(p))


def _table(data: dict, key: str, source: str) -> dict:
    if key not in data:
        raise ToolError(f"{source}: missing table [{key}] (see the shipped resources/tool.toml)")
    if not isinstance(data[key], dict):
        raise ToolError(f"{source}: [{key}] must be a table, got {type(data[key]).__name__}")
    return data[key]


def _positive(table: dict, key: str, where: str, source: str) -> float:
    try:
        value = _number(table, key, where, source)
    except MachineError as exc:
        raise ToolError(str(exc)) from None
    if value <= 0:
        raise ToolError(f"{source}: [{where}] {key} = {value:g} must be a positive number of mm")
    return value


def parse_tool(data: dict, source: str = "tool.toml") -> Tool:
    """Validate the parsed TOML tables of a tool.toml and build the Tool (ToolError naming the key)."""
    cutter = _table(data, "cutter", source)
    v = {k: _positive(cutter, k, "cutter", source) for k in CUTTER_KEYS}
    rules = (
        ("neck_radius_mm", v["neck_radius_mm"] <= v["shank_radius_mm"] * (1 + 1e-12),
         "the neck is not wider than the shank it is ground from"),
        ("flute_length_mm", v["flute_length_mm"] >= v["ball_radius_mm"],
         "the flutes are at least the ball long"),
        ("neck_length_mm", v["neck_length_mm"] >= v["flute_length_mm"],
         "the neck ends at or after the flutes (tip to the end of the neck)"),
        ("stick_out_mm", v["stick_out_mm"] > v["neck_length_mm"],
         "the stick-out (tip to the collet nut) is longer than the neck: the collet grips the shank"),
    )
    for key, ok, why in rules:
        if not ok:
            raise ToolError(f"{source}: [cutter] {key} = {v[key]:g} does not fit: {why}")
    stages = cutter.get("holder", data.get("holder"))
    if stages is None:
        raise ToolError(f"{source}: missing key [cutter] holder: give the holder's stages as "
                        f"[[length_mm, radius_mm], ...] from the collet nut's face towards the spindle")
    if not (isinstance(stages, list) and 1 <= len(stages) <= MAX_HOLDER_STAGES):
        raise ToolError(f"{source}: [cutter] holder must be a list of 1 to {MAX_HOLDER_STAGES} "
                        f"[length_mm, radius_mm] stages, got {str(stages)[:60]}")
    holder: list[tuple[float, float]] = []
    for k, st in enumerate(stages):
        if not (isinstance(st, list) and len(st) == 2):
            raise ToolError(f"{source}: [cutter] holder stage {k + 1} must be [length_mm, radius_mm], got {st!r}")
        stage = {"length_mm": st[0], "radius_mm": st[1]}
        holder.append((_positive(stage, "length_mm", f"cutter.holder {k + 1}", source),
                       _positive(stage, "radius_mm", f"cutter.holder {k + 1}", source)))
    nose = _table(data, "spindle_nose", source)
    return Tool(ball_radius=v["ball_radius_mm"], flute_length=v["flute_length_mm"],
                neck_radius=v["neck_radius_mm"], neck_length=v["neck_length_mm"],
                shank_radius=v["shank_radius_mm"], stick_out=v["stick_out_mm"], holder=tuple(holder),
                nose_length=_positive(nose, "length_mm", "spindle_nose", source),
                nose_radius=_positive(nose, "radius_mm", "spindle_nose", source), source=source)


def tool_to_toml(tool: Tool) -> str:
    """The tool as tool.toml text; ``parse_tool(tomllib.loads(text))`` gives the same values."""
    f = _fmt
    stages = ", ".join(f"[{f(h)}, {f(r)}]" for h, r in tool.holder)
    return "\n".join([
        "# bladecam tool assembly (resources/tool.toml documents every key). Lengths in mm along the tool",
        "# axis from the tool tip; radii in mm.",
        "",
        "[cutter]",
        f"ball_radius_mm = {f(tool.ball_radius)}",
        f"flute_length_mm = {f(tool.flute_length)}",
        f"neck_radius_mm = {f(tool.neck_radius)}",
        f"neck_length_mm = {f(tool.neck_length)}",
        f"shank_radius_mm = {f(tool.shank_radius)}",
        f"stick_out_mm = {f(tool.stick_out)}",
        f"holder = [{stages}]",
        "",
        "[spindle_nose]",
        f"length_mm = {f(tool.nose_length)}",
        f"radius_mm = {f(tool.nose_radius)}",
    ]) + "\n"


def resolve_tool(tool: Tool | str | Path | None, tool_radius: float | None = None,
                 tool_length: float | None = None) -> Tool:
    """The one tool of a job (docs/DECISIONS.md): a tool file (or Tool) is the source of the ball
    radius and the stick-out, and a ``tool_radius`` or ``tool_length`` (mm) given besides must agree
    with it (ToolError naming both); without one, the shipped default assembly with that ball radius
    and stick-out (the defaults': 1.5 and 40 mm, when None)."""
    if tool is None:
        base = load_tool()
        if tool_radius is not None and not math.isclose(tool_radius, base.ball_radius):
            base = base.with_ball_radius(float(tool_radius))
        if tool_length is not None and not math.isclose(tool_length, base.stick_out):
            if tool_length <= base.neck_length:
                raise ToolError(f"tool length {tool_length:g} mm is not longer than the default tool's neck "
                                f"({base.neck_length:g} mm from the tip): give a tool file (--tool) for so short a "
                                f"tool")
            base = replace(base, stick_out=float(tool_length), source="")
        return base
    t = tool if isinstance(tool, Tool) else load_tool(tool)
    name = t.source or "the tool file"
    if tool_radius is not None and not math.isclose(tool_radius, t.ball_radius):
        raise ToolError(f"--tool-radius {tool_radius:g} mm differs from {name}'s ball_radius_mm = {t.ball_radius:g}: "
                        f"the tool file gives the radius; leave out --tool-radius or edit the file")
    if tool_length is not None and not math.isclose(tool_length, t.stick_out):
        raise ToolError(f"tool length {tool_length:g} mm differs from {name}'s stick_out_mm = {t.stick_out:g}: "
                        f"the tool file gives the stick-out (d_T); leave out the tool length or edit the file")
    return t
