"""The figures plan.json reports about a sampled schedule: time, safety (core.schedule.safety's rule),
support (what drives deformation and vibration, paper Table 4) and how collaborative the plan is."""

from __future__ import annotations

import numpy as np

from core.paths.plan import PathPlan
from core.paths.regions import REGION_NAMES
from core.paths.scallop import path_scallops
from core.schedule.safety import violations
from core.schedule.step_times import step_times
from core.schedule.steps import Schedule
from core.schedule.timeline import SafetyProfile, Timeline
from core.util.rowwise import row_norm, row_sum_of_products

TIP = REGION_NAMES.index("tip")


def _weighted(values: np.ndarray, weights: np.ndarray) -> float:
    w = weights.sum()
    return float((values * weights).sum() / w) if w > 0 else 0.0


def figures(tl: Timeline, plan: PathPlan, schedule: Schedule, safety: SafetyProfile) -> dict:
    """Schedule and support figures: total time, minimum tip spacing and capsule clearance with their
    times, violations (core.schedule.safety.violations), and what drives deformation and vibration
    (paper Table 4). ``safety``: the column's SafetyProfile."""
    p = plan.params
    at, between, clear = safety.at, safety.between, safety.clearance
    i_min = int(np.argmin(at))
    j_min = int(np.argmin(between)) if len(between) else 0
    k_min = int(np.argmin(clear))
    bad_at, bad_between, bad_clear = violations(at, between, clear, p.h_safe)
    n_viol = int(bad_at.sum() + bad_between.sum())
    dt = np.diff(tl.t, append=tl.t[-1])
    both = tl.left.cutting & tl.right.cutting
    cl = tl.left.tips + p.tool_radius * tl.left.axes
    cr = tl.right.tips + p.tool_radius * tl.right.axes
    d = cl - cr
    off_axis = row_norm(d - row_sum_of_products(d, tl.left.axes)[:, None] * tl.left.axes)
    # cutting length per side between consecutive samples, and whether the other cutter supports it
    seg_l = row_norm(np.diff(tl.left.tips, axis=0))
    seg_r = row_norm(np.diff(tl.right.tips, axis=0))
    cut_l = tl.left.cutting[:-1] & tl.left.cutting[1:]
    cut_r = tl.right.cutting[:-1] & tl.right.cutting[1:]
    supported = both[:-1] & both[1:] & (off_axis[:-1] < 1e-3) & (off_axis[1:] < 1e-3)
    total_cut = float((seg_l * cut_l).sum() + (seg_r * cut_r).sum())
    sup_cut = float((seg_l * (cut_l & supported)).sum() + (seg_r * (cut_r & supported)).sum())
    over = []
    weights = []
    for s, c in ((tl.left, cl), (tl.right, cr)):
        m = s.cutting
        over.append(np.abs(c[m, 0] - plan.frame.x_clamp))
        weights.append(dt[m])
    over_v, over_w = np.concatenate(over), np.concatenate(weights)
    return {
        "mode": schedule.mode,
        "feed_mm_min": schedule.feed,
        "a_max_mm_s2": schedule.a_max,
        "period_ms": float(tl.t[1] - tl.t[0]) if len(tl.t) > 1 else 0.0,
        "samples": int(len(tl.t)),
        "total_time_s": round(float(tl.t[-1]) / 1000.0, 3),
        "step_time_s": step_times(tl.t, tl.left.step, tl.right.step),
        "scallop": path_scallops(plan.paths, p.tool_radius),
        "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
        "min_tip_spacing_time_ms": round(float(tl.t[i_min] if at[i_min] <= between.min(initial=np.inf)
                                               else tl.t[j_min]), 3),
        "min_capsule_clearance_mm": round(float(clear[k_min]), 6),
        "min_capsule_clearance_time_ms": round(float(tl.t[k_min]), 3),
        "spacing_violations": n_viol,
        "capsule_violations": int(bad_clear.sum()),
        "support": {
            "supported_cutting_share": round(sup_cut / total_cut, 6) if total_cut > 0 else 0.0,
            "torsional_lever_arm_mm": {"mean": round(_weighted(off_axis[both], dt[both]), 6),
                                       "max": round(float(off_axis[both].max(initial=0.0)), 6)},
            "overturning_lever_arm_mm": {"mean": round(_weighted(over_v, over_w), 6),
                                         "max": round(float(over_v.max(initial=0.0)), 6)},
            "note": "torsional arm: distance between the two ball centres across the left tool axis, while "
                    "both cut; overturning arm: distance of the cutting ball centre from the clamp plane",
        },
        "collaboration": collaboration(tl, plan, schedule.mode, cut_l, cut_r, seg_l, seg_r, supported),
        "stages": schedule.stages,
    }


def collaboration(tl: Timeline, plan: PathPlan, mode: str, cut_l: np.ndarray, cut_r: np.ndarray,
                  seg_l: np.ndarray, seg_r: np.ndarray, supported: np.ndarray) -> dict:
    """How much of the plan is machined collaboratively: paths, cutting length (mm, both cutters) and
    job time (s), each collaborative (symmetrical or staggered), of it supported (both cutters cutting
    with their axes in line), and single-sided, with the shares of the whole. In collaborative mode a
    cut is collaborative outside the tip region; in symmetric mode every path is machined by both
    cutters together, in single mode every path single-sided. Per interval of the time column
    (n - 1,): cut_l, cut_r whether each cutter cuts over it, seg_l, seg_r its length (mm), supported
    as in ``figures``; an interval's region is that of its first row."""
    if mode == "collaborative":
        coll_l, coll_r = cut_l & (tl.left.code[:-1] != TIP), cut_r & (tl.right.code[:-1] != TIP)
    else:
        coll_l, coll_r = (cut_l, cut_r) if mode == "symmetric" else (cut_l & False, cut_r & False)
    tip_l, tip_r = cut_l & ~coll_l, cut_r & ~coll_r
    dt = np.diff(tl.t)
    length = {"collaborative": float((seg_l * coll_l).sum() + (seg_r * coll_r).sum()),
              "supported": float((seg_l * (coll_l & supported)).sum() + (seg_r * (coll_r & supported)).sum()),
              "single_sided": float((seg_l * tip_l).sum() + (seg_r * tip_r).sum())}
    any_coll = coll_l | coll_r
    time_s = {"collaborative": float(dt[any_coll].sum()) / 1000.0,
              "supported": float(dt[any_coll & supported].sum()) / 1000.0,
              "single_sided": float(dt[~any_coll & (tip_l | tip_r)].sum()) / 1000.0}
    total_length = length["collaborative"] + length["single_sided"]
    total_time = float(tl.t[-1] - tl.t[0]) / 1000.0 if len(tl.t) else 0.0
    tip = {"collaborative": [r.is_tip for r in plan.regions], "symmetric": [False] * len(plan.regions),
           "single": [True] * len(plan.regions)}[mode]
    n_tip = sum(tip)
    reasons: dict[str, int] = {}
    for r, single in zip(plan.regions, tip, strict=True):
        if single:
            reason = r.reason if mode == "collaborative" else "single mode"
            reasons[reason] = reasons.get(reason, 0) + 1
    return {
        "paths": {"total": len(plan.regions), "collaborative": len(plan.regions) - n_tip, "single_sided": n_tip,
                  "collaborative_share": round((len(plan.regions) - n_tip) / len(plan.regions), 6)
                  if plan.regions else 0.0},
        "tip_reasons": reasons,
        "cutting_length_mm": {k: round(v, 3) for k, v in length.items()},
        "cutting_length_share": {k: round(v / total_length, 6) if total_length > 0 else 0.0 for k, v in length.items()},
        "job_time_s": {k: round(v, 3) for k, v in time_s.items()},
        "job_time_share": {k: round(v / total_time, 6) if total_time > 0 else 0.0 for k, v in time_s.items()},
    }
