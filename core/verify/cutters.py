"""``bladecam verify``: the checks of the two cutters together (``two_cutters``): one common time column
on the period, tip spacing >= h_safe at and between samples, tool capsules that never touch (the
distance between their axis segments in closed form), feed and acceleration along the path, every
cutting ball centre on the blade's offset surface (``_surface``), and no ball in the blade at any
other row nor on the straight moves between rows (``_clearance``). The balls' distances are verify's
own (core.verify.distance), measured once per side along the rows (``_tracks``).

How the tessellation's error counts: the distances are to the blade's triangles, made afresh from
the blade (core.paths.tessellation.surface_mesh); their chords lie inside a convex blade (outside
a concave one) by up to the tessellation's own tolerance where it is a table's, and by up to a few
hundredths of a millimetre along a rounded edge, whose chords are coarser. MISS_TOLERANCE and
ROW_DIP below are what the checks allow for it.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from core.paths.regions import REGION_NAMES
from core.records import DEFAULT_CHORD_TOL
from core.util.polyline import ball_centres
from core.verify.distance import DistanceIndex, segment_gaps
from core.verify.report import Report

#: how far a cutting ball centre may sit outside the offset surface (mm): the check's own tessellation
#: (0.25 mm chordwise) lies inside a rounded edge by up to a few hundredths of a millimetre there
MISS_TOLERANCE = 0.05
#: how far a ball centre at a row may lie inside the offset surface (mm): the check's tessellation
#: against the smooth blade
ROW_DIP = 2e-3
#: mm: a ball's distance beyond the offset surface is measured exactly up to this, a lower bound
#: beyond it (a miss that large is reported as at least this)
BALL_EXACT = 0.1
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


def _capsule_gap(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
    """(n,) mm: the distance between the segments a0-a1 and b0-b1 (each (n, 3) mm), row by row, in
    closed form (core.verify.distance.segment_gaps: the closest pair of two segments, with no
    iterations)."""
    return segment_gaps(a0, a1, b0, b1)


def two_cutters(left: dict, right: dict, inp: dict, index: DistanceIndex, surface_stride: int,
                rep: Report) -> None:
    """The time column, the tip spacing and tool clearance, feed and acceleration along the path, and
    the balls on and off the offset surface (module docstring). ``left``, ``right``: the CL tables
    (core.verify.read); ``inp``: plan.json's inputs; ``index``: verify's index of the blade's
    tessellation; ``surface_stride``: every how many cutting rows the offset surface is checked."""
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
    # kinematics on cutting stretches (a repeated row, a finding of the time column, divides by zero)
    dt = np.diff(t)
    for name, s in (("left", left), ("right", right)):
        _kinematics(name, s, t, dt, feed, a_max, rep)
    chord_tol = inp.get("chord_tol_mm") or DEFAULT_CHORD_TOL
    tracks = _tracks({"left": left, "right": right}, r, index, surface_stride, chord_tol + ROW_DIP)
    _surface(left, right, t, r, tracks, surface_stride, rep)
    _clearance(left, right, t, r, tracks, chord_tol, rep)
    rep.figures.update({"samples": int(len(t)),
                        "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
                        "min_capsule_gap_mm": round(float(gap.min()), 6)})


@np.errstate(divide="ignore", invalid="ignore")
def _kinematics(name: str, s: dict, t: np.ndarray, dt: np.ndarray, feed: float, a_max: float,
                rep: Report) -> None:
    """One cutter's speed and acceleration along its path on cutting stretches."""
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


def _tracks(cls: dict, r: float, index: DistanceIndex, surface_stride: int, dip: float) -> dict:
    """Each side's ball distances (``_track``), the two sides in two threads."""
    with ThreadPoolExecutor(2) as pool:
        return dict(zip(SIDES, pool.map(lambda side: _track(cls[side], r, index, surface_stride, dip), SIDES),
                        strict=True))


def _track(s: dict, r: float, index: DistanceIndex, surface_stride: int, dip: float) -> dict:
    """One side's ball centres' distances from the blade (mm; exact up to r + BALL_EXACT, lower bounds
    beyond), measured along the rows in order (neighbours share the search's start): "rows" (n,) at
    the rows not cutting and every surface_stride-th cutting row (nan at the others); "moves" (m,) at
    points every half tool radius along the straight move between each two rows (the move's index in
    "seg" (m,)): a move across the blade lands a point within a quarter radius of where it enters,
    where the ball's centre is nearer the surface than r. A point of a move is measured where its
    bound from the rows either side (``_between_bound``) allows it to lie ``dip`` (mm) or more inside
    the offset surface, or lower than the least clearance measured: elsewhere it keeps that bound,
    so that the moves' findings and least clearance are those of measuring every point."""
    c = ball_centres(s["p"], s["w"], r)
    wanted = ~s["cutting"]
    wanted[np.flatnonzero(s["cutting"])[::surface_stride]] = True
    length = np.linalg.norm(np.diff(c, axis=0), axis=1)
    pieces = np.maximum(np.ceil(length / (0.5 * r)), 1).astype(np.int64)
    seg = np.repeat(np.arange(len(c) - 1), pieces)
    frac = (np.arange(len(seg)) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 0.5) / pieces[seg]
    between = c[seg] + frac[:, None] * (c[seg + 1] - c[seg])
    rows = np.full(len(c), np.nan)
    rows[wanted] = index.distances(c[wanted], cutoff=r + BALL_EXACT)
    moves = _between_bound(rows, seg, frac, length)
    measured = np.zeros(len(seg), bool)
    todo = moves - r < -dip
    todo[np.argpartition(moves, min(len(moves) // 100, len(moves) - 1))[:len(moves) // 100 + 1]] = True
    least = float(np.min(rows[~s["cutting"]], initial=np.inf)) - r  # (the rows not cutting: all measured)
    while todo.any():  # (the lowest bounds first: then those still below the least measured)
        moves[todo] = index.distances(between[todo], cutoff=r + BALL_EXACT)
        measured |= todo
        least = min(least, float(moves[todo].min()) - r)
        todo = ~measured & (moves - r < least)
    return {"rows": rows, "moves": moves, "seg": seg}


def _between_bound(rows: np.ndarray, seg: np.ndarray, frac: np.ndarray, length: np.ndarray) -> np.ndarray:
    """(m,) mm: a lower bound of the distance from the blade of each point a fraction frac (m,) along
    the straight move seg (m,) between two rows whose distances are ``rows`` (n,) mm (nan: not
    measured, bound 0) and whose ball centres lie length (n - 1,) mm apart. The squared distance to
    any set less the squared norm is concave (a least of affine functions), so along a move of
    length L, d(s)^2 >= (1 - s) d(0)^2 + s d(1)^2 - L^2 s (1 - s)."""
    d0, d1 = np.nan_to_num(rows[seg]), np.nan_to_num(rows[seg + 1])
    f = (1.0 - frac) * d0 * d0 + frac * d1 * d1 - length[seg] ** 2 * frac * (1.0 - frac)
    return np.sqrt(np.maximum(f, 0.0))


def _surface(left: dict, right: dict, t: np.ndarray, r: float, tracks: dict, surface_stride: int,
             rep: Report) -> None:
    """The cutting balls on the offset surface (every surface_stride-th): no gouge deeper than ROW_DIP,
    no air cut beyond MISS_TOLERANCE (a miss beyond BALL_EXACT is at least that: a lower bound)."""
    for name, s in (("left", left), ("right", right)):
        idx = np.flatnonzero(s["cutting"])[::surface_stride]
        if idx.size == 0:
            continue
        dist = tracks[name]["rows"][idx] - r
        rep.many("surface", np.flatnonzero((dist < -ROW_DIP) | (dist > MISS_TOLERANCE)),
                 lambda j, idx=idx, dist=dist, name=name: (
                     f"t = {t[idx[j]]:.1f} ms: {name} ball {'cuts into' if dist[j] < 0 else 'misses'} "
                     f"the blade by {'at least ' if dist[j] > BALL_EXACT else ''}{abs(dist[j]):.4f} mm"))
        rep.figures[f"{name}_surface_offset_mm"] = [round(float(dist.min()), 6), round(float(dist.max()), 6)]


def _clearance(left: dict, right: dict, t: np.ndarray, r: float, tracks: dict, chord_tol: float,
               rep: Report) -> None:
    """No ball in the blade at a row that does not cut (a turn, an idle or a lift: the classic crash is
    a rapid through the workpiece), nor on the straight move a controller makes between two rows,
    cutting or not (``_track``'s points along it). A row may dip ROW_DIP into the offset surface (as
    a cutting row may), a move between rows that much more than the plan's chord tolerance (its
    straight line strays that far from the path: the dip ``_tracks`` is given)."""
    for name, s in (("left", left), ("right", right)):
        idle = np.flatnonzero(~s["cutting"])
        at_rows = tracks[name]["rows"][idle] - r
        on_moves, seg = tracks[name]["moves"] - r, tracks[name]["seg"]
        rep.many("surface", np.flatnonzero(at_rows < -ROW_DIP),
                 lambda j, idle=idle, d=at_rows, name=name, s=s: (
                     f"t = {t[idle[j]]:.1f} ms: {name} ball, not cutting "
                     f"({_region_name(s['region'][idle[j]])}), {abs(d[j]):.4f} mm inside the blade"))
        deep = np.flatnonzero(on_moves < -(chord_tol + ROW_DIP))
        worst = deep[np.unique(seg[deep], return_index=True)[1]]  # (one finding per move)
        rep.many("surface", worst,
                 lambda j, d=on_moves, name=name, seg=seg: (
                     f"t = {t[seg[j]]:.1f} to {t[seg[j] + 1]:.1f} ms: {name} ball's straight move between "
                     f"two rows passes {abs(d[j]):.4f} mm inside the blade"))
        low = float(min(at_rows.min(initial=np.inf), on_moves.min(initial=np.inf)))
        rep.figures[f"{name}_clearance_mm"] = round(low, 6) if np.isfinite(low) else None


def _region_name(code: int) -> str:
    return REGION_NAMES[code] if 0 <= code < len(REGION_NAMES) else str(code)
