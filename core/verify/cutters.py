"""``bladecam verify``: the checks of the two cutters together (``two_cutters``): one common time column
on the period, tip spacing >= h_safe at and between samples, tool capsules that never touch, feed and
acceleration along the path, and every cutting ball centre on the blade's offset surface."""

from __future__ import annotations

import numpy as np

from core.paths.tessellation import TriangleIndex, distance_to_surface
from core.util.polyline import ball_centres
from core.verify.report import Report

#: how far a cutting ball centre may sit outside the offset surface (mm): the check's own tessellation
#: (0.25 mm chordwise) lies inside a rounded edge by up to a few hundredths of a millimetre there
MISS_TOLERANCE = 0.05
SIDES = ("left", "right")


def _closest_between(d0: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """Minimum of |d0 + s (d1 - d0)| over s in [0, 1], row by row (a quadratic in s)."""
    e = d1 - d0
    qa = np.einsum("ij,ij->i", e, e)
    qb = np.einsum("ij,ij->i", d0, e)
    s = np.zeros(len(d0))
    np.divide(-qb, qa, out=s, where=qa > 1e-18)
    s = np.clip(s, 0.0, 1.0)
    return np.sqrt(np.einsum("ij,ij->i", d0 + s[:, None] * e, d0 + s[:, None] * e))


def _capsule_gap(a0, a1, b0, b1, iterations: int = 40) -> np.ndarray:
    """Distance between segments by alternating projections (convex sets: converges to the minimum);
    a row stops once neither projection moves by more than 1e-12 mm."""
    da, db = a1 - a0, b1 - b0
    la, lb = np.einsum("ij,ij->i", da, da), np.einsum("ij,ij->i", db, db)
    la1, lb1 = np.where(la > 0, la, 1.0), np.where(lb > 0, lb, 1.0)
    s = np.full(len(a0), 0.5)
    t = np.full(len(a0), 0.5)
    act = np.arange(len(a0))
    for _ in range(iterations):
        if act.size == 0:
            break
        pa = a0[act] + s[act, None] * da[act]
        tn = np.clip(np.einsum("ij,ij->i", pa - b0[act], db[act]) / lb1[act], 0.0, 1.0)
        pb = b0[act] + tn[:, None] * db[act]
        sn = np.clip(np.einsum("ij,ij->i", pb - a0[act], da[act]) / la1[act], 0.0, 1.0)
        moved = ((np.abs(sn - s[act]) * np.sqrt(la[act]) > 1e-12)
                 | (np.abs(tn - t[act]) * np.sqrt(lb[act]) > 1e-12))
        s[act], t[act] = sn, tn
        act = act[moved]
    return np.linalg.norm(a0 + s[:, None] * da - (b0 + t[:, None] * db), axis=1)


#: plan.json's inputs that verify reads, each a positive number
def two_cutters(left: dict, right: dict, inp: dict, index: TriangleIndex, surface_stride: int,
                 rep: Report) -> None:
    """The time column, the tip spacing and tool clearance, feed and acceleration along the path, and
    the cutting balls on the offset surface (module docstring)."""
    h, r, feed, a_max = inp["h_safe"], inp["tool_radius"], inp["feed"], inp["a_max"]
    stick = inp["tool_length"]
    t = left["t"]
    if len(t) != len(right["t"]) or np.abs(t - right["t"]).max(initial=0) > 1e-9:
        rep.bad("time column", f"left and right CL tables do not share one time column ({len(t)} and "
                               f"{len(right['t'])} rows)")
        return
    back = np.flatnonzero(np.diff(t) <= 0)
    rep.many("time column", back[:1], lambda i: f"t = {t[i]:.3f} ms: time column not strictly increasing "
                                                f"({back.size} rows)")
    period = inp.get("period_ms")
    if period is not None:  # every row on the controllers' period, t = k * period (to the file's 1e-6 ms)
        off = np.flatnonzero(np.abs(t - np.round(np.arange(len(t)) * period, 6)) > 1.5e-6)
        rep.many("time column", off[:1], lambda i: f"t = {t[i]:.6f} ms: row {i} is off the period of "
                                                   f"{period:g} ms ({off.size} rows)")
    steps = set(np.unique(left["step"])) | set(np.unique(right["step"]))
    if not steps <= set(range(1, 8)):
        rep.bad("time column", f"steps outside 1..7: {sorted(steps - set(range(1, 8)))}")
    # tip spacing at and between samples
    d = left["p"] - right["p"]
    at = np.linalg.norm(d, axis=1)
    between = _closest_between(d[:-1], d[1:])
    for arr, what in ((at, "at sample"), (between, "between samples")):
        rep.many("tip spacing", np.flatnonzero(arr < h - 1e-6),
                 lambda i, arr=arr, what=what: f"t = {t[i]:.1f} ms: tip spacing {arr[i]:.4f} mm < h_safe "
                                               f"{h} mm ({what})")
    # capsules
    ca, cb = ball_centres(left["p"], left["w"], r), ball_centres(right["p"], right["w"], r)
    gap = _capsule_gap(ca, ca + stick * left["w"], cb, cb + stick * right["w"]) - 2 * r
    rep.many("tool clearance", np.flatnonzero(gap <= 0),
             lambda i: f"t = {t[i]:.1f} ms: the tools touch (capsule gap {gap[i]:.4f} mm)")
    # kinematics on cutting stretches
    dt = np.diff(t)
    for name, s in (("left", left), ("right", right)):
        v = np.linalg.norm(np.diff(s["p"], axis=0), axis=1) / dt
        same = s["cutting"][:-1] & s["cutting"][1:] & (s["path"][:-1] == s["path"][1:])
        rep.many("feed", np.flatnonzero(same & (v > feed / 60000.0 * 1.01)),
                 lambda i, v=v, name=name: f"t = {t[i]:.1f} ms: {name} cutter at {v[i] * 60000:.1f} mm/min > "
                                           f"feed {feed} mm/min")
        both = same[:-1] & same[1:]
        acc = np.abs(np.diff(v)) / (0.5 * (dt[:-1] + dt[1:]))
        rep.many("path acceleration", np.flatnonzero(both & (acc > a_max / 1e6 * 1.05)),
                 lambda i, acc=acc, name=name: f"t = {t[i + 1]:.1f} ms: {name} cutter accelerates at "
                                               f"{acc[i] * 1e6:.1f} mm/s^2 > a_max {a_max} mm/s^2")
        rep.figures[f"{name}_peak_speed_mm_min"] = round(float(v[same].max(initial=0) * 60000), 3)
        rep.figures[f"{name}_peak_accel_mm_s2"] = round(float(acc[both].max(initial=0) * 1e6), 3)
    # cutting points on the offset surface
    cutters = (("left", left), ("right", right))
    picked = {name: np.nonzero(s["cutting"])[0][::surface_stride] for name, s in cutters}
    allc = np.concatenate([ball_centres(s["p"][picked[n]], s["w"][picked[n]], r) for n, s in cutters])
    alld = distance_to_surface(allc, index) - r if len(allc) else np.empty(0)  # one search tree for both
    dists = {"left": alld[:len(picked["left"])], "right": alld[len(picked["left"]):]}
    for name in SIDES:
        idx, dist = picked[name], dists[name]
        if idx.size == 0:
            continue
        rep.many("surface", np.flatnonzero((dist < -2e-3) | (dist > MISS_TOLERANCE)),
                 lambda j, idx=idx, dist=dist, name=name: (
                     f"t = {t[idx[j]]:.1f} ms: {name} ball {'cuts into' if dist[j] < 0 else 'misses'} "
                     f"the blade by {abs(dist[j]):.4f} mm"))
        rep.figures[f"{name}_surface_offset_mm"] = [round(float(dist.min()), 6), round(float(dist.max()), 6)]
    rep.figures.update({"samples": int(len(t)),
                        "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
                        "min_capsule_gap_mm": round(float(gap.min()), 6)})
