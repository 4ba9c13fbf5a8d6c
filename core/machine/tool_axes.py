"""Executed tool axes of the single-sided paths (the tip region, and paths taken out of collaborative
machining): one axis per path wherever one serves, so that the head does not swing while it cuts.

In the tip region the paper puts the tool axis on the surface normal. Round the rounded edges the
normal turns by up to 100 degrees within a millimetre of tip travel, and the 3-RPS head can follow
only by swinging the spindle, which the XYZ stage compensates over the gauge length (280 mm): the
axes then ask for over a hundred millimetres of axis travel per millimetre of tip, and the machine
crawls there whatever the timing.

A ball-end cutter cuts the same surface whatever its axis, as long as the ball centre stays where it
is and the contact stays on the ball's cutting hemisphere. So the axis of a single-sided path is
chosen, about the fixed ball centres (the tips move with the axes), within two limits at every point:

- the head's reach: the axis within ``max_tilt_deg`` of the spindle axis;
- the contact on the cutting hemisphere with a margin: the axis within CONTACT_LIMIT_DEG of the
  surface normal at the contact (the contact then stays 10 degrees above the ball's equator, where
  the neck begins).

Each limit is a spherical cap of axes; a path's axes that keep both limits everywhere are the
intersection of the caps of all its points. The axis of a path is the point of that intersection
reached from the path's mean normal (weighted by the ball centres' arc length) by projecting onto the
most violated cap in turn (the remotest-set method of projections onto convex sets): the mean normal
itself where it keeps every contact on the hemisphere, else the nearest axis tilted just enough
towards the edge the path wraps round. Along the path the axis is then constant: the head does not
swing while the cutter cuts, and the change from one path's axis to the next is made on the
non-cutting turn between them (core.paths.contours.turning_path), where it is small because the
mean normals and the edges change little from one path to the next.

Where no one axis serves a path (its normals more than 2 x CONTACT_LIMIT_DEG apart, or beyond the
head's reach together), the path is halved by arc length, up to MAX_SPLITS times, until each piece
has an axis (each piece's found from the path's mean normal, so that the pieces' axes differ no
more than their caps make them); the axes of the pieces are interpolated along the arc length
between knots at the path's two ends and the inner pieces' middles, so the forced swing is spread
over the whole path, and each point's axis is projected onto its own two caps (``onto_lens``).

A point whose two caps do not meet (its normal more than max_tilt_deg + CONTACT_LIMIT_DEG from the
spindle axis: beyond what the machine reaches with the contact within the margin) has its contact cap
widened until they do: its one axis is then its normal turned to the head's limit (the least contact
angle the head allows), and it is flagged. Such points force a swing where they follow each other.

**Strokes.** ``single_sided_axes`` takes optional ``strokes`` (StrokeCaps): the XYZ stage's strokes
as caps too. About a fixed ball centre the stage position is affine in the axis but for the head's
parasitic motion (a few millimetres; core.machine.kinematics), so each stroke end is a half-space of
axes, {w : w . m >= bound}, one more spherical cap per point about the stage axis m (the same for
every point, so a piece's caps about m are its narrowest point's), projected onto like the others. The
paths are chosen without the strokes first; a path whose axes leave one (the bounds linearised at its
axes, exact there) is chosen again with its stroke caps, up to STROKE_ROUNDS times, each round
linearised at the last round's axes. A point whose contact cap has no axis in common with its reach
and strokes has its contact cap widened to the nearest axis that keeps both (the machine's limits
are hard, the contact margin is not); a point no axis within reach keeps within its strokes is left
out of the stroke caps and flagged (``within_strokes``): its path's axis is chosen for the others,
and the plan's limit check refuses the plan.

**Clearance.** ``single_sided_axes`` takes an optional ``clearance(centres, axes) -> (m,) mm``: the
least distance from the tool assembly above the ball (neck, shank, holder) to the blade at each point
(negative: a collision). Where it is negative the point's contact cap is narrowed by
CLEARANCE_STEP_DEG (the axis stood up towards the surface normal there, which lifts the neck and
shank off the surface round the contact) and the path's axis is chosen again, up to CLEARANCE_ROUNDS
times; the points still colliding are flagged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from core.util.polyline import cumulative_length, unit_rows
from core.util.rowwise import row_norm

#: the largest angle between the executed axis and the surface normal at the contact (degrees): the
#: contact stays this far from the ball's equator, 90 degrees off the axis, where the neck begins
CONTACT_LIMIT_DEG = 80.0
#: rounds of projections onto the most violated cap per piece of path
PROJECTION_ROUNDS = 200
#: a path no one axis serves is halved at most this many times (into at most 2^MAX_SPLITS pieces)
MAX_SPLITS = 6
#: the limits hold to this (radians)
ANGLE_TOLERANCE = 1e-9
#: rounds of turning the axes away from a collision the clearance callable reports
CLEARANCE_ROUNDS = 4
#: each round narrows a colliding point's contact cap by this much (degrees)
CLEARANCE_STEP_DEG = 20.0
#: rounds of linearising the strokes at the chosen axes and choosing again
STROKE_ROUNDS = 3
#: a stroke cap holds to this (its cosine)
STROKE_TOLERANCE = 1e-12
#: a path is chosen again where its axes leave a stroke's aim by more than this share of the slack
#: (StrokeCaps.slack) the aim leaves inside the stroke
STROKE_REDO_SHARE = 0.1

Clearance = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class StrokeCaps:
    """The XYZ stage's strokes as caps on the axes about the fixed ball centres: ``directions`` (k, 3)
    unit; ``bounds(index, axes)`` (m, k), for the points ``index`` (m,) (the paths concatenated) at the
    unit axes (m, 3), the least ``w . directions[j]`` each keeps its strokes with, aimed ``slack``
    (a cosine) or more inside them and linearised at those axes: exact there (the axes keep every
    stroke where w . directions >= bounds(index, w) - slack), and the caps
    {w : w . directions[j] >= bound} about any other axis w."""

    directions: np.ndarray
    bounds: Callable[[np.ndarray, np.ndarray], np.ndarray]
    slack: float


def within(w: np.ndarray, centre: np.ndarray, limit) -> np.ndarray:
    """Unit axes w (n, 3) turned towards the unit vectors ``centre`` ((3,) or (n, 3)), in the plane of
    the two, where they are more than ``limit`` radians (a number or (n,)) from them (the projection
    onto a spherical cap)."""
    centre = np.broadcast_to(centre, w.shape)
    limit = np.broadcast_to(np.asarray(limit, float), (len(w),))
    cos = np.einsum("ij,ij->i", w, centre)
    over = cos < np.cos(limit)
    if not over.any():
        return w
    perp = w[over] - cos[over, None] * centre[over]
    norm = row_norm(perp)
    out = w.copy()
    ok = norm > 1e-12  # w opposite the centre has no plane: left for the caller's check
    sel = np.flatnonzero(over)[ok]
    lim = limit[sel]
    out[sel] = np.cos(lim)[:, None] * centre[sel] + np.sin(lim)[:, None] * perp[ok] / norm[ok, None]
    return out


def onto_lens(w: np.ndarray, a: np.ndarray, alpha, b: np.ndarray, beta: float) -> np.ndarray:
    """Unit axes w (n, 3) moved to the nearest point of the intersection of two spherical caps: of
    radius ``alpha`` (a number or (n,), rad) about the unit rows ``a`` (n, 3) and of radius ``beta``
    about ``b`` (3,). The projection onto one cap where it lands inside the other, else the nearer of
    the two points where the caps' rims cross; where the caps do not meet, the projection onto the
    cap about ``b``. (Alternating the two projections crawls into the thin lens two nearly tangent caps
    make.)"""
    alpha = np.broadcast_to(np.asarray(alpha, float), (len(w),))
    out = within(w, a, alpha)
    cos_a, cos_b = np.cos(alpha + ANGLE_TOLERANCE), np.cos(beta + ANGLE_TOLERANCE)
    bad = np.flatnonzero(out @ b < cos_b)
    if bad.size == 0:
        return out
    onto_b = within(w[bad], b, beta)
    inside = np.einsum("ij,ij->i", onto_b, a[bad]) >= cos_a[bad]
    out[bad[inside]] = onto_b[inside]
    k = bad[~inside]
    if k.size == 0:
        return out
    # the rims cross at x = c1 a + c2 b + t (a x b): x.a = cos alpha, x.b = cos beta, |x| = 1
    ak, ca, cb = a[k], np.cos(alpha[k]), np.cos(beta)
    g = ak @ b
    det = np.maximum(1.0 - g * g, 1e-300)
    c1, c2 = (ca - g * cb) / det, (cb - g * ca) / det
    base = c1[:, None] * ak + c2[:, None] * b
    axis = np.cross(ak, b)
    t2 = (1.0 - row_norm(base) ** 2) / np.maximum(row_norm(axis) ** 2, 1e-300)
    meet = t2 >= 0.0
    t = np.sqrt(np.maximum(t2, 0.0))
    plus, minus = base + t[:, None] * axis, base - t[:, None] * axis
    nearer = np.einsum("ij,ij->i", plus, w[k]) >= np.einsum("ij,ij->i", minus, w[k])
    cross = unit_rows(np.where(nearer[:, None], plus, minus))
    out[k] = np.where(meet[:, None], cross, onto_b[~inside])
    return out


@dataclass(frozen=True)
class AxisChoice:
    """The executed axes of single-sided paths: ``axes`` one (m, 3) array of unit axes per path;
    ``within_limits`` (n,) over all points (the paths concatenated), where both limits hold;
    ``clear`` (n,) where the clearance callable found no collision (all True without one);
    ``pieces`` per path, the number of pieces with an axis of their own (1: one axis for the path);
    ``within_strokes`` (n,) where the axis keeps the machine's strokes (all True without them)."""

    axes: list
    within_limits: np.ndarray
    clear: np.ndarray
    pieces: np.ndarray
    within_strokes: np.ndarray


def _mean_normals(normals: np.ndarray, weights: np.ndarray, starts: np.ndarray, spindle: np.ndarray,
                  tilt: float) -> np.ndarray:
    """(p, 3) the weighted mean normal of each run of points from ``starts`` to the next start, turned
    within the head's reach (the spindle axis where the normals cancel out)."""
    ref = np.add.reduceat(normals * weights[:, None], starts)
    ref = np.where(row_norm(ref)[:, None] > 1e-9, unit_rows(ref), spindle)
    return within(ref, spindle, tilt)


def _piece_axes(normals: np.ndarray, start: np.ndarray, starts: np.ndarray, limit: np.ndarray,
                spindle: np.ndarray, tilt: float, stroke: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One axis per piece (consecutive points from ``starts`` to the next start) and whether it keeps
    every point's contact cap (``limit`` (n,) rad), its stroke caps (``stroke``: the directions (k, 3)
    and each point's bounds (n, k), StrokeCaps; None: no strokes) and the tilt cap: from the piece's
    ``start`` axis (p, 3), projections onto the most violated cap in turn (module docstring)."""
    sizes = np.diff(np.append(starts, len(normals)))
    owner = np.repeat(np.arange(len(starts)), sizes)
    w = start.copy()
    cos_lim = np.cos(limit + ANGLE_TOLERANCE)
    cos_tilt = np.cos(tilt + ANGLE_TOLERANCE)
    # a piece's stroke caps: per direction the narrowest of its points' (they share the directions)
    dirs = np.zeros((0, 3)) if stroke is None else stroke[0]
    need = np.zeros((len(starts), 0)) if stroke is None else np.maximum.reduceat(stroke[1], starts, axis=0)

    def stroke_margins(k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pieces k's least margin (cosine) over their stroke caps (inf without) and that cap."""
        over = w[k] @ dirs.T - need[k] + STROKE_TOLERANCE
        if over.shape[1] == 0:
            return np.full(len(k), np.inf), np.zeros(len(k), int)
        j = over.argmin(axis=1)
        return over[np.arange(len(k)), j], j

    active = np.arange(len(starts))
    pts = np.arange(len(normals))  # the points of the active pieces
    for _ in range(PROJECTION_ROUNDS):
        margin = np.einsum("ij,ij->i", normals[pts], w[owner[pts]]) - cos_lim[pts]
        local = np.searchsorted(pts, starts[active])  # each active piece's first point in pts
        worst = np.minimum.reduceat(margin, local)
        least, cap = stroke_margins(active)
        bad = (worst < 0) | (least < 0) | (w[active] @ spindle < cos_tilt)
        if not bad.any():
            break
        # each violating piece onto its most violated cap: the first most violated point's contact cap
        hit = np.flatnonzero(margin < 0)
        piece = np.searchsorted(local, hit, side="right") - 1
        is_worst = (margin[hit] == worst[piece]) & (worst[piece] <= least[piece])
        hit = hit[is_worst]
        pieces, first = np.unique(owner[pts[hit]], return_index=True)
        k = pts[hit[first]]
        w[pieces] = onto_lens(w[pieces], normals[k], limit[k], spindle, tilt)
        on = (least < 0) & (least < worst)  # or its stroke cap
        if on.any():
            sp, j = active[on], cap[on]
            w[sp] = onto_lens(w[sp], dirs[j], np.arccos(np.clip(need[sp, j], -1.0, 1.0)), spindle, tilt)
        moved = active[bad]
        w[moved] = within(w[moved], spindle, tilt)
        active = moved
        pts = np.flatnonzero(np.isin(owner, active))
    margin = np.einsum("ij,ij->i", normals, w[owner]) - cos_lim
    ok = ((np.minimum.reduceat(margin, starts) >= 0) & (stroke_margins(np.arange(len(starts)))[0] >= 0)
          & (w @ spindle >= cos_tilt))
    return w, ok


def _path_axes(normals: np.ndarray, s: np.ndarray, bounds: np.ndarray, limit: np.ndarray,
               spindle: np.ndarray, tilt: float, stroke: tuple | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axes (n, 3) of paths laid end to end (``bounds`` (p + 1,) their first points and the end; ``s``
    (n,) each point's arc length along its own path), whether the limits hold at each point, and the
    number of pieces of each path (module docstring); ``stroke`` as in _piece_axes."""
    n = len(normals)
    ds = np.diff(s)
    weights = np.zeros(n)
    inner = np.ones(n - 1, bool)
    inner[bounds[1:-1] - 1] = False  # no segment between the end of one path and the next
    seg = np.where(inner, ds, 0.0) / 2.0
    weights[:-1] += seg
    weights[1:] += seg
    single = np.diff(bounds) == 1
    weights[bounds[:-1][single]] = 1.0  # (a path of one point: its normal)
    # every piece of a path starts from the path's mean normal: the pieces' axes then differ no more
    # than their caps make them
    ref = _mean_normals(normals, weights, bounds[:-1], spindle, tilt)
    pieces = [np.array([a]) for a in bounds[:-1]]  # per path, the first points of its pieces
    done_axes: dict[int, np.ndarray] = {}
    todo = list(range(len(pieces)))
    for depth in range(MAX_SPLITS + 1):
        if not todo:
            break
        starts = np.concatenate([pieces[k] for k in todo])
        ends = np.concatenate([np.append(pieces[k][1:], bounds[k + 1]) for k in todo])
        pts = np.concatenate([np.arange(a, b) for a, b in zip(starts, ends, strict=True)])
        local = np.concatenate([[0], np.cumsum(ends - starts)[:-1]])
        path_of = np.concatenate([np.full(len(pieces[k]), k) for k in todo])
        sub = None if stroke is None else (stroke[0], stroke[1][pts])
        w, ok = _piece_axes(normals[pts], ref[path_of], local, limit[pts], spindle, tilt, sub)
        by_start = dict(zip(starts.tolist(), range(len(starts)), strict=True))
        again = []
        for k in todo:
            idx = [by_start[a] for a in pieces[k].tolist()]
            if ok[idx].all() or depth == MAX_SPLITS:
                done_axes[k] = w[idx]
                continue
            split = []  # halve, by arc length, each piece that has no axis (and more than one point)
            for a, b, good in zip(pieces[k], np.append(pieces[k][1:], bounds[k + 1]), ok[idx], strict=True):
                split.append(a)
                if not good and b - a > 1:
                    mid = int(np.searchsorted(s[a:b], 0.5 * (s[a] + s[b - 1]))) + a
                    split.append(min(max(mid, a + 1), b - 1))
            pieces[k] = np.array(split)
            again.append(k)
        todo = again
    axes = np.empty((n, 3))
    for k in range(len(pieces)):
        a, b = bounds[k], bounds[k + 1]
        piece_w = done_axes[k]
        if len(piece_w) == 1:
            axes[a:b] = piece_w[0]
            continue
        # the pieces' axes linear in arc length between knots at the path's ends and the middles of the
        # inner pieces: the swing spread over the whole path
        ends = np.append(pieces[k][1:], b)
        mid = 0.5 * (s[pieces[k]] + s[ends - 1])
        mid[0], mid[-1] = s[a], s[b - 1]
        for j in range(3):
            axes[a:b, j] = np.interp(s[a:b], mid, piece_w[:, j])
        axes[a:b] = unit_rows(axes[a:b])
    axes = onto_lens(axes, normals, limit, spindle, tilt)  # (a no-op where the path's axis serves)
    ok = ((np.einsum("ij,ij->i", axes, normals) >= np.cos(limit + ANGLE_TOLERANCE))
          & (axes @ spindle >= np.cos(tilt + ANGLE_TOLERANCE)))
    axes = np.where(ok[:, None], axes, within(normals, spindle, tilt))
    if stroke is not None:  # a point the interpolated axes take out of a stroke: its own caps alone
        out = np.flatnonzero((axes @ stroke[0].T - stroke[1] + STROKE_TOLERANCE < 0).any(axis=1))
        if out.size:
            w, good = _piece_axes(normals[out], axes[out], np.arange(out.size), limit[out], spindle, tilt,
                                  (stroke[0], stroke[1][out]))
            axes[out[good]] = w[good]
            ok[out[~good]] = False
    return axes, ok, np.array([len(p) for p in pieces])


def _stroke_axes(normals: np.ndarray, s: np.ndarray, bounds: np.ndarray, limit: np.ndarray,
                 spindle: np.ndarray, tilt: float, strokes: StrokeCaps | None, index: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """_path_axes within the strokes too (``index`` (n,): the points' numbers for ``strokes.bounds``),
    and where the axes keep the strokes (exactly, StrokeCaps.bounds at the axes): the paths are chosen
    without the strokes; a path whose axes leave a stroke's aim is chosen again with its stroke caps,
    linearised at its axes, up to STROKE_ROUNDS times (each round's bounds at least the last's: the
    linearisations add up)."""
    axes, ok, pieces = _path_axes(normals, s, bounds, limit, spindle, tilt)
    inside = np.ones(len(normals), bool)
    if strokes is None:
        return axes, ok, pieces, inside
    dirs = strokes.directions
    lo = np.full((len(normals), len(dirs)), -np.inf)
    owner = np.repeat(np.arange(len(bounds) - 1), np.diff(bounds))
    look = np.arange(len(normals))  # the points of the paths chosen last
    for round_ in range(STROKE_ROUNDS + 1):
        fresh = strokes.bounds(index[look], axes[look])
        margin = axes[look] @ dirs.T - fresh
        inside[look] = (margin + strokes.slack >= 0).all(axis=1)
        redo = np.unique(owner[look[(margin + STROKE_REDO_SHARE * strokes.slack < 0).any(axis=1)]])
        if redo.size == 0 or round_ == STROKE_ROUNDS:
            break
        lo[look] = np.maximum(lo[look], fresh)
        look = np.concatenate([np.arange(bounds[k], bounds[k + 1]) for k in redo])
        sub_bounds = np.concatenate([[0], np.cumsum(np.diff(bounds)[redo])])
        wide, need = _widened(normals[look], axes[look], limit[look], spindle, tilt, (dirs, lo[look]))
        axes[look], ok[look], pieces[redo] = _path_axes(normals[look], s[look], sub_bounds, wide, spindle, tilt,
                                                        (dirs, need))
    return axes, ok, pieces, inside


def _widened(normals: np.ndarray, axes: np.ndarray, limit: np.ndarray, spindle: np.ndarray, tilt: float,
             stroke: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The contact caps ``limit`` (n,) rad and the stroke bounds (``stroke`` as in _piece_axes) for
    the points whose caps have no axis in common: a contact cap widened to the axis within the head's
    reach and the strokes nearest the point's ``axes`` (n, 3) (its axis without the strokes: the
    contact as near the normal as the machine allows); where the reach and the strokes leave no axis,
    the point's stroke caps left out (its path's axis chosen for the other points; it leaves a stroke)."""
    dirs, need = stroke
    bad = np.flatnonzero((axes @ dirs.T - need + STROKE_TOLERANCE < 0).any(axis=1))
    if bad.size == 0:
        return limit, need
    _, good = _piece_axes(normals[bad], axes[bad], np.arange(bad.size), limit[bad], spindle, tilt,
                          (dirs, need[bad]))
    bad = bad[~good]  # (a point its axis keeps within the strokes has them in common)
    if bad.size == 0:
        return limit, need
    free, fits = _piece_axes(normals[bad], axes[bad], np.arange(bad.size), np.full(bad.size, np.pi), spindle,
                             tilt, (dirs, need[bad]))
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", free, normals[bad]), -1.0, 1.0))
    wide, need = limit.copy(), need.copy()
    wide[bad[fits]] = np.maximum(limit[bad[fits]], angle[fits] + 4 * ANGLE_TOLERANCE)
    need[bad[~fits]] = -np.inf
    return wide, need


def single_sided_axes(centres: list[np.ndarray], normals: list[np.ndarray], spindle: np.ndarray,
                      max_tilt_deg: float, clearance: Clearance | None = None,
                      strokes: StrokeCaps | None = None) -> AxisChoice:
    """The executed axes of single-sided paths of ball centres (each (m, 3) mm) with the surface
    normals at their contacts ((m, 3) unit), for a head whose spindle axis is ``spindle`` (3,) and
    reaches ``max_tilt_deg``; ``clearance`` and ``strokes`` optional (module docstring)."""
    if not centres:
        return AxisChoice([], np.zeros(0, bool), np.zeros(0, bool), np.zeros(0, int), np.zeros(0, bool))
    spindle = np.asarray(spindle, float) / np.linalg.norm(spindle)
    tilt = np.radians(max_tilt_deg)
    n = np.concatenate(normals)
    c = np.concatenate(centres)
    sizes = np.array([len(p) for p in centres])
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    s = np.concatenate([cumulative_length(p) for p in centres])  # each path's own arc length
    # a point whose normal is beyond the head's reach and the contact limit together has its contact cap
    # widened until it meets the head's reach: its one axis is then its normal turned to the head's limit
    beyond = np.arccos(np.clip(n @ spindle, -1.0, 1.0)) - tilt + 4 * ANGLE_TOLERANCE
    limit = np.maximum(np.radians(CONTACT_LIMIT_DEG), beyond)
    every = np.arange(len(c))
    axes, ok, pieces, inside = _stroke_axes(n, s, bounds, limit, spindle, tilt, strokes, every)
    clear = np.ones(len(c), bool)
    if clearance is not None:
        owner = np.repeat(np.arange(len(centres)), sizes)
        for round_ in range(CLEARANCE_ROUNDS + 1):
            clear = np.asarray(clearance(c, axes), float) >= 0.0
            if clear.all() or round_ == CLEARANCE_ROUNDS:
                break
            # (never narrower than the point's normal is from the head's reach: each point keeps an axis)
            narrower = limit[~clear] - np.radians(CLEARANCE_STEP_DEG)
            limit[~clear] = np.maximum(narrower, np.maximum(beyond[~clear], 0.0))
            redo = np.unique(owner[~clear])  # only the paths with a collision are chosen again
            sel = np.concatenate([np.arange(bounds[k], bounds[k + 1]) for k in redo])
            sub_bounds = np.concatenate([[0], np.cumsum(sizes[redo])])
            axes[sel], ok[sel], pieces[redo], inside[sel] = _stroke_axes(n[sel], s[sel], sub_bounds, limit[sel],
                                                                         spindle, tilt, strokes, sel)
    ok = ((np.einsum("ij,ij->i", axes, n) >= np.cos(np.radians(CONTACT_LIMIT_DEG) + ANGLE_TOLERANCE))
          & (axes @ spindle >= np.cos(tilt + ANGLE_TOLERANCE)))
    return AxisChoice(np.split(axes, bounds[1:-1]), ok, clear, pieces, inside)
