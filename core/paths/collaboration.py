"""How collaborative a plan is, and how far to go: the warning the command line and the workbench both
give when fewer than half of its contour paths are machined from both sides (the paper's plans are
mostly so), with which K_max would make how many contours collaborative and what lowering h_safe can do.

A contour goes to the tip region by its staggered ratio K when K >= K_max (core.paths.regions.divide);
K does not depend on K_max, so at a new K_max the contours single-sided for their ratio and with
K < K_max become collaborative, and no other contour changes region: the counts come from the ratios
the plan has already measured (no planning). Contours single-sided for their tip spacing
('spacing <= h_safe ...') wait for a lower h_safe instead, which changes every contour's edge
stretches and ratio: how many it gains needs the regions divided again (a re-plan, which reuses the
paths). The paper's ranges: K_max 0.1-0.2, h_safe 1-1.5 tool radii; a value outside them is outside
the method.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from core.paths.plan import PathPlan

#: below this share of collaborative contours a plan warns
LOW_SHARE = 0.5



PAPER_K_MAX = (0.1, 0.2)
PAPER_H_SAFE_R = (1.0, 1.5)
#: the reasons (core.paths.regions) a contour is single-sided for, by the parameter that changes it
RATIO_REASON = "staggered ratio"
SPACING_REASONS = ("spacing <=", "thin middle")
#: a tip path's reason -> the parameter that would make it collaborative
REMEDY = {RATIO_REASON: "raise K_max", **{r: "lower h_safe" for r in SPACING_REASONS}}
#: the share of collaborative contours the advice aims at (the warning's threshold)
TARGET_SHARE = LOW_SHARE


@dataclass(frozen=True)
class KMaxOption:
    """K_max ``value`` would make ``paths`` of ``total`` contours collaborative; ``in_paper``: inside
    the paper's 0.1-0.2; ``why``: 'the paper's upper limit', 'half the contours', 'every contour
    single-sided for its ratio'."""

    value: float
    paths: int
    total: int
    in_paper: bool
    why: str


def collaborative_at(plan: PathPlan, k_max: float) -> int:
    """How many contours would be collaborative at ``k_max`` (the regions of the plan's h_safe)."""
    return sum(1 for r in plan.regions
               if not r.is_tip or (r.reason.startswith(RATIO_REASON) and r.staggered_ratio < k_max))


def just_above(ratio: float) -> float:
    """The K_max (to 0.01) that takes a contour of staggered ratio ``ratio`` in (K < K_max)."""
    return round(math.floor(ratio * 100.0 + 1e-9) / 100.0 + 0.01, 2)


def k_max_options(plan: PathPlan) -> list[KMaxOption]:
    """The K_max values worth naming above the plan's: the paper's upper limit (when it gains a
    contour), the lowest that makes TARGET_SHARE of the contours collaborative, and the lowest that
    takes in every contour single-sided for its ratio; each once, in increasing order, below 1."""
    p = plan.params
    n = len(plan.regions)
    ratios = sorted(r.staggered_ratio for r in plan.regions if r.is_tip and r.reason.startswith(RATIO_REASON))
    now = collaborative_at(plan, p.k_max)
    values: dict[float, str] = {}
    if p.k_max < PAPER_K_MAX[1] and collaborative_at(plan, PAPER_K_MAX[1]) > now:
        values[PAPER_K_MAX[1]] = "the paper's upper limit"
    need = math.ceil(TARGET_SHARE * n) - (n - len([r for r in plan.regions if r.is_tip]))
    if 0 < need <= len(ratios):
        values.setdefault(just_above(ratios[need - 1]), "half the contours")
    if ratios:
        values.setdefault(just_above(ratios[-1]), "every contour single-sided for its ratio")
    lo, hi = PAPER_K_MAX
    return [KMaxOption(v, collaborative_at(plan, v), n, lo - 1e-9 <= v <= hi + 1e-9, why)
            for v, why in sorted(values.items()) if p.k_max < v < 1.0]


def k_max_text(plan: PathPlan) -> str:
    """'raise K_max (now 0.15) to 0.2 (the paper's upper limit): 21 of 46 paths collaborative; to
    0.27 (half the contours): 23, outside the paper's 0.1-0.2, outside the method', or ''."""
    options = k_max_options(plan)
    if not options:
        return ""
    parts = []
    for k, o in enumerate(options):
        outside = "" if o.in_paper else ", outside the paper's 0.1–0.2: outside the method"
        count = f"{o.paths} of {o.total} paths collaborative" if k == 0 else f"{o.paths}"
        parts.append(f"to {o.value:g} ({o.why}): {count}{outside}")
    return f"raise K_max (now {plan.params.k_max:g}) " + "; ".join(parts)


def h_safe_text(plan: PathPlan) -> str:
    """What lowering h_safe can do: how many contours wait for it, the paper's lowest value, or ''."""
    p = plan.params
    n = sum(1 for r in plan.regions if r.is_tip and r.reason.startswith(SPACING_REASONS))
    if n == 0:
        return ""
    lowest = PAPER_H_SAFE_R[0] * p.tool_radius
    paths = "path" if n == 1 else "paths"
    if p.h_safe <= lowest + 1e-9:
        return (f"{n} {paths} single-sided for their tip spacing; h_safe (now {p.h_safe:g} mm) is at the "
                "paper's lowest, 1 tool radius")
    return (f"lower h_safe (now {p.h_safe:g} mm; the paper's lowest {lowest:g} mm = 1 r) for the {n} {paths} "
            "single-sided for their tip spacing (it shortens every edge stretch: re-plan to count)")


def collaboration_warning(plan: PathPlan) -> str:
    """'' when most contour paths are collaborative (or the mode does not use the regions); else a
    warning naming the share and how far to go: which K_max would make how many paths collaborative,
    whether that is inside the paper's range, and what lowering h_safe is for."""
    if plan.params.mode != "collaborative" or not plan.regions:
        return ""
    tips = [r for r in plan.regions if r.is_tip]
    n, n_collab = len(plan.regions), len(plan.regions) - len(tips)
    if n_collab >= LOW_SHARE * n:
        return ""
    how = " · or ".join(t for t in (k_max_text(plan), h_safe_text(plan)) if t)
    how = f"; {how}" if how else ""
    if n_collab == 0:
        return f"NOT COLLABORATIVE: all {n} paths single-sided (tip region){how}"
    return f"only {n_collab} of {n} paths collaborative ({100 * n_collab / n:.0f} %){how}"
