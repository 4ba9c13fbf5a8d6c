"""The shown plan's verdict and its violations: one meaning for every widget (no Qt here).

A violation is a run of consecutive time samples (the machine clock's rows) where the plan breaks
what it checks: the tip spacing below h_safe at or between two samples or the two tool capsules
touching (core.schedule.timeline.SafetyProfile), a part of a tool assembly or head in the blade or
the clamp, or a part of one side's assembly in the other side's (core.machine.collisions, the plan's
ClearanceProfile). The verdict, the status line, the violation list, the timeline's marks and the
export's advice all count these runs and name their kinds. ``find_violations`` runs once per plan,
off the GUI thread (plan_data.prepare); the widgets only read its record.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from core.machine.collisions import HEAD_PARTS
from core.result import PlanResult
from core.schedule.safety import violations as safety_violations

#: the kinds of violation, in the order the list and the summaries give them
SPACING, CLEARANCE = "tip spacing", "tool clearance"
BLADE, CLAMP, PAIR = "part – blade", "part – clamp", "part – part"
KINDS = (SPACING, CLEARANCE, BLADE, CLAMP, PAIR)
#: what each kind's depth measures
DEPTH_OF = {SPACING: "mm below h_safe", CLEARANCE: "mm of overlap of the tool capsules",
            BLADE: "mm into the blade", CLAMP: "mm into the clamp", PAIR: "mm of overlap of the two parts"}
#: the part column's name for the safety rule's kinds (the collisions name their parts)
RULE_PART = {SPACING: "tips", CLEARANCE: "tool capsules"}
#: the menu entry that loads another tool assembly
TOOL_MENU = "File ▸ Tool file…"

#: what to change, per kind (the safety rule's kinds: per plan mode)
RULE_ADVICE = {
    "collaborative": "raise K_max or h_safe, or lower the feed",
    "symmetric": "the symmetric mode is an unsafe preview (the paper's Fig. 13): plan in the collaborative "
                 "or single mode",
    "single": "raise h_safe",
}
COLLISION_ADVICE = {
    BLADE: "use a tool that reaches: a longer neck or stick-out, or a slimmer neck, shank or holder (another "
           f"tool file: {TOOL_MENU})",
    CLAMP: f"use a longer stick-out or holder, so that the head stays off the clamp (another tool file: {TOOL_MENU})",
    PAIR: "raise h_safe to keep the two assemblies apart, or use a slimmer holder or head (another tool file: "
          f"{TOOL_MENU})",
}
#: what to change for verify's other kinds of finding (core.verify.report.KINDS)
FINDING_ADVICE = {
    "axis range": "the machines' strokes are too short for this blade, or the blade is not centred on them: "
                  "move the blade or use a machine file with longer strokes",
    "axis speed": "lower the feed or a_max, or use a machine file with larger limits",
    "axis acceleration": "lower the feed or a_max, or use a machine file with larger limits",
    "axis velocities": "lower the feed or a_max, or use a machine file with larger limits",
    "feed": "lower the feed or a_max",
    "path acceleration": "lower a_max or the feed",
}
OTHER_ADVICE = ("the files written do not match the plan: export again, and report it with the findings if "
                "it repeats")


def count_text(n: int) -> str:
    """'1 violation', '7 violations'."""
    return f"{n} violation{'s' if n != 1 else ''}"


def collision_kind(against: str) -> str:
    """The kind of a core.machine.collisions.Collision, from what it hits."""
    return BLADE if against == "blade" else CLAMP if against == "clamp" else PAIR


def collision_part(side: str, part: str, against: str) -> str:
    """The part a collision names: 'left neck', or both parts when one side's hits the other's."""
    return f"left {part} – {against}" if side == "both" else f"{side} {part}"


def item_text(kind: str, part: str, depth: float) -> str:
    """One thing broken, as a sentence's part: 'left neck 0.492 mm into the blade'."""
    if kind == SPACING:
        return f"tip spacing {depth:.3f} mm below h_safe"
    if kind == CLEARANCE:
        return f"tool capsules {depth:.3f} mm into each other"
    if kind == PAIR:
        return f"{part} {depth:.3f} mm into each other"
    return f"{part} {depth:.3f} {DEPTH_OF[kind]}"


def rule_advice(mode: str) -> str:
    return RULE_ADVICE.get(mode, "change the parameters")


@dataclass(frozen=True)
class Violations:
    """A plan's violations (module docstring). ``rows``: the list's columns, one row per run (k,):
    'start', 'end' (sample indices, inclusive), 't0', 't1' (ms), 'step' (at the start), 'left',
    'right' (each cutter's path at the start), 'spacing_n' (samples and intervals of the run with the
    tip spacing below h_safe), 'clearance_n' (samples with the tool capsules touching), 'min_spacing'
    (mm, at or between samples), 'min_clearance' (mm), 'depth_spacing' (mm below h_safe, >= 0),
    'depth_clearance' (mm of capsule overlap, >= 0), 'depth' (mm: the run's deepest of its kinds'),
    'items' (object: list of (kind, part, depth mm, deepest sample) per run, KINDS order, deepest
    first within a kind), 'kind' (str: the run's kinds joined by ' + '), 'part' and 'depths' (str: the
    items' parts and depths, joined by ' / '). ``kinds``: kind -> runs that have it; ``deepest``:
    kind -> (part, depth mm, sample) of its deepest item; ``safe``: nothing broken; ``mode``,
    ``h_safe``: the plan's."""

    rows: dict
    kinds: dict = field(default_factory=dict)
    deepest: dict = field(default_factory=dict)
    safe: bool = True
    mode: str = "collaborative"
    h_safe: float = 0.0

    @property
    def n(self) -> int:
        return len(self.rows.get("start", ()))

    def verdict(self) -> str:
        """The verdict's label: 'SAFE' or 'UNSAFE: 7 violations'."""
        return "SAFE" if self.safe else f"UNSAFE: {count_text(self.n)}"

    def kinds_text(self) -> str:
        """'2 tip spacing (deepest 0.120 mm below h_safe), 5 part – blade (deepest: left neck 0.492 mm
        into the blade)', '' when safe."""
        parts = []
        for kind in KINDS:
            if self.kinds.get(kind):
                part, depth, _ = self.deepest[kind]
                deepest = (f"deepest {depth:.3f} {DEPTH_OF[kind]}" if kind in RULE_PART
                           else f"deepest: {item_text(kind, part, depth)}")
                parts.append(f"{self.kinds[kind]} {kind} ({deepest})")
        return ", ".join(parts)

    def summary(self) -> str:
        """One line for the status bar and the log: 'safe', or the verdict with its kinds."""
        return "safe" if self.safe else f"UNSAFE: {count_text(self.n)}: {self.kinds_text()}"

    def advice(self) -> list[str]:
        """What to change, one line per kind present (the safety rule's kinds share one, which the two
        assemblies meeting shares too when the rule is broken)."""
        rule = bool(self.kinds.get(SPACING) or self.kinds.get(CLEARANCE))
        out = [rule_advice(self.mode)] if rule else []
        # (the two assemblies meet where the tips come too close: the rule's advice is theirs then)
        return out + [COLLISION_ADVICE[k] for k in (BLADE, CLAMP, PAIR) if self.kinds.get(k)
                      and not (k == PAIR and rule)]

    def tooltip(self) -> str:
        """The verdict's tooltip: what a violation is, the runs per kind and what to change."""
        rule = (f"tip spacing >= h_safe {self.h_safe:g} mm at and between samples, the tool capsules apart, "
                "no part of a tool assembly or head in the blade, the clamp or the other assembly")
        if self.safe:
            return f"no time sample or interval between two breaks the safety rule ({rule})"
        advice = "\n".join(f"• {a}" for a in self.advice())
        return (f"{count_text(self.n)}: runs of consecutive time samples that break the safety rule ({rule}):"
                f"\n{self.kinds_text()}\nthe violation list (Job tab) gives each one. What to change:\n{advice}")


def _spacing_columns(res: PlanResult, start: np.ndarray, end: np.ndarray) -> dict:
    """The safety rule's columns of the runs (see Violations.rows)."""
    safety, h = res.safety, res.plan.params.h_safe
    bad_at, bad_between, bad_clear = safety_violations(safety.at, safety.between, safety.clearance, h)

    def run_sum(flags: np.ndarray, stop: np.ndarray) -> np.ndarray:  # flags[start:stop] per run
        c = np.concatenate([[0], np.cumsum(flags, dtype=np.int64)])
        return c[stop] - c[start]

    def run_min(values: np.ndarray, stop: np.ndarray) -> np.ndarray:  # min of values[start:stop] per run
        padded = np.concatenate([values, [np.inf]])
        bounds = np.column_stack([start, np.minimum(np.maximum(stop, start + 1), len(values))]).ravel()
        return np.where(stop > start, np.minimum.reduceat(padded, bounds)[::2], np.inf)

    # the intervals inside a run are start..end-1 (a violating interval marks both its samples)
    min_spacing = np.minimum(run_min(safety.at, end + 1), run_min(safety.between, end))
    min_clearance = run_min(safety.clearance, end + 1)
    return {"spacing_n": run_sum(bad_at, end + 1) + run_sum(bad_between, end),
            "clearance_n": run_sum(bad_clear, end + 1), "min_spacing": min_spacing,
            "min_clearance": min_clearance, "depth_spacing": np.maximum(h - min_spacing, 0.0),
            "depth_clearance": np.maximum(-min_clearance, 0.0)}


def _run_items(res: PlanResult, start: np.ndarray, cols: dict) -> list[list[tuple]]:
    """Per run, its items (kind, part, depth mm, deepest sample): the safety rule's kinds, then each
    part's collision stretches in the run (the deepest per part and kind)."""
    items: list[list[tuple]] = [[] for _ in start]
    for k in range(len(start)):
        if cols["spacing_n"][k]:
            items[k].append((SPACING, RULE_PART[SPACING], float(cols["depth_spacing"][k]), int(start[k])))
        if cols["clearance_n"][k]:
            items[k].append((CLEARANCE, RULE_PART[CLEARANCE], float(cols["depth_clearance"][k]), int(start[k])))
    deepest: list[dict] = [{} for _ in start]
    for c in res.collisions:  # (a stretch's rows are danger rows: it lies inside one run)
        k = int(np.searchsorted(start, c.first, side="right")) - 1
        if k < 0:
            continue
        key = (collision_kind(c.against), collision_part(c.side, c.part, c.against))
        if key not in deepest[k] or deepest[k][key][0] < c.depth:
            deepest[k][key] = (float(c.depth), int(c.row))
    order = {kind: i for i, kind in enumerate(KINDS)}
    for k, found in enumerate(deepest):
        hits = sorted(found.items(), key=lambda e: (order[e[0][0]], -e[1][0]))
        items[k] += [(kind, part, depth, row) for (kind, part), (depth, row) in hits]
    return items


def find_violations(res: PlanResult, danger: np.ndarray, step: np.ndarray) -> Violations:
    """The violations of a planned result (with its schedule): the runs of ``danger`` (n,) bool (the
    rows that break the safety rule or collide: plan_data.danger_rows), each with its kinds, parts
    and depths; ``step`` (n,) the job's step per sample."""
    tl, params = res.timeline, res.plan.params
    d = np.asarray(danger, bool)
    f = np.diff(np.concatenate([[0], d.astype(np.int8), [0]]))
    start, end = np.flatnonzero(f == 1), np.flatnonzero(f == -1) - 1
    if not len(start):
        return Violations(empty_rows(), safe=bool(res.safe) and not res.collisions, mode=params.mode,
                          h_safe=float(params.h_safe))
    cols = _spacing_columns(res, start, end)
    items = _run_items(res, start, cols)
    kinds: dict[str, int] = {}
    deepest: dict[str, tuple] = {}
    for run in items:
        for kind in dict.fromkeys(i[0] for i in run):
            kinds[kind] = kinds.get(kind, 0) + 1
        for kind, part, depth, row in run:
            if kind not in deepest or deepest[kind][1] < depth:
                deepest[kind] = (part, depth, row)
    rows = {"start": start, "end": end, "t0": tl.t[start], "t1": tl.t[end], "step": np.asarray(step)[start],
            "left": tl.left.path[start], "right": tl.right.path[start], **cols,
            "depth": np.array([max((i[2] for i in run), default=0.0) for run in items]),
            "items": _objects(items),
            "kind": _objects([" + ".join(dict.fromkeys(i[0] for i in run)) or "safety rule" for run in items]),
            "part": _objects([" / ".join(i[1] for i in run) for run in items]),
            "depths": _objects([" / ".join(f"{i[2]:.3f}" for i in run) for run in items])}
    return Violations(rows, kinds, deepest, False, params.mode, float(params.h_safe))


def empty_rows() -> dict[str, np.ndarray]:
    """Violations.rows with no run."""
    numbers = ("start", "end", "t0", "t1", "step", "left", "right", "spacing_n", "clearance_n", "min_spacing",
               "min_clearance", "depth_spacing", "depth_clearance", "depth")
    return {name: np.zeros(0) for name in numbers} | {name: _objects([]) for name in TEXTS}


#: Violations.rows' object columns
TEXTS = ("items", "kind", "part", "depths")


def _objects(values: list) -> np.ndarray:
    out = np.empty(len(values), object)
    out[:] = values
    return out


def collisions_at(res: PlanResult, row: int) -> list[str]:
    """What collides at ``row``: 'left neck 0.412 mm into the blade (deepest 0.492 mm at sample 39181)',
    ... (each collision stretch that holds the row, with its depth there from the plan's clearance
    columns and its deepest; a stretch whose deepest point lies between two rows gives that depth)."""
    profile = res.clearance
    if profile is None:
        return []
    heads = [p for p in profile.parts if p in HEAD_PARTS]
    out = []
    for c in profile.collisions:
        if not c.first <= row <= c.last:
            continue
        kind = collision_kind(c.against)
        if kind == BLADE:
            value = profile.blade[c.side][row, profile.parts.index(c.part)]
        elif kind == CLAMP:
            value = profile.clamp[c.side][row, heads.index(c.part)]
        else:
            value = profile.tools[row]
        part = collision_part(c.side, c.part, c.against)
        if value >= 0:  # (its deepest point lies between this row and the next)
            out.append(item_text(kind, part, float(c.depth)) + " (between two rows)")
        elif c.row != row:
            out.append(item_text(kind, part, -float(value)) + f" (deepest {c.depth:.3f} mm at sample {c.row})")
        else:
            out.append(item_text(kind, part, -float(value)))
    return out


def finding_advice(kinds: Iterable[str], found: Violations | None) -> list[str]:
    """What to change for a verify report's kinds of finding (core.verify.report.KINDS): the safety
    rule's by the plan's mode, a collision's by the plan's own collision kinds (``found``), the
    machines' and the feed's by theirs; one line each, no repeats."""
    out = []
    mode = found.mode if found is not None else "collaborative"
    for kind in kinds:
        if kind in (SPACING, CLEARANCE):
            out.append(rule_advice(mode))
        elif kind == "collision":
            own = [COLLISION_ADVICE[k] for k in (BLADE, CLAMP, PAIR) if found is not None and found.kinds.get(k)]
            out += own or [f"a part of the tool assembly collides: use another tool file ({TOOL_MENU})"]
        else:
            out.append(FINDING_ADVICE.get(kind, OTHER_ADVICE))
    return list(dict.fromkeys(out))
