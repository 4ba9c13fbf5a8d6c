"""Collision check of the whole tool assembly and the heads (core.machine.tool's parts).

What is checked, on every row of the two sides' tables and on the motion between two rows:
- each part of each side's assembly (flutes, neck, shank, holder stages, spindle nose, spindle housing,
  platform) against the blade, a triangle mesh (the gouge check's tessellation, or a mesh blade's facets);
- the heads' parts (spindle housing, platform) against the clamp fixture (``Clamp``);
- every part of one side against every part of the other.
A part is a cylinder about the tool axis; it is checked as the capsule round its axis segment (which
holds it: the figures are the capsule's clearance, as the shared check_assembly.py measures it).

How (the project's own triangle index, core.paths.gouge.TriangleIndex: a benchmark against FCL and
coal is in tests/benchmarks/bench_clearance.py and docs/DECISIONS.md):
- a part's distance from the blade at one pose: exact point-to-mesh distances at samples along its axis
  segment; a mesh point at least D from two samples h apart is at least sqrt(D^2 - h^2/4) from the
  segment between them (``piece_bound``: the exact least distance for two different D), so the samples
  give a lower bound, and the pieces whose bound comes within REFINE of the part's radius are halved
  until the bound is within PRECISION of the distance;
- along the rows (``sweep``): between two poses a part's axis points move at most |dc| + s_max |dw|
  (the ball centre's move plus the farthest end's turn), so a clearance C at one row bounds the next
  rows' from below by C less the motion since. The rows are evaluated at a coarse stride first, and
  only the stretches where that bound comes within REFINE of touching are evaluated at finer strides,
  down to every row; the motion between two rows (what a row interval could hide) is bounded the same
  way, and an interval whose bound still allows a collision is evaluated at interpolated poses
  (centres linear, axes normalised), halving up to SUBDIVISIONS times.
Every clearance is therefore a lower bound of the capsule's, exact (to micrometres) wherever it is
below REFINE; a collision is a clearance below -TOLERANCE.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from core.machine.tool import Part
from core.paths.tessellation import TriangleIndex
from core.schedule.safety import segment_distance

#: mm: a clearance below -TOLERANCE is a collision (the gouge check's tolerance)
TOLERANCE = 1e-3
#: mm: clearances below this are evaluated exactly (to micrometres); above it they are lower bounds
REFINE = 0.05
#: mm: a piece of a part's axis is halved until its bound is within PRECISION of the distance (about
#: h^2 / (8 D) for a piece h long D from the blade), or it is MIN_STEP long
PRECISION = 5e-4
MIN_STEP = 0.01
#: mm: the coarsest spacing (the part's radius up to this)
MAX_STEP = 8.0
#: row strides of the sweep's levels (the last is every row)
STRIDES = (256, 32, 4, 1)
#: halvings of a row interval whose motion could hide a collision
SUBDIVISIONS = 6
#: mm added to the motion bound of a row interval: how far the machines' motion between two rows may
#: stray from the straight line between them (the planner's chord tolerance, core.records)
CHORD_SLACK = 1e-3


@dataclass(frozen=True)
class Clamp:
    """The clamp fixture that grips the blade's root: the block inboard of the clamp plane
    (X_W <= x_clamp), as long along Y_W as the root (y_min..y_max) and half_width either side of
    Z_W = 0 (mm)."""

    x_clamp: float
    half_width: float
    y_min: float = -np.inf
    y_max: float = np.inf

    def distance(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points, mm, W -> (n,) distance from the block (0 inside), mm."""
        dx = np.maximum(points[:, 0] - self.x_clamp, 0.0)
        dy = np.maximum(np.maximum(self.y_min - points[:, 1], points[:, 1] - self.y_max), 0.0)
        dz = np.maximum(np.abs(points[:, 2]) - self.half_width, 0.0)
        return np.sqrt(dx * dx + dy * dy + dz * dz)


def clamp_of(index: TriangleIndex, x_clamp: float, half_width: float) -> Clamp:
    """The clamp of a blade's mesh: as long along Y_W as the mesh's corners inboard of the clamp plane
    X_W = x_clamp (the root it grips; the whole blade's Y_W extent where none lie inboard)."""
    corners = np.concatenate([index.a, index.a + index.ab, index.a + index.ac], axis=1)
    root = corners[1, corners[0] <= x_clamp]
    y = root if root.size else corners[1]
    return Clamp(float(x_clamp), float(half_width), float(y.min()), float(y.max()))


def _axis_samples(part: Part, step: float) -> np.ndarray:
    n = max(int(np.ceil((part.s1 - part.s0) / step)), 1)
    return np.linspace(part.s0, part.s1, n + 1)


def piece_bound(da: np.ndarray, db: np.ndarray, h) -> np.ndarray:
    """The least distance from a segment of length h of any point at least da from its one end and
    db from the other (elementwise, mm): where its foot on the segment lies x from the first end, the
    distance is at least sqrt(da^2 - x^2) and sqrt(db^2 - (h - x)^2), the larger of the two least
    where they meet (x clipped to the segment); a point whose foot lies beyond an end is at least
    min(da, db) away."""
    h = np.asarray(h, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = np.clip((da * da - db * db + h * h) / np.where(h > 0, 2.0 * h, 1.0), 0.0, h)
    inner = np.sqrt(np.maximum(np.maximum(da * da - x * x, db * db - (h - x) ** 2), 0.0))
    return np.minimum(np.minimum(da, db), inner)  # (a point whose foot is an end: that end's distance)


#: mm: a part whose far end lies within this of the ball centre (the flutes of a small ball) is measured
#: exactly, without the coarse clouds: it lies next to the blade wherever the ball cuts
NEAR_MM = 5.0

#: mm: axis points whose nearest mesh corner lies more than this inside the part keep the corners' bound
#: (within their cover, 0.53 mm on the sample), not measured exactly: the part collides there either way,
#: its depth found to that cover
DEEP_MM = 1.0

#: mm: a point goes on to the finer clouds until its bound clears what settles it by this much
SETTLE = 1.0

#: cell sizes (mm) of the blade's coarse point clouds (``BladeDistance``), coarsest first; 0: the mesh's
#: corners themselves (their cover is a third of the finest cloud's on the sample's check tessellation,
#: 0.53 mm: the neck, 1.5 to 3 mm off the blade, is then bounded closely enough for the sweep to skip rows)
CELLS = (16.0, 4.0, 1.0, 0.0)


class BladeDistance:
    """Distances from points to a triangle mesh, cheap where the points are far: the mesh's corners
    thinned to one per cubic cell of each size in CELLS, each cloud with its cover radius (every point
    of the mesh lies within it of a point of the cloud: the farthest corner from its cell's
    representative plus the farthest any point of a triangle lies from its nearest corner, at most the
    longest edge over sqrt 3), give lower bounds (distance to the cloud less the cover); the exact
    distance (the TriangleIndex's) is computed only where those bounds do not settle a question. A
    nearest-neighbour search from far off a dense mesh visits many of its triangles (1.2 ms a point
    40 mm off the sample blade's check tessellation): the clouds answer those in microseconds."""

    def __init__(self, index: TriangleIndex):
        self.index = index
        corners = np.concatenate([index.a, index.a + index.ab, index.a + index.ac], axis=1).T
        edge = np.sqrt(max(index.e00.max(), index.e11.max(),
                           (index.e00 + index.e11 - 2 * index.e01).max()))
        self.levels = []
        for cell in CELLS:
            if cell == 0.0:  # the corners themselves (each once): cover edge / sqrt 3
                self.levels.append((cKDTree(np.unique(corners, axis=0)), edge / np.sqrt(3.0)))
                continue
            key = np.floor(corners / cell).astype(np.int64)
            key -= key.min(axis=0)
            flat = (key[:, 0] * (key[:, 1].max() + 1) + key[:, 1]) * (key[:, 2].max() + 1) + key[:, 2]
            _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
            rep = corners[first]
            cover = float(np.sqrt(((corners - rep[inverse]) ** 2).sum(axis=1).max())) + edge / np.sqrt(3.0)
            self.levels.append((cKDTree(rep), cover))

    def lower(self, points: np.ndarray, enough: float, clouds: bool = True, radius: float = 0.0
              ) -> tuple[np.ndarray, np.ndarray]:
        """(lower bounds (n,) mm of the points' distances from the mesh, exact (n,) bool): each point
        taken through the clouds (``clouds``: points known to lie near the mesh skip them) until a bound
        reaches ``enough`` + SETTLE; one whose finest bound stays below ``enough`` is measured
        (``measure``, for a part of ``radius``)."""
        n = len(points)
        out = np.zeros(n)
        todo = np.arange(n)
        for tree, cover in self.levels if clouds else ():
            if not todo.size:
                break
            d, _ = tree.query(points[todo], k=1)
            out[todo] = np.maximum(d - cover, 0.0)
            # (down to the finer clouds until the bound clears ``enough`` by SETTLE: a close bound lets
            # the sweep along the rows skip more of them)
            todo = todo[out[todo] < enough + SETTLE]
        todo = todo[out[todo] < enough]
        exact = np.zeros(n, bool)
        if todo.size:
            out[todo], exact[todo] = self.measure(points[todo], radius)
        return out, exact

    def measure(self, points: np.ndarray, radius: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(distances (n,) mm, exact (n,) bool) of axis points of a part of ``radius`` (mm): exact (the
        TriangleIndex's), but for points the mesh's corners put more than DEEP_MM inside the part (a
        nearest corner nearer than radius - DEEP_MM: the exact search is slow far off a dense mesh,
        and the part collides there either way), which keep the corners' bound and are not exact."""
        tree, cover = self.levels[-1]
        d, _ = tree.query(points, k=1)
        out = np.maximum(d - cover, 0.0)
        exact = d >= radius - DEEP_MM
        if exact.any():
            out[exact] = self.index.closest(points[exact])[0]
        return out, exact


_DISTANCES: dict[int, tuple[TriangleIndex, BladeDistance]] = {}


def blade_distance(index: TriangleIndex | BladeDistance) -> BladeDistance:
    """The BladeDistance of a TriangleIndex (built once per index and kept while it lives)."""
    if isinstance(index, BladeDistance):
        return index
    kept = _DISTANCES.get(id(index))
    if kept is None or kept[0] is not index:
        for key in [k for k, (i, _) in _DISTANCES.items() if i is not index]:
            del _DISTANCES[key]  # (one blade at a time: the last one asked for)
        kept = _DISTANCES[id(index)] = (index, BladeDistance(index))
    return kept[1]


def part_blade(part: Part, index, centres: np.ndarray, axes: np.ndarray,
               refine: float = REFINE, precision: float = PRECISION) -> np.ndarray:
    """(n,) mm: the clearance of ``part``'s capsule from the mesh ``index`` (a TriangleIndex or its
    BladeDistance) at the poses (ball centres (n, 3) mm and unit axes (n, 3), W): a lower bound,
    within ``precision`` where below ``refine``."""
    n = len(centres)
    if n == 0:
        return np.empty(0)
    dist = blade_distance(index)
    index = dist.index
    r = part.radius
    s = _axis_samples(part, min(max(r, 0.25), MAX_STEP))
    h = s[1] - s[0] if len(s) > 1 else 0.0
    # the samples' distances: bounds from the coarse clouds first (a piece whose two ends' bounds
    # leave it clear by refine is settled by them; piece_bound grows with both)
    enough = r + refine
    near = part.s1 <= NEAR_MM  # (a part next to the ball lies next to the blade wherever it cuts)
    d, exact = dist.lower((centres[:, None, :] + s[None, :, None] * axes[:, None, :]).reshape(-1, 3), enough,
                          clouds=not near, radius=r)
    d, exact = d.reshape(n, len(s)), exact.reshape(n, len(s))
    if len(s) == 1:
        return d[:, 0] - r
    bound = piece_bound(d[:, :-1], d[:, 1:], h) - r               # per piece (n, m)
    # a piece near the blade whose ends are bounds only: its ends measured
    rough = (bound < refine) & ~(exact[:, :-1] & exact[:, 1:])
    if rough.any():
        ends = np.zeros_like(exact)
        ends[:, :-1] |= rough
        ends[:, 1:] |= rough
        ends &= ~exact
        i, j = np.nonzero(ends)
        d[i, j], exact[i, j] = dist.measure(centres[i] + s[j][:, None] * axes[i], r)
        bound = piece_bound(d[:, :-1], d[:, 1:], h) - r
    # the least clearance measured at a sample of each pose: a piece whose bound is within precision of
    # it cannot lower the pose's least clearance by more (branch and bound)
    upper = np.where(exact, d, np.inf).min(axis=1) - r
    rows, pieces = np.nonzero((bound < refine) & (bound < upper[:, None] - precision))
    # pieces near the blade: halved until PRECISION (their ends' distances known, the midpoints measured)
    a_s, b_s = s[pieces], s[pieces + 1]
    a_d, b_d = d[rows, pieces], d[rows, pieces + 1]
    best = bound.min(axis=1)
    near = np.unique(rows)
    best[near] = np.minimum(upper[near], np.where(bound[near] < refine, np.inf, bound[near]).min(axis=1))
    while len(rows):
        mid = 0.5 * (a_s + b_s)
        m_d, m_exact = dist.measure(centres[rows] + mid[:, None] * axes[rows], r)
        np.minimum.at(upper, rows, np.where(m_exact, m_d - r, np.inf))
        half = 0.5 * (b_s - a_s)
        bnd_a = piece_bound(a_d, m_d, half) - r
        bnd_b = piece_bound(m_d, b_d, half) - r
        final = (half <= MIN_STEP) | (half * half <= 8.0 * precision * np.maximum(np.minimum(a_d, b_d), 1e-9))
        useful = np.minimum(refine, upper[rows] - precision)
        again_a, again_b = (bnd_a < useful) & ~final, (bnd_b < useful) & ~final
        done_a = np.where(again_a, np.inf, bnd_a)
        done_b = np.where(again_b, np.inf, bnd_b)
        np.minimum.at(best, rows, np.minimum(done_a, done_b))
        rows = np.concatenate([rows[again_a], rows[again_b]])
        a_s, b_s = np.concatenate([a_s[again_a], mid[again_b]]), np.concatenate([mid[again_a], b_s[again_b]])
        a_d, b_d = np.concatenate([a_d[again_a], m_d[again_b]]), np.concatenate([m_d[again_a], b_d[again_b]])
    return best


def part_clamp(part: Part, clamp: Clamp, centres: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(n,) mm: the clearance of ``part``'s capsule from the clamp block. The block's distance is convex
    along the axis segment: its minimum by golden-section search (to 1e-6 of the part's length)."""
    lo, hi = np.full(len(centres), part.s0), np.full(len(centres), part.s1)
    g = 0.5 * (np.sqrt(5.0) - 1.0)

    def f(s):
        return clamp.distance(centres + s[:, None] * axes)

    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(int(np.ceil(np.log(1e-6) / np.log(g)))):
        left = f1 <= f2
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        x2n = np.where(left, x1, lo + g * (hi - lo))
        x1n = np.where(left, hi - g * (hi - lo), x2)
        new = np.where(left, x1n, x2n)
        fn = f(new)
        f1, f2 = np.where(left, fn, f2), np.where(left, f1, fn)
        x1, x2 = x1n, x2n
    ends = np.minimum(f(np.full(len(centres), part.s0)), f(np.full(len(centres), part.s1)))
    return np.minimum(np.minimum(f1, f2), ends) - part.radius


def part_pair(a: Part, b: Part, centres_a: np.ndarray, axes_a: np.ndarray, centres_b: np.ndarray,
              axes_b: np.ndarray) -> np.ndarray:
    """(n,) mm: the clearance between capsules of part ``a`` (first poses) and part ``b`` (second)."""
    return segment_distance(centres_a + a.s0 * axes_a, centres_a + a.s1 * axes_a,
                            centres_b + b.s0 * axes_b, centres_b + b.s1 * axes_b) - a.radius - b.radius


def clearance(parts, index: TriangleIndex, centres: np.ndarray, axes: np.ndarray) -> dict[str, np.ndarray]:
    """Each part's clearance from the blade at each pose, independently: {part name: (n,) mm}, a lower
    bound, exact to micrometres below REFINE (``part_blade``). ``parts``: core.machine.tool.Part's
    (core.machine.tool.assembly, or Tool.parts for the tool alone); ``index`` the blade's mesh;
    ``centres`` (n, 3) mm ball centres and ``axes`` (n, 3) unit tool axes (tip -> spindle), W."""
    centres, axes = np.asarray(centres, float), np.asarray(axes, float)
    return {p.name: part_blade(p, index, centres, axes) for p in parts}


# -- along the rows --------------------------------------------------------------------------------

def interpolated(centres: np.ndarray, axes: np.ndarray, rows: np.ndarray, frac: np.ndarray):
    """Poses between rows and rows + 1 at fractions frac: centres linear, axes normalised."""
    j = np.minimum(rows + 1, len(centres) - 1)
    c = centres[rows] + frac[:, None] * (centres[j] - centres[rows])
    w = axes[rows] + frac[:, None] * (axes[j] - axes[rows])
    return c, w / np.linalg.norm(w, axis=1, keepdims=True)


def motion(centres: np.ndarray, axes: np.ndarray, s_max: float) -> np.ndarray:
    """(n - 1,) mm: the most any axis point at most s_max from the ball centre moves between rows."""
    return (np.linalg.norm(np.diff(centres, axis=0), axis=1)
            + s_max * np.linalg.norm(np.diff(axes, axis=0), axis=1))


def _inside(a: np.ndarray, b: np.ndarray, stride: int) -> np.ndarray:
    """The rows a + stride, a + 2 stride, ... below b of each interval (a, b) (every row where the
    interval is no longer than the stride), concatenated."""
    step = np.where(b - a > stride, stride, 1)
    count = (b - a - 1) // step
    keep = count > 0
    a, step, count = a[keep], step[keep], count[keep]
    first = np.repeat(np.cumsum(count) - count, count)
    k = np.arange(int(count.sum())) - first + 1
    return np.repeat(a, count) + k * np.repeat(step, count)


def sweep(evaluate, moves: np.ndarray, n: int, refine: float = REFINE, tolerance: float = TOLERANCE,
          closest: bool = True):
    """A clearance along n rows from few evaluations (module docstring).

    evaluate(rows, frac) -> (len(rows),) mm: the clearance at the poses frac (0 <= frac < 1) of the way
    from each row to the next; moves (n - 1,) mm: how far the geometry can move between two rows.
    Rows are evaluated where the bound comes below ``refine``, and with ``closest`` below the least
    clearance evaluated, so that the row of the least value is an evaluated one (the closest approach,
    ``_item``); without it, the moves between rows are not looked into (poses, not a motion).
    Returns (value (n,) mm: a lower bound at every row, exact where below ``refine``; hidden: list of
    (row, frac, clearance) of poses between two rows found colliding deeper than ``tolerance``)."""
    if n == 0:
        return np.empty(0), []
    cum = np.concatenate([[0.0], np.cumsum(moves)])
    rows = np.unique(np.append(np.arange(0, n, STRIDES[0]), n - 1))
    vals = evaluate(rows, np.zeros(len(rows)))
    for stride in STRIDES[1:]:
        a, b = rows[:-1], rows[1:]
        bound = 0.5 * (vals[:-1] + vals[1:] - (cum[b] - cum[a]))
        # (below the least evaluated clearance too: the closest approach is then an evaluated row)
        bad = np.flatnonzero((bound < (max(refine, vals.min()) if closest else refine)) & (b - a > 1))
        if not bad.size:
            break
        new = _inside(a[bad], b[bad], stride)
        if not new.size:
            continue
        new_vals = evaluate(new, np.zeros(len(new)))
        rows = np.concatenate([rows, new])
        vals = np.concatenate([vals, new_vals])
        order = np.argsort(rows, kind="stable")
        rows, vals = rows[order], vals[order]
    out = np.empty(n)
    out[rows] = vals
    # rows between two evaluated ones: bounded from both
    k = np.searchsorted(rows, np.arange(n), side="right") - 1
    k_next = np.minimum(k + 1, len(rows) - 1)
    at = np.arange(n)
    bound = np.maximum(vals[k] - (cum[at] - cum[rows[k]]), vals[k_next] - (cum[rows[k_next]] - cum[at]))
    skipped = np.ones(n, bool)
    skipped[rows] = False
    out[skipped] = bound[skipped]
    # the motion between two evaluated rows that are neighbours
    hidden = []
    if not closest:
        return out, hidden
    a = rows[:-1][np.diff(rows) == 1]
    lo_f, hi_f = np.zeros(len(a)), np.ones(len(a))
    v_lo, v_hi = out[a], out[np.minimum(a + 1, n - 1)]
    span = cum[a + 1] - cum[a] + CHORD_SLACK
    for _ in range(SUBDIVISIONS + 1):
        check = (v_lo >= -tolerance) & (v_hi >= -tolerance) & (0.5 * (v_lo + v_hi - span) < -tolerance)
        if not check.any():
            break
        a, lo_f, hi_f, v_lo, v_hi, span = (x[check] for x in (a, lo_f, hi_f, v_lo, v_hi, span))
        mid = 0.5 * (lo_f + hi_f)
        v_mid = evaluate(a, mid)
        hit = v_mid < -tolerance
        hidden += [(int(r), float(f), float(v)) for r, f, v in zip(a[hit], mid[hit], v_mid[hit], strict=True)]
        keep = ~hit
        a, lo_f, hi_f, v_lo, v_hi, span, mid, v_mid = (x[keep] for x in (a, lo_f, hi_f, v_lo, v_hi, span, mid, v_mid))
        a = np.concatenate([a, a])
        lo_f, hi_f = np.concatenate([lo_f, mid]), np.concatenate([mid, hi_f])
        v_lo, v_hi = np.concatenate([v_lo, v_mid]), np.concatenate([v_mid, v_hi])
        span = np.concatenate([span, span]) * 0.5
    else:  # halved SUBDIVISIONS times and still unresolved: counted at their own bound
        check = (v_lo >= -tolerance) & (v_hi >= -tolerance) & (0.5 * (v_lo + v_hi - span) < -tolerance)
        hidden += [(int(r), float(f), float(0.5 * (x + y - s)))
                   for r, f, x, y, s in zip(a[check], lo_f[check], v_lo[check], v_hi[check], span[check], strict=True)]
    return out, hidden


def least_clearance(parts, index):
    """A callable (centres (m, 3), axes (m, 3)) -> (m,) mm: the least clearance of any of ``parts``
    from the blade at each pose, exact where negative (a collision), a lower bound at or above 0: the
    form a tool-axis strategy takes to turn its axes clear (core.machine.tool_axes). The poses are
    taken as the points of paths one after another (a strategy's ball centres): each part is swept
    along them (``sweep``, without the closest approach), and a call with the same centres as the last
    measures only the poses whose axis changed."""
    index = blade_distance(index)
    last: dict = {}

    def least(centres: np.ndarray, axes: np.ndarray) -> np.ndarray:
        centres, axes = np.asarray(centres, float), np.asarray(axes, float)
        n = len(centres)
        out = np.full(n, np.inf)
        todo = np.arange(n)
        if last and last["centres"].shape == centres.shape and np.array_equal(last["centres"], centres):
            todo = np.flatnonzero(np.any(last["axes"] != axes, axis=1))
            out = last["values"].copy()
            out[todo] = np.inf
        c, w = centres[todo], axes[todo]
        got = np.full(len(todo), np.inf)
        for part in parts:
            moves = motion(c, w, max(abs(part.s0), abs(part.s1)))
            v, _ = sweep(lambda rows, frac, part=part: part_blade(part, index, c[rows], w[rows], refine=0.0),
                         moves, len(todo), refine=0.0, closest=False)
            np.minimum(got, v, out=got)
        out[todo] = got
        last.update(centres=centres.copy(), axes=axes.copy(), values=out.copy())
        return out

    return least
