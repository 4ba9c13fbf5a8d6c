"""``bladecam verify``: the checks of one cutter against its own files, run for both sides at once (in
helper processes while core.verify checks the two cutters together).

Completeness (``path_checks``): the ball centres (tip + r axis) are compared, not the tips: where a
machine's tilt limit turned the tool axis (core.machine.postprocess.limit_tilt, the single-sided paths'
axes: core.machine.tool_axes), it turned it about the ball centre, so the CL tables' tips differ from pairs.csv's (which keeps
the paper's axes) while the centres stay the same. Per side and path:
- every cutting row's centre lies within ``ROW_TOL`` of the polyline through pairs.csv's centres of
  its path (a path pairs.csv lacks, or a row moved off, is a finding);
- in order of time, the cutting rows of a path advance along it (back by at most ``ORDER_TOL``);
- every pair point's centre lies within ``REACH_TOL`` of the straight line a controller moves along
  between two consecutive rows that both cut that path (a deleted path, a truncated job, a row taken
  out of the cut all leave points unreached).
Axis tables (``axes_checks``): forward kinematics of every row reproduces the CL tip and axis, every
stroke, speed and acceleration limit of machine.toml holds, and the velocity columns are the
derivative of the positions (``derivative_slack``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from core.errors import MachineError
from core.machine.kinematics import forward_kinematics
from core.machine.model import AXES, Machine
from core.verify_read import Report

#: mm: how far a cutting row's ball centre may lie from its path's polyline of pair centres (between
#: two pair points the tip moves straight and the axis turns, so the centre bulges off their chord by
#: r (1 - cos(turn / 2)): 1e-4 mm on the sample blade, 5e-3 mm where a ball rolls over a mesh's facet edge)
ROW_TOL = 0.01
#: mm: how far a pair point's ball centre may lie from the cutter's chords (the controller's straight
#: lines between rows; the plan keeps them within its chord tolerance, 0.001 mm by default: 1.3e-3 mm
#: measured on the sample blade and on BladeX)
REACH_TOL = 0.01
#: mm: how far a run of rows cutting one path may end behind where it started, or start behind where
#: the path's run before it ended
ORDER_TOL = 0.005
#: the label coordinate that keeps a search to one path: larger than any distance on a blade (mm)
_LABEL = 1e6


def _segment_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance (n,) of points x (n, 3) from the segments a -> b (n, 3), and the parameter s in [0, 1]
    of the nearest point."""
    e = b - a
    ee = np.einsum("ij,ij->i", e, e)
    s = np.clip(np.einsum("ij,ij->i", x - a, e) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
    d = a + s[:, None] * e - x
    return np.sqrt(np.einsum("ij,ij->i", d, d)), s


def near_segments(x: np.ndarray, x_label: np.ndarray, verts: np.ndarray, a: np.ndarray, b: np.ndarray,
                  seg_label: np.ndarray, tol: float, exact: float | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For points x (n, 3) mm with integer labels (n,): the nearest of the segments verts[a] -> verts[b]
    (m,) with the same label (a == b: a single point). Returns its distance (n,) mm (inf where no
    segment has the label), index (n,) and parameter s (n,): exact where it is from ``exact`` (default
    ``tol``) to ``tol`` mm, at most ``exact`` below it, above ``tol`` beyond it. Vectorised: a k-d tree
    of the segments' midpoints (the label as a fourth coordinate ``_LABEL`` mm apart), two candidates
    per point, then, for the points they leave farther than ``exact``, every segment near enough to
    be nearer (its midpoint within the distance found, at most tol, plus half the longest segment)."""
    n = len(x)
    dist, seg, par = np.full(n, np.inf), np.zeros(n, int), np.zeros(n)
    if n == 0 or len(a) == 0:
        return dist, seg, par
    mid = 0.5 * (verts[a] + verts[b])
    half = 0.5 * np.linalg.norm(verts[b] - verts[a], axis=1).max()
    tree = cKDTree(np.column_stack([mid, seg_label * _LABEL]), balanced_tree=False)
    q = np.column_stack([x, x_label * _LABEL])
    k = min(2, len(a))
    _, cand = tree.query(q, k=k, distance_upper_bound=_LABEL / 2)
    cand = cand.reshape(n, k)

    def take(rows: np.ndarray, segs: np.ndarray, repeated: bool = False) -> None:
        d, s = _segment_distance(x[rows], verts[a[segs]], verts[b[segs]])
        better = d < dist[rows]
        if repeated:  # (several candidates per row: keep the least)
            order = np.lexsort((d, rows))
            first = np.r_[True, rows[order][1:] != rows[order][:-1]]
            rows, segs, d, s = rows[order][first], segs[order][first], d[order][first], s[order][first]
            better = d < dist[rows]
        dist[rows[better]], seg[rows[better]], par[rows[better]] = d[better], segs[better], s[better]

    for j in range(k):
        ok = np.flatnonzero(cand[:, j] < len(a))
        take(ok, cand[ok, j])
    far = np.flatnonzero(dist > (tol if exact is None else exact))
    if far.size:  # (the right segment's midpoint may be farther than two others')
        lists = tree.query_ball_point(q[far], r=np.minimum(dist[far], tol) + half)
        sizes = np.fromiter((len(v) for v in lists), int, len(lists))
        if sizes.sum():
            take(np.repeat(far, sizes), np.concatenate([np.asarray(v, int) for v in lists if v]), True)
    return dist, seg, par


def _runs(k: np.ndarray) -> str:
    """'3-9, 40-41' for the sorted integers k (at most three runs, then how many more)."""
    if k.size == 0:
        return ""
    cut = np.flatnonzero(np.diff(k) != 1)
    starts, ends = k[np.r_[0, cut + 1]], k[np.r_[cut, len(k) - 1]]
    text = ", ".join(f"{s}" if s == e else f"{s}-{e}" for s, e in zip(starts[:3], ends[:3], strict=True))
    return text + (f" and {len(starts) - 3} more stretches" if len(starts) > 3 else "")


def _covering(lo: np.ndarray, hi: np.ndarray, at: np.ndarray) -> np.ndarray:
    """For intervals [lo, hi] (m,) and values at (n,): the index of an interval holding each value (the
    one reaching farthest of those starting at or before it), -1 where none does."""
    if len(lo) == 0:
        return np.full(len(at), -1)
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    reach = np.maximum.accumulate(hi)
    sets = np.r_[True, hi[1:] > reach[:-1]]                  # (an interval that raises the reach)
    who = order[np.maximum.accumulate(np.where(sets, np.arange(len(lo)), 0))]
    j = np.searchsorted(lo, at, side="right") - 1
    ok = (j >= 0) & (reach[np.maximum(j, 0)] >= at)
    return np.where(ok, who[np.maximum(j, 0)], -1)


def path_checks(side: str, pairs: dict, cl: dict, tool_radius: float, rep: Report) -> dict:
    """Completeness of one cutter (module docstring) against pairs.csv (``pairs``: its arrays sorted
    by path and k). Findings go into ``rep``; returns its figures.

    Each cutting row is placed on its path (the nearest point of the polyline of pair centres: an arc
    coordinate), and so are the rows just before and after each run of rows cutting one path; the
    chord from a row to the next covers the arc between their places. A pair point is reached when a
    chord covering it passes within REACH_TOL of it: first the chords between two rows that both cut
    the path and lie on it, then, for the points those leave, the chords into and out of each run
    (rows lie on a fixed period, so a cut begins and ends between two rows). One search
    (near_segments), then sorting: no second search of the rows."""
    r = tool_radius
    pp, pk = pairs["path"], pairs["k"]
    pc = pairs[f"{side}_tip"] + r * pairs[f"{side}_axis"]
    t, path, cut = cl["t"], cl["path"], cl["cutting"]
    n = len(t)
    ci = np.flatnonzero(cut)
    cpath = path[ci]
    # the rows into (before) and out of (after) each run of rows cutting one path, with its path
    before, after = np.maximum(ci - 1, 0), np.minimum(ci + 1, n - 1)
    first = ci[(ci > 0) & ~(cut[before] & (path[before] == cpath))]
    last = ci[(ci < n - 1) & ~(cut[after] & (path[after] == cpath))]
    rows = np.r_[ci, first - 1, last + 1]
    label = np.r_[cpath, path[first], path[last]]
    nc = len(ci)
    centres = cl["p"][rows] + r * cl["w"][rows]
    # pairs.csv's polylines: consecutive points of one path (a path of one point: that point), and
    # an arc coordinate along all of them (paths 1 m apart: no interval reaches from one to the next)
    link = np.flatnonzero(pp[1:] == pp[:-1])
    lone = np.flatnonzero(np.r_[True, pp[1:] != pp[:-1]] & np.r_[pp[1:] != pp[:-1], True])
    pa, pb = np.r_[link, lone], np.r_[link + 1, lone]
    step = np.linalg.norm(np.diff(pc, axis=0), axis=1)
    arc = np.r_[0.0, np.cumsum(np.where(pp[1:] == pp[:-1], step, 1000.0))]
    dist_all, seg, s = near_segments(centres, label, pc, pa, pb, pp[pa], ROW_TOL, ROW_TOL / 10)
    u = arc[pa[seg]] + s * (arc[pb[seg]] - arc[pa[seg]])
    dist = dist_all[:nc]
    known = np.isin(cpath, pp)
    stray = np.flatnonzero(~known)
    if stray.size:
        rep.many("off path", stray[np.unique(cpath[stray], return_index=True)[1]],
                 lambda j: f"t = {t[ci[j]]:.1f} ms: the {side} cutter cuts path {cpath[j]}, which pairs.csv "
                           "does not have")
    on = known & (dist <= ROW_TOL)
    rep.many("off path", np.flatnonzero(known & ~on),
             lambda j: f"t = {t[ci[j]]:.1f} ms: {side} cutting row {dist[j]:.4f} mm off path {cpath[j]} "
                       "(pairs.csv's ball centres)")
    # a row not cutting between two rows cutting one path (a cut is never interrupted for one row)
    gap = np.flatnonzero((np.diff(ci) == 2) & (cpath[1:] == cpath[:-1]))
    rep.many("completeness", gap, lambda j: f"t = {t[ci[j] + 1]:.1f} ms: the {side} cutter's row is not "
                                            f"cutting between two rows cutting path {cpath[j]}")
    # order: each run of rows cutting one path advances along it, and each run of a path starts where
    # the one before it ended or farther (compared at the runs' ends: a row's place is ambiguous where
    # a mesh's ball rolls round a facet corner and its path of centres nearly meets itself)
    pos_first, pos_last = np.searchsorted(ci, first), np.searchsorted(ci, last)
    onpos = np.flatnonzero(on)
    run = np.searchsorted(pos_first, onpos, side="right") - 1
    runs, head = np.unique(run, return_index=True)
    tail = len(run) - 1 - np.unique(run[::-1], return_index=True)[1]
    if runs.size:
        seq = np.column_stack([onpos[head], onpos[tail]]).ravel()       # (positions in ci, in time)
        by = seq[np.argsort(cpath[seq], kind="stable")]
        du = np.diff(u[by])
        back = np.flatnonzero((cpath[by][1:] == cpath[by][:-1]) & (du < -ORDER_TOL))
        if back.size:  # (one finding per path: its largest step back)
            o = np.lexsort((du[back], cpath[by][back]))
            worst = np.sort(back[o][np.r_[True, cpath[by][back][o][1:] != cpath[by][back][o][:-1]]])
            rep.many("order", worst,
                     lambda j: f"t = {t[ci[by[j + 1]]]:.1f} ms: the {side} cutter is {-du[j]:.3f} mm back "
                               f"along path {cpath[by[j]]} from t = {t[ci[by[j]]]:.1f} ms (cut out of order)")
    # reach: the chords between consecutive rows cutting one path (and each such row alone), then
    # those into and out of each run
    inner = np.flatnonzero((np.diff(ci) == 1) & (cpath[1:] == cpath[:-1]) & on[1:] & on[:-1])
    alone = np.flatnonzero(on)
    ends_ok = np.isfinite(dist_all)
    into = np.flatnonzero(on[pos_first] & ends_ok[nc + np.arange(len(first))])
    out = np.flatnonzero(on[pos_last] & ends_ok[nc + len(first) + np.arange(len(last))])
    reach = np.full(len(pp), np.inf)
    ra_in, rb_in = inner, inner + 1
    ra_end = np.r_[pos_first[into], pos_last[out], alone]
    rb_end = np.r_[nc + into, nc + len(first) + out, alone]
    for ra, rb, slack in ((ra_in, rb_in, 1e-9), (ra_end, rb_end, REACH_TOL)):
        todo = np.flatnonzero(reach > REACH_TOL)
        lo, hi = np.minimum(u[ra], u[rb]) - slack, np.maximum(u[ra], u[rb]) + slack
        held = _covering(lo, hi, arc[todo])
        h = held >= 0
        d = _segment_distance(pc[todo[h]], centres[ra[held[h]]], centres[rb[held[h]]])[0]
        reach[todo[h]] = np.minimum(reach[todo[h]], d)
    todo = np.flatnonzero(reach > REACH_TOL / 10)
    if todo.size:  # (where a row's place on a sharp turn is ambiguous: the nearest chord of all)
        ra, rb = np.r_[ra_in, ra_end], np.r_[rb_in, rb_end]
        d = near_segments(pc[todo], pp[todo], centres, ra, rb, label[ra], REACH_TOL, REACH_TOL / 10)[0]
        reach[todo] = np.minimum(reach[todo], d)
    miss = np.flatnonzero(reach > REACH_TOL)
    if miss.size:
        paths, start, n_miss = np.unique(pp[miss], return_index=True, return_counts=True)
        total = np.bincount(pp)[paths]
        cut_paths = set(np.unique(cpath[on]).tolist())

        def line(j: int) -> str:
            idx = miss[start[j]:start[j] + n_miss[j]]
            if paths[j] not in cut_paths:
                return f"the {side} cutter never cuts path {paths[j]} ({total[j]} pair points)"
            far = reach[idx][np.isfinite(reach[idx])]
            return (f"the {side} cutter misses {idx.size} of the {total[j]} pair points of path {paths[j]} "
                    f"(k {_runs(pk[idx])}): up to {far.max(initial=0):.3f} mm from its cut")

        rep.many("completeness", np.arange(len(paths)), line)
    return {f"{side}_path_error_mm": float(f"{dist[on].max(initial=0):.3g}"),
            f"{side}_reach_error_mm": float(f"{reach[np.isfinite(reach)].max(initial=0):.3g}")}


def derivative_slack(t: np.ndarray, x: np.ndarray, v: np.ndarray, a_lim: float) -> np.ndarray:
    """(n - 1,) mm/ms: how far the chord velocity (x[i+1] - x[i]) / (t[i+1] - t[i]) lies outside what
    velocities v (n,) mm/ms at the two rows allow (0 inside): between the rows the axis moves at v(tau)
    with |dv/dtau| <= a_lim (mm/ms^2), so its mean velocity lies within [min, max] of v[i], v[i+1]
    widened by a_lim dt, allowing for the rounding of the written positions (1e-6 mm), times (1e-6 ms)
    and velocities (1e-9 mm/ms). Any time column, uniform or not."""
    dt = np.diff(t)
    c = np.diff(x) / dt
    lo, hi = np.minimum(v[:-1], v[1:]), np.maximum(v[:-1], v[1:])
    room = a_lim * dt + (1e-6 + 1e-6 * np.abs(c)) / dt + 2e-9
    return np.maximum(np.maximum(lo - c, c - hi) - room, 0.0)


def axes_checks(side: str, a: np.ndarray, cl: dict, machine: Machine, rep: Report, name: str) -> dict:
    """One side's axis table ``a`` (n, 13) (the file ``name``) against its CL table and machine.toml:
    forward kinematics (core.machine.kinematics, the mechanism solved by Newton's method, not the
    planner's closed-form inverse) reproduces the CL tip and axis (1e-3 mm, 1e-4 rad); every stroke,
    speed and acceleration limit holds (acceleration: the change of the velocity column between two
    rows over their time step); the velocities are the derivative of the positions. Returns figures."""
    t = cl["t"]
    figures: dict = {}
    if len(a) != len(t) or np.abs(a[:, 0] - t).max(initial=0) > 1e-9:
        rep.bad("time column", f"{name}: its time column differs from the CL tables' ({len(a)} rows, "
                               f"the CL tables {len(t)})")
        return figures
    try:
        tips, axes = forward_kinematics(machine, side, a[:, 1:7])
    except MachineError as exc:
        rep.bad("forward kinematics", f"{name}: {exc}")
        return figures
    ep = np.linalg.norm(tips - cl["p"], axis=1)
    w = cl["w"] / np.linalg.norm(cl["w"], axis=1)[:, None]
    ew = np.arccos(np.clip((axes * w).sum(axis=1), -1.0, 1.0))
    for arr, tol, what, unit in ((ep, 1e-3, "tip", "mm"), (ew, 1e-4, "axis", "rad")):
        rep.many("forward kinematics", np.flatnonzero(arr > tol),
                 lambda i, arr=arr, what=what, unit=unit: (f"t = {t[i]:.1f} ms: {side} forward kinematics "
                                                           f"misses the CL {what} by {arr[i]:.2e} {unit}"))
    figures[f"{side}_fk_error_mm"] = float(f"{ep.max(initial=0):.3g}")
    for k, axis in enumerate(AXES):
        peak = _axis_column(side, axis, t, a[:, 1 + k], a[:, 7 + k], machine.limits.axis(axis), rep)
        figures[f"{side}_{axis}_peak_accel_mm_s2"] = round(peak, 2)
    return figures


def _axis_column(side: str, axis: str, t: np.ndarray, x: np.ndarray, v: np.ndarray, lim,
                 rep: Report) -> float:
    """One axis's positions x (n,) mm and velocities v (n,) mm/ms at times t (n,) ms against its limits
    ``lim`` (stroke, speed, acceleration) and as a derivative; returns its peak acceleration, mm/s^2."""
    dt = np.diff(t)
    rep.many("axis range", np.flatnonzero((x < lim.min_mm - 1e-6) | (x > lim.max_mm + 1e-6)),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} = {x[i]:.4f} mm outside its stroke "
                       f"[{lim.min_mm:g}, {lim.max_mm:g}]")
    speed = np.abs(v) * 1000.0
    rep.many("axis speed", np.flatnonzero(speed > lim.max_speed_mm_s * (1 + 1e-6) + 1e-6),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} moves at {speed[i]:.3f} mm/s > "
                       f"{lim.max_speed_mm_s:g} mm/s")
    # the mean acceleration between two rows' velocities (as the planner bounds it), allowing for the
    # rounding of the written velocities (1e-9 mm/ms) and times
    dv = np.diff(v)
    acc = np.abs(dv) / dt * 1e6
    slack = (2e-9 / dt + np.abs(dv) * 2e-6 / dt**2) * 1e6
    hard = np.flatnonzero(acc > lim.max_accel_mm_s2 * (1 + 1e-6) + slack)
    rep.many("axis acceleration", hard[np.argsort(-acc[hard])],
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} accelerates at {acc[i]:.1f} mm/s^2 > "
                       f"{lim.max_accel_mm_s2:g} mm/s^2 (to the next row)")
    out = derivative_slack(t, x, v, lim.max_accel_mm_s2 / 1e6)
    bad = np.flatnonzero(out > 0)
    rep.many("axis velocities", bad[np.argsort(-out[bad])],
             lambda i: f"t = {t[i]:.1f} ms: {side} v{axis.lstrip('d')} is not the derivative of {axis}: from "
                       f"this row to the next {axis} moves at {(x[i + 1] - x[i]) / dt[i] * 1000:.3f} mm/s, "
                       f"the rows say {v[i] * 1000:.3f} and {v[i + 1] * 1000:.3f} mm/s")
    return float(acc.max(initial=0))
