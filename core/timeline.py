"""Sampling a schedule on its common time column and the figures plan.json reports about it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .motion import Samples, sample_moves
from .pipeline import PathPlan
from .safety import capsule_clearance, tip_spacing
from .schedule import Schedule


@dataclass(frozen=True)
class Timeline:
    """t : (n,) ms; left, right : Samples on t."""

    t: np.ndarray
    left: Samples
    right: Samples


def sample(schedule: Schedule, period: float) -> Timeline:
    t = schedule.times(period)
    return Timeline(t, sample_moves(schedule.left, t), sample_moves(schedule.right, t))


def _weighted(values: np.ndarray, weights: np.ndarray) -> float:
    w = weights.sum()
    return float((values * weights).sum() / w) if w > 0 else 0.0


def figures(tl: Timeline, plan: PathPlan, schedule: Schedule) -> dict:
    """Schedule and support figures: total time, minimum tip spacing and capsule clearance with their
    times, violations, and what drives deformation and vibration (paper Table 4)."""
    p = plan.params
    at, between = tip_spacing(tl.left.tips, tl.right.tips)
    i_min = int(np.argmin(at))
    j_min = int(np.argmin(between)) if len(between) else 0
    clear = capsule_clearance(tl.left.tips, tl.left.axes, tl.right.tips, tl.right.axes, p.tool_radius,
                              p.tool_length)
    k_min = int(np.argmin(clear))
    n_viol = int((at < p.h_safe - 1e-9).sum() + (between < p.h_safe - 1e-9).sum())
    dt = np.diff(tl.t, append=tl.t[-1])
    both = tl.left.cutting & tl.right.cutting
    cl = tl.left.tips + p.tool_radius * tl.left.axes
    cr = tl.right.tips + p.tool_radius * tl.right.axes
    d = cl - cr
    off_axis = np.linalg.norm(d - (d * tl.left.axes).sum(1)[:, None] * tl.left.axes, axis=1)
    # cutting length per side between consecutive samples, and whether the other cutter supports it
    seg_l = np.linalg.norm(np.diff(tl.left.tips, axis=0), axis=1)
    seg_r = np.linalg.norm(np.diff(tl.right.tips, axis=0), axis=1)
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
        "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
        "min_tip_spacing_time_ms": round(float(tl.t[i_min] if at[i_min] <= between.min(initial=np.inf)
                                               else tl.t[j_min]), 3),
        "min_capsule_clearance_mm": round(float(clear[k_min]), 6),
        "min_capsule_clearance_time_ms": round(float(tl.t[k_min]), 3),
        "spacing_violations": n_viol,
        "capsule_violations": int((clear <= 0).sum()),
        "support": {
            "supported_cutting_share": round(sup_cut / total_cut, 6) if total_cut > 0 else 0.0,
            "torsional_lever_arm_mm": {"mean": round(_weighted(off_axis[both], dt[both]), 6),
                                       "max": round(float(off_axis[both].max(initial=0.0)), 6)},
            "overturning_lever_arm_mm": {"mean": round(_weighted(over_v, over_w), 6),
                                         "max": round(float(over_v.max(initial=0.0)), 6)},
            "note": "torsional arm: distance between the two ball centres across the left tool axis, while "
                    "both cut; overturning arm: distance of the cutting ball centre from the clamp plane",
        },
        "stages": schedule.stages,
    }
