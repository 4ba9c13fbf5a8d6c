"""``bladecam verify``: the checks of one cutter against its own files, run for both sides at once (in
helper processes while core.verify.cutters checks the two cutters together).

Completeness (``path_checks``): the ball centres (tip + r axis) are compared, not the tips: where a
machine's tilt limit turned the tool axis (core.machine.reach.limit_tilt, the single-sided paths'
axes: core.machine.tool_axes), it turned it about the ball centre, so the CL tables' tips differ from
pairs.csv's (which keeps the paper's axes) while the centres stay the same. Per side and path:
- every cutting row's centre lies within ``ROW_TOL`` of the polyline through pairs.csv's centres of
  its path (a path pairs.csv lacks, or a row moved off, is a finding);
- in order of time, the cutting rows of a path advance along it (back by at most ``ORDER_TOL``);
- every pair point's centre lies within ``REACH_TOL`` of the straight line a controller moves along
  between two consecutive rows that both cut that path (a deleted path, a truncated job, a row taken
  out of the cut all leave points unreached).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from core.paths.regions import REGION_CODE, REGION_NAMES
from core.records import DEFAULT_CHORD_TOL
from core.util.polyline import ball_centres
from core.verify.report import Report

#: mm: how far a cutting row's ball centre may lie from its path's polyline of pair centres (between
#: two pair points the tip moves straight and the axis turns, so the centre bulges off their chord by
#: r (1 - cos(turn / 2)): 1e-4 mm on the sample blade, 5e-3 mm where a ball rolls over a mesh's facet edge)
ROW_TOL = 0.01
#: mm: how far a pair point's ball centre may lie from the cutter's chords (the controller's straight
#: lines between rows; the plan keeps them within its chord tolerance, 0.001 mm by default: 1.3e-3 mm
#: measured on the sample blade and on BladeX); a plan made with a larger chord tolerance is allowed
#: the difference (``reach_tolerance``)
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


def label_checks(side: str, pairs: dict, cl: dict, rows: np.ndarray, ends: tuple[np.ndarray, np.ndarray],
                 rep: Report) -> None:
    """The CL table's labels of its cutting ``rows`` (those on their path) against pairs.csv, the
    segment of pairs.csv each lies on given by its two ``ends``: a row's region is the region of
    pairs.csv at its place (at either end of the segment), and its step is the tip region's (1 or 2)
    on a path of pairs.csv's tip region, never step 1 (the tip region's leading cutter) elsewhere."""
    region, step, path = cl["region"][rows], cl["step"][rows], cl["path"][rows]
    want_a, want_b = pairs["region"][ends[0]], pairs["region"][ends[1]]
    wrong = np.flatnonzero((region != want_a) & (region != want_b))

    def name(code) -> str:
        return REGION_NAMES[int(code)] if 0 <= int(code) < len(REGION_NAMES) else str(int(code))

    rep.many("labels", wrong, lambda j: f"t = {cl['t'][rows[j]]:.1f} ms: the {side} cutting row is labelled "
                                        f"{name(region[j])}, where pairs.csv has {name(want_a[j])} (path {path[j]})")
    tip = pairs["region"] == REGION_CODE["tip"]
    tip_paths = np.setdiff1d(np.unique(pairs["path"][tip]), np.unique(pairs["path"][~tip]))
    on_tip = np.isin(path, tip_paths)
    odd = np.flatnonzero((on_tip & (step > 2)) | (~on_tip & (step == 1)))
    rep.many("labels", odd, lambda j: f"t = {cl['t'][rows[j]]:.1f} ms: the {side} cutting row of path {path[j]} "
                                      f"({'tip region' if on_tip[j] else 'collaborative'}) is labelled step "
                                      f"{step[j]}")


def reach_tolerance(chord_tol: float | None) -> float:
    """REACH_TOL for a plan made with the chord tolerance ``chord_tol`` mm (None: not recorded, the
    default's): a row's chord strays up to that tolerance from the planned path, so a pair point may
    lie that much farther from the cutter's chords than at the default."""
    if chord_tol is None:
        return REACH_TOL
    return REACH_TOL + max(0.0, chord_tol - DEFAULT_CHORD_TOL)


def path_checks(side: str, pairs: dict, cl: dict, tool_radius: float, rep: Report,
                reach_tol: float = REACH_TOL) -> dict:
    """Completeness of one cutter (module docstring) against pairs.csv (``pairs``: its arrays sorted
    by path and k). Findings go into ``rep``; returns its figures.

    Each cutting row is placed on its path (the nearest point of the polyline of pair centres: an arc
    coordinate), and so are the rows just before and after each run of rows cutting one path; the
    chord from a row to the next covers the arc between their places. A pair point is reached when a
    chord covering it passes within reach_tol of it: first the chords between two rows that both cut
    the path and lie on it, then, for the points those leave, the chords into and out of each run
    (rows lie on a fixed period, so a cut begins and ends between two rows). One search
    (near_segments), then sorting: no second search of the rows."""
    r = tool_radius
    pair_path, pair_k = pairs["path"], pairs["k"]
    pair_centres = ball_centres(pairs[f"{side}_tip"], pairs[f"{side}_axis"], r)
    t, path, cut = cl["t"], cl["path"], cl["cutting"]
    n = len(t)
    cut_rows = np.flatnonzero(cut)
    cut_path = path[cut_rows]
    # the rows into (before) and out of (after) each run of rows cutting one path, with its path
    before, after = np.maximum(cut_rows - 1, 0), np.minimum(cut_rows + 1, n - 1)
    first = cut_rows[(cut_rows > 0) & ~(cut[before] & (path[before] == cut_path))]
    last = cut_rows[(cut_rows < n - 1) & ~(cut[after] & (path[after] == cut_path))]
    rows = np.r_[cut_rows, first - 1, last + 1]
    label = np.r_[cut_path, path[first], path[last]]
    n_cut = len(cut_rows)
    centres = ball_centres(cl["p"][rows], cl["w"][rows], r)
    # pairs.csv's polylines: consecutive points of one path (a path of one point: that point), and
    # an arc coordinate along all of them (paths 1 m apart: no interval reaches from one to the next)
    link = np.flatnonzero(pair_path[1:] == pair_path[:-1])
    lone = np.flatnonzero(np.r_[True, pair_path[1:] != pair_path[:-1]] & np.r_[pair_path[1:] != pair_path[:-1], True])
    seg_a, seg_b = np.r_[link, lone], np.r_[link + 1, lone]
    step = np.linalg.norm(np.diff(pair_centres, axis=0), axis=1)
    arc = np.r_[0.0, np.cumsum(np.where(pair_path[1:] == pair_path[:-1], step, 1000.0))]
    dist_all, seg, s = near_segments(centres, label, pair_centres, seg_a, seg_b, pair_path[seg_a], ROW_TOL,
                                     ROW_TOL / 10)
    u = arc[seg_a[seg]] + s * (arc[seg_b[seg]] - arc[seg_a[seg]])
    dist = dist_all[:n_cut]
    known = np.isin(cut_path, pair_path)
    stray = np.flatnonzero(~known)
    if stray.size:
        rep.many("off path", stray[np.unique(cut_path[stray], return_index=True)[1]],
                 lambda j: f"t = {t[cut_rows[j]]:.1f} ms: the {side} cutter cuts path {cut_path[j]}, which pairs.csv "
                           "does not have")
    on = known & (dist <= ROW_TOL)
    rep.many("off path", np.flatnonzero(known & ~on),
             lambda j: f"t = {t[cut_rows[j]]:.1f} ms: {side} cutting row {dist[j]:.4f} mm off path {cut_path[j]} "
                       "(pairs.csv's ball centres)")
    on_rows = np.flatnonzero(on)
    label_checks(side, pairs, cl, cut_rows[on_rows], (seg_a[seg[on_rows]], seg_b[seg[on_rows]]), rep)
    # a row not cutting between two rows cutting one path (a cut is never interrupted for one row)
    gap = np.flatnonzero((np.diff(cut_rows) == 2) & (cut_path[1:] == cut_path[:-1]))
    rep.many("completeness", gap, lambda j: f"t = {t[cut_rows[j] + 1]:.1f} ms: the {side} cutter's row is not "
                                            f"cutting between two rows cutting path {cut_path[j]}")
    # order: each run of rows cutting one path advances along it, and each run of a path starts where
    # the one before it ended or farther (compared at the runs' ends: a row's place is ambiguous where
    # a mesh's ball rolls round a facet corner and its path of centres nearly meets itself)
    pos_first, pos_last = np.searchsorted(cut_rows, first), np.searchsorted(cut_rows, last)
    onpos = np.flatnonzero(on)
    run = np.searchsorted(pos_first, onpos, side="right") - 1
    runs, head = np.unique(run, return_index=True)
    tail = len(run) - 1 - np.unique(run[::-1], return_index=True)[1]
    if runs.size:
        seq = np.column_stack([onpos[head], onpos[tail]]).ravel()       # (positions in cut_rows, in time)
        by = seq[np.argsort(cut_path[seq], kind="stable")]
        du = np.diff(u[by])
        back = np.flatnonzero((cut_path[by][1:] == cut_path[by][:-1]) & (du < -ORDER_TOL))
        if back.size:  # (one finding per path: its largest step back)
            o = np.lexsort((du[back], cut_path[by][back]))
            worst = np.sort(back[o][np.r_[True, cut_path[by][back][o][1:] != cut_path[by][back][o][:-1]]])
            rep.many("order", worst,
                     lambda j: f"t = {t[cut_rows[by[j + 1]]]:.1f} ms: the {side} cutter is {-du[j]:.3f} mm back "
                               f"along path {cut_path[by[j]]} from t = {t[cut_rows[by[j]]]:.1f} ms (cut out of order)")
    # reach: the chords between consecutive rows cutting one path (and each such row alone), then
    # those into and out of each run
    inner = np.flatnonzero((np.diff(cut_rows) == 1) & (cut_path[1:] == cut_path[:-1]) & on[1:] & on[:-1])
    alone = np.flatnonzero(on)
    ends_ok = np.isfinite(dist_all)
    into = np.flatnonzero(on[pos_first] & ends_ok[n_cut + np.arange(len(first))])
    out = np.flatnonzero(on[pos_last] & ends_ok[n_cut + len(first) + np.arange(len(last))])
    reach = np.full(len(pair_path), np.inf)
    inner_a, inner_b = inner, inner + 1
    end_a = np.r_[pos_first[into], pos_last[out], alone]
    end_b = np.r_[n_cut + into, n_cut + len(first) + out, alone]
    for ra, rb, slack in ((inner_a, inner_b, 1e-9), (end_a, end_b, reach_tol)):
        todo = np.flatnonzero(reach > reach_tol)
        lo, hi = np.minimum(u[ra], u[rb]) - slack, np.maximum(u[ra], u[rb]) + slack
        held = _covering(lo, hi, arc[todo])
        h = held >= 0
        d = _segment_distance(pair_centres[todo[h]], centres[ra[held[h]]], centres[rb[held[h]]])[0]
        reach[todo[h]] = np.minimum(reach[todo[h]], d)
    todo = np.flatnonzero(reach > reach_tol / 10)
    if todo.size:  # (where a row's place on a sharp turn is ambiguous: the nearest chord of all)
        ra, rb = np.r_[inner_a, end_a], np.r_[inner_b, end_b]
        d = near_segments(pair_centres[todo], pair_path[todo], centres, ra, rb, label[ra], reach_tol, reach_tol / 10)[0]
        reach[todo] = np.minimum(reach[todo], d)
    miss = np.flatnonzero(reach > reach_tol)
    if miss.size:
        paths, start, n_miss = np.unique(pair_path[miss], return_index=True, return_counts=True)
        total = np.bincount(pair_path)[paths]
        cut_paths = set(np.unique(cut_path[on]).tolist())

        def line(j: int) -> str:
            idx = miss[start[j]:start[j] + n_miss[j]]
            if paths[j] not in cut_paths:
                return f"the {side} cutter never cuts path {paths[j]} ({total[j]} pair points)"
            far = reach[idx][np.isfinite(reach[idx])]
            return (f"the {side} cutter misses {idx.size} of the {total[j]} pair points of path {paths[j]} "
                    f"(k {_runs(pair_k[idx])}): up to {far.max(initial=0):.3f} mm from its cut")

        rep.many("completeness", np.arange(len(paths)), line)
    return {f"{side}_path_error_mm": float(f"{dist[on].max(initial=0):.3g}"),
            f"{side}_reach_error_mm": float(f"{reach[np.isfinite(reach)].max(initial=0):.3g}")}
