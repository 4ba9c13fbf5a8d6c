"""Sampling a schedule on its common time column and the figures plan.json reports about it."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from core.errors import Cancelled
from core.paths.interpolation import subdivision_points
from core.schedule.motion import Samples
from core.schedule.safety import capsule_clearance, tip_spacing, unsafe_samples
from core.schedule.steps import Schedule
from core.util.parallel import both, per_side, worth_threads
from core.util.rowwise import row_norm


@dataclass(frozen=True)
class Timeline:
    """t : (n,) ms; left, right : Samples on t."""

    t: np.ndarray
    left: Samples
    right: Samples


@dataclass(frozen=True)
class SafetyProfile:
    """The safety figures of a time column: tip spacing at the rows (n,) and its minimum between them
    (n-1,) (core.schedule.safety.tip_spacing), and the two tool capsules' clearance at the rows (n,),
    mm; ``unsafe`` (n,) bool marks the rows that break the safety rule (core.schedule.safety)."""

    at: np.ndarray
    between: np.ndarray
    clearance: np.ndarray
    unsafe: np.ndarray

    @classmethod
    def of(cls, tl: Timeline, tool_radius: float, stick_out: float, h_safe: float) -> SafetyProfile:
        """The figures of ``tl`` for a tool (mm), the spacing and the clearance in two threads."""
        (at, between), clear = both(
            lambda: tip_spacing(tl.left.tips, tl.right.tips),
            lambda: capsule_clearance(tl.left.tips, tl.left.axes, tl.right.tips, tl.right.axes, tool_radius,
                                      stick_out), parallel=worth_threads(len(tl.t)))
        return cls(at, between, clear, unsafe_samples(at, between, clear, h_safe))


#: how far a ball centre may stray from the straight line between two rows (mm)
ROW_TOLERANCE = 5e-4


@dataclass(frozen=True)
class Insertion:
    """Where the rows of a sorted column t (n,) and of sorted new times (m,) go when merged (new rows
    after equal old ones): old_at (n,) and new_at (m,) positions in the merged (n + m,) column."""

    old_at: np.ndarray
    new_at: np.ndarray

    @classmethod
    def of(cls, t: np.ndarray, new_t: np.ndarray) -> Insertion:
        return cls(np.arange(len(t)) + np.searchsorted(new_t, t, side="left"),
                   np.searchsorted(t, new_t, side="right") + np.arange(len(new_t)))

    @property
    def is_new(self) -> np.ndarray:
        """(n + m,) bool: the merged rows that are new."""
        flag = np.zeros(len(self.old_at) + len(self.new_at), bool)
        flag[self.new_at] = True
        return flag

    def merge(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Rows of a (old) and b (new) in merged order (an integer scatter: 2x a boolean one)."""
        out = np.empty((len(self.old_at) + len(self.new_at),) + a.shape[1:], a.dtype)
        out[self.old_at] = a
        out[self.new_at] = b
        return out

    def merge_samples(self, a: Samples, b: Samples) -> Samples:
        return Samples(*(self.merge(getattr(a, f.name), getattr(b, f.name)) for f in fields(Samples)))


#: new rows closer than this to another row are dropped (ms): differences over shorter intervals
#: only measure the rounding of the written numbers
MIN_ROW_GAP = 5e-3


def vertices_in(schedule: Schedule, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Both cutters' vertex instants inside the intervals (lo[k], hi[k]) (ms): where a cutter starts a
    move or passes a vertex of its polyline (core.schedule.movetable.MoveTable.vertex_times). Rows there keep
    every straight line between two consecutive rows on one segment of the path, so a row's chord
    speed is the true mean speed even where the path has sharp corners (edges), instead of dipping
    across a corner."""
    left, right = both(lambda: schedule.left_table.vertex_times(lo, hi),  # (two threads)
                       lambda: schedule.right_table.vertex_times(lo, hi),
                       parallel=worth_threads(len(lo)))
    return np.concatenate([left, right])


def _distance(col: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(m,) distance from each x to the nearest value of the sorted column ``col`` (inf if empty)."""
    if col.size == 0:
        return np.full(x.shape, np.inf)
    k = np.searchsorted(col, x)
    last = len(col) - 1
    return np.minimum(np.abs(col[np.clip(k, 0, last)] - x), np.abs(col[np.clip(k - 1, 0, last)] - x))


def _apart(cols: list[np.ndarray], new_t: np.ndarray, gap: float = MIN_ROW_GAP) -> np.ndarray:
    """The sorted new times that are at least ``gap`` from the rows of every sorted column of
    ``cols`` and from each other."""
    new_t = np.unique(new_t)
    if new_t.size == 0:
        return new_t
    d = np.full(new_t.shape, np.inf)
    for col in cols:
        d = np.minimum(d, _distance(col, new_t))
    new_t = new_t[d >= gap]
    if new_t.size < 2:
        return new_t
    keep = np.ones(new_t.size, bool)
    last = new_t[0]
    gaps = np.diff(new_t)
    if (gaps >= gap).all():
        return new_t
    for i in range(1, new_t.size):  # rare: thin out clusters closer than the gap
        if new_t[i] - last < gap:
            keep[i] = False
        else:
            last = new_t[i]
    return new_t[keep]


def new_rows(cols: list[np.ndarray], vertices: np.ndarray, others: np.ndarray) -> np.ndarray:
    """New row times among the rows of the sorted columns ``cols``: the vertex times first, then the
    other times apart from rows and vertices; all on the CL tables' 1e-6 ms grid, so that the
    positions written are those at the times written."""
    vertices, others = np.round(vertices, 6), np.round(others, 6)
    v = _apart(cols, vertices)
    o = _apart(cols + [v], others)
    return np.union1d(v, o)


class _Rows:
    """The time column while ``sample`` adds rows: the period rows (t, left, right: fixed) and the rows
    added so far, kept apart (sorted times, and each round's samples as they came) and merged into
    the column once at the end: each round then costs what its new rows cost, not a copy of the whole
    column. A row is named by an id: i for period row i, len(t) + k for the k-th added row in time
    order. Every row's time differs from every other's (new_rows keeps them MIN_ROW_GAP apart)."""

    def __init__(self, t: np.ndarray, left: Samples, right: Samples):
        self.t, self.left, self.right = t, left, right
        self.chunks: list[tuple[np.ndarray, Samples, Samples]] = []
        self.added = np.empty(0)                 # the added rows' times, sorted
        self.order = np.empty(0, np.int64)       # k-th added row (time order) -> its row in the chunks
        self._points: dict = {}                  # (side, field) -> tips / axes over the chunks

    def add(self, new_t: np.ndarray, lm: Samples, rm: Samples) -> None:
        self.chunks.append((new_t, lm, rm))
        times = np.concatenate([c[0] for c in self.chunks])
        self.order = np.argsort(times, kind="stable")
        self.added = times[self.order]
        for side, s in (("left", lm), ("right", rm)):
            for name in ("tips", "axes"):
                old = self._points.get((side, name))
                part = getattr(s, name)
                self._points[side, name] = part if old is None else np.concatenate([old, part])

    def ids(self, added_t: np.ndarray) -> np.ndarray:
        """The ids of added rows at times ``added_t``."""
        return len(self.t) + np.searchsorted(self.added, added_t)

    def time(self, ids: np.ndarray) -> np.ndarray:
        n = len(self.t)
        return np.where(ids < n, self.t[np.minimum(ids, n - 1)], self.added[np.clip(ids - n, 0, None)]
                        if self.added.size else 0.0)

    def neighbour(self, x: np.ndarray, after: bool) -> np.ndarray:
        """The id of the row just after (``after``) or just before each row time x; -1 where none."""
        n, m = len(self.t), len(self.added)
        if after:
            k, j = np.searchsorted(self.t, x, "right"), np.searchsorted(self.added, x, "right")
            tk = np.where(k < n, self.t[np.minimum(k, n - 1)], np.inf)
            tj = np.where(j < m, self.added[np.minimum(j, m - 1)], np.inf) if m else np.full(x.shape, np.inf)
            ids = np.where(tk <= tj, k, n + j)
            return np.where(np.isinf(np.minimum(tk, tj)), -1, ids)
        k, j = np.searchsorted(self.t, x, "left") - 1, np.searchsorted(self.added, x, "left") - 1
        tk = np.where(k >= 0, self.t[np.maximum(k, 0)], -np.inf)
        tj = np.where(j >= 0, self.added[np.maximum(j, 0)], -np.inf) if m else np.full(x.shape, -np.inf)
        ids = np.where(tk >= tj, k, n + j)
        return np.where(np.isinf(np.maximum(tk, tj)), -1, ids)

    def points(self, ids: np.ndarray, side: str, name: str) -> np.ndarray:
        """(m, 3) tips or axes of one cutter at the rows ``ids``."""
        n = len(self.t)
        out = np.empty((len(ids), 3))
        old = ids < n
        out[old] = getattr(getattr(self, side), name)[ids[old]]
        if not old.all():
            out[~old] = self._points[side, name][self.order[ids[~old] - n]]
        return out

    def merged(self) -> tuple[np.ndarray, Samples, Samples]:
        """The whole column in time order (the period rows unchanged where nothing was added)."""
        if not self.chunks:
            return self.t, self.left, self.right
        ins = Insertion.of(self.t, self.added)

        def added(k: int) -> Samples:
            parts = [c[k] for c in self.chunks]
            return Samples(*(np.concatenate([getattr(s, f.name) for s in parts])[self.order]
                             for f in fields(Samples)))

        chunk = {"left": 1, "right": 2}  # (each chunk holds times, left samples, right samples)
        sides = per_side(lambda side: ins.merge_samples(getattr(self, side), added(chunk[side])),
                         parallel=worth_threads(len(self.t)))  # (the two cutters in two threads)
        return ins.merge(self.t, self.added), sides["left"], sides["right"]


def _unique_ids(ids: np.ndarray, n: int) -> np.ndarray:
    """np.unique of row ids in [0, n) by marking them (no sort: the same sorted ids)."""
    seen = np.zeros(n, bool)
    seen[ids] = True
    return np.flatnonzero(seen)


def sample(schedule: Schedule, period: float, tool_radius: float | None = None,
           tol: float = ROW_TOLERANCE, rounds: int = 5, cancel=None,
           samples: tuple[Samples, Samples] | None = None) -> Timeline:
    """Both cutters on the common time column: every ``period`` ms, plus rows inserted wherever a
    controller moving in a straight line between two rows would take either ball centre (or tip) more
    than ``tol`` mm off the planned motion, i.e. where the tool turns quickly round an edge: first as
    many rows as a sagitta estimate from the rows asks for, then halving (``rounds`` times at most)
    wherever a midpoint check still finds a larger deviation. ``samples``: both cutters on the period
    rows when they were sampled already (core.schedule.steps.checked_schedule)."""
    t = schedule.times(period)
    left, right = samples if samples is not None else schedule.sample(t)
    r = tool_radius or 0.0

    def estimate(side: str) -> np.ndarray:
        """The sagitta estimate of one cutter's ball centres and tips over each interval."""
        s_ = left if side == "left" else right
        est = np.zeros(len(t) - 1)
        for pts in (s_.tips + r * s_.axes, s_.tips):
            d = np.diff(pts, axis=0)
            c = row_norm(d)
            u = d / np.where(c > 0, c, 1.0)[:, None]
            turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1.0, 1.0))
            theta = np.zeros(len(c))
            theta[:-1] = turn
            theta[1:] = np.maximum(theta[1:], turn)
            rot = np.arccos(np.clip(np.einsum("ij,ij->i", s_.axes[:-1], s_.axes[1:]), -1.0, 1.0))
            est = np.maximum(est, c * np.maximum(theta, rot) / 8.0)
        return est

    per = per_side(estimate, parallel=worth_threads(len(t)))
    est = np.maximum(per["left"], per["right"])
    pieces = np.where(est > 0.25 * tol, np.ceil(np.sqrt(est / (0.5 * tol))), 1).astype(int)
    pieces = np.minimum(pieces, 256)
    rows = _Rows(t, left, right)
    last = np.empty(0)  # the rows added by the last round
    if (pieces > 1).any():
        fast = np.nonzero(pieces > 1)[0]
        last = new_rows([t], vertices_in(schedule, t[fast], t[fast + 1]), subdivision_points(t, pieces))
        if last.size:
            rows.add(last, *schedule.sample(last))
    for _ in range(rounds):
        if cancel is not None and cancel():
            raise Cancelled()
        if last.size == 0:
            break
        # the intervals next to the last round's rows, named by the row they start at
        before, after = rows.neighbour(last, after=False), rows.neighbour(last, after=True)
        starts = _unique_ids(np.concatenate([before[before >= 0], rows.ids(last[after >= 0])]),
                             len(t) + len(rows.added))
        ends = rows.neighbour(rows.time(starts), after=True)
        ta, tb = rows.time(starts), rows.time(ends)
        tm = 0.5 * (ta + tb)
        lm, rm = schedule.sample(tm)
        dev = np.zeros(starts.size)
        for side, mid in (("left", lm), ("right", rm)):
            tip_a, tip_b = rows.points(starts, side, "tips"), rows.points(ends, side, "tips")
            ax_a, ax_b = rows.points(starts, side, "axes"), rows.points(ends, side, "axes")
            for pa, pb, pm in ((tip_a + r * ax_a, tip_b + r * ax_b, mid.tips + r * mid.axes),
                               (tip_a, tip_b, mid.tips)):
                dev = np.maximum(dev, row_norm(pm - 0.5 * (pa + pb)))
        bad = dev > tol
        if not bad.any():
            break
        last = new_rows([t, rows.added], vertices_in(schedule, ta[bad], tb[bad]), tm[bad])
        if last.size == 0:
            break
        rows.add(last, *schedule.sample(last))
    return Timeline(*rows.merged())


def period_rows(schedule: Schedule, period: float, samples: tuple[Samples, Samples] | None = None) -> Timeline:
    """Both cutters on the period rows alone (``schedule.times(period)``, no rows added round the
    edges); ``samples``: those rows sampled already (core.schedule.steps.checked_schedule)."""
    t = schedule.times(period)
    left, right = samples if samples is not None else schedule.sample(t)
    return Timeline(t, left, right)
