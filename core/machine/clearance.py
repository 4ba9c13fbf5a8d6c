"""Collision check of the whole tool assembly and the heads (core.machine.tool's parts).

What is checked, on every row of the two sides' tables and on the motion between two rows:
- each part of each side's assembly (flutes, neck, shank, holder stages, spindle nose, spindle housing,
  platform) against the blade, a triangle mesh (the gouge check's tessellation, or a mesh blade's facets);
- the heads' parts (spindle housing, platform) against the clamp fixture (``Clamp``);
- every part of one side against every part of the other.
A part is a cylinder about the tool axis; it is checked as the capsule round its axis segment (which
holds it: the figures are the capsule's clearance, as the shared check_assembly.py measures it).

How (a uniform grid of the blade's triangles and a compiled exact search, core.paths.meshgrid.MeshGrid,
the blade index's: ``TriangleIndex.grid``; a benchmark
against FCL is in tests/benchmarks/bench_clearance.py and docs/DECISIONS.md):
- a part's distance from the blade at one pose: a lower bound from the grid alone (the distance
  transform of its occupied cells), and where that comes within EXACT_MM of touching, the exact
  distance of the axis segment from the triangles near it;
- along the rows (``sweep``): between two poses a part's axis points move at most |dc| + s_max |dw|
  (the ball centre's move plus the farthest end's turn), so a clearance C at one row bounds the next
  rows' from below by C less the motion since. The rows are evaluated at a coarse stride first, and
  only the stretches where that bound comes within REFINE of touching are evaluated at finer strides,
  down to every row; the motion between two rows (what a row interval could hide) is bounded the same
  way, and an interval whose bound still allows a collision is evaluated at interpolated poses
  (centres linear, axes normalised), halving up to SUBDIVISIONS times.
Every clearance is therefore a lower bound of the capsule's, exact wherever it is below EXACT_MM (and
the sweep evaluates every row within REFINE of touching); a collision is a clearance below -TOLERANCE.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.machine.tool import Part
from core.paths.meshgrid import MeshGrid
from core.paths.tessellation import TriangleIndex
from core.schedule.safety import segment_distance

#: mm: a clearance below -TOLERANCE is a collision (the gouge check's tolerance)
TOLERANCE = 1e-3
#: mm: the sweep along the rows evaluates every row whose bound comes below this
REFINE = 0.05
#: mm: a part's clearance from the blade below this is measured exactly; above it, it is a lower bound
#: (a collision deeper than a part thicker than THIN_MM shows on the grid is not: ``part_blade``)
EXACT_MM = 2.0
THIN_MM = 4.0
#: mm: the most a part's axis points are spaced for the grid's bound (a quarter of its radius up to this)
MAX_STEP = 8.0
#: row strides of the sweep's levels, each half the last (a level evaluates the midpoints of the
#: intervals whose bound the last left open, down to every row)
STRIDES = (256, 128, 64, 32, 16, 8, 4, 2, 1)
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


def mesh_grid(index: TriangleIndex | MeshGrid) -> MeshGrid:
    """The compiled exact search of a blade's TriangleIndex (``TriangleIndex.grid``), or the MeshGrid
    given."""
    return index if isinstance(index, MeshGrid) else index.grid


def part_blade(part: Part, index, centres: np.ndarray, axes: np.ndarray, exact_below: float = EXACT_MM
               ) -> np.ndarray:
    """(n,) mm: the clearance of ``part``'s capsule from the mesh ``index`` (a TriangleIndex or its
    MeshGrid) at the poses (ball centres (n, 3) mm and unit axes (n, 3), W), where the grid's bounds
    do not settle it measured exactly:
    exact between -EXACT_MM and ``exact_below``; above, a lower bound (the grid's, or exact_below
    itself); below -EXACT_MM, where the grid's upper bound shows the part that deep in the blade, that
    upper bound (a collision at least that deep). A part thicker than THIN_MM (holder, spindle, head),
    whose exact distance takes the triangles within its whole radius, is measured only within REFINE
    of touching, and a collision of it only until it is certain: its depth is at least the value's
    (the grid's upper bound, or the search's first triangle deeper than 2 TOLERANCE)."""
    n = len(centres)
    if n == 0:
        return np.empty(0)
    grid = mesh_grid(index)
    r = part.radius
    thin = r <= THIN_MM
    band, deep_below = (exact_below, -EXACT_MM) if thin else (min(exact_below, REFINE), -TOLERANCE)
    p0, p1 = centres + part.s0 * axes, centres + part.s1 * axes
    step = max(grid.h, min(0.25 * r, MAX_STEP))
    out = grid.bound(p0, p1, step) - r
    near = np.flatnonzero(out < band)
    if near.size:
        upper = grid.bound(p0[near], p1[near], step, upper=True) - r
        deep = upper < deep_below
        out[near[deep]] = upper[deep]
        near = near[~deep]
        got = grid.distance(p0[near], p1[near], r + band, out[near] + r + 2.0 * grid.h,
                            enough=-1.0 if thin else r - 2.0 * TOLERANCE) - r
        out[near] = np.maximum(got, out[near])
    return out


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


def row_steps(centres: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n - 1,) mm and (n - 1,): how far the ball centre moves and the unit axis turns (its chord)
    between rows; an axis point s from the centre moves at most the first plus |s| times the second."""
    return np.linalg.norm(np.diff(centres, axis=0), axis=1), np.linalg.norm(np.diff(axes, axis=0), axis=1)


def motion(centres: np.ndarray, axes: np.ndarray, s_max: float) -> np.ndarray:
    """(n - 1,) mm: the most any axis point at most s_max from the ball centre moves between rows."""
    move, turn = row_steps(centres, axes)
    return move + s_max * turn


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
        at = np.searchsorted(rows, new)
        rows, vals = np.insert(rows, at, new), np.insert(vals, at, new_vals)
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
    hidden: list[tuple[int, float, float]] = []
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
    index = mesh_grid(index)
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
            v, _ = sweep(lambda rows, frac, part=part: part_blade(part, index, c[rows], w[rows]),
                         moves, len(todo), refine=0.0, closest=False)
            np.minimum(got, v, out=got)
        out[todo] = got
        last.update(centres=centres.copy(), axes=axes.copy(), values=out.copy())
        return out

    return least
