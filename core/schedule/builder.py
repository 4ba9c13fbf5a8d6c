"""Timed moves of the two cutters, built path by path for core.schedule.steps: each cutter's growing move
list (``Cutter``), and ``MoveBuilder``'s primitives: cutting stretches from speed to speed that stop
at the contact path's tight corners, the moves in the air (core.schedule.air), symmetrical stretches of both
cutters through their sync maps (core.schedule.motion.sync_map), and speed stages (core.schedule.sigmoid). Units: mm,
ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.errors import PlanningError
from core.paths.contours import TURN_LIFT
from core.paths.plan import PathPlan
from core.paths.tessellation import TriangleIndex
from core.schedule.air import HOME_CLEARANCE, AirMoves
from core.schedule.motion import (
    SMOOTH_PEAK,
    SYNC_ACCEL_SHARE,
    MappedLaw,
    Move,
    MoveTag,
    RampLaw,
    WaitLaw,
    make_move,
    ramp_law,
    stop_distance,
    sync_map,
    sync_window,
    tight_corners,
)
from core.schedule.sigmoid import speed_stage
from core.util.polyline import cumulative_length

RAPID_FACTOR = 3.0       # rapid moves at 3 x the feed
#: mm a cutter backs off the blade to wait out a speed stage that would cut below the minimum feed
#: (MoveBuilder.lifted_stage)
STAGE_LIFT = 1.0


@dataclass
class Cutter:
    """The growing move list of one cutter; ``t`` is the end of its last move (ms)."""

    side: str
    tip: np.ndarray
    axis: np.ndarray
    moves: list[Move] = field(default_factory=list)
    t: float = 0.0

    def add(self, law, points, axes, tag: MoveTag, cum=None) -> None:
        self.moves.append(make_move(self.t, law, points, axes, tag, cum))
        self.t += law.duration
        self.tip = np.asarray(points, float)[-1]
        self.axis = np.asarray(axes, float)[-1]

    def wait_until(self, t: float, step: int, path: int, region: str = "idle") -> float:
        """Stand still until time t (ms); returns the wait in ms."""
        dt = t - self.t
        if dt > 1e-9:
            self.add(WaitLaw(dt), self.tip[None], self.axis[None], MoveTag(step, path, False, region))
        return max(dt, 0.0)


class MoveBuilder(AirMoves):
    """Both cutters' move lists under construction for one plan, feed and a_max (converted to mm/ms
    and mm/ms^2), with the plan's per-pair figures (cumulative lengths, tight corners, sync maps: ``memo``) and, for the
    collaborative mode's safety rounds, snapshots to resume from."""

    def __init__(self, plan: PathPlan, feed_mm_min: float, a_max_mm_s2: float, profile: str, memo: dict,
                 index: TriangleIndex | None = None):
        self.plan = plan
        #: the blade index the moves in the air keep clear of (AirMoves.blade_index; None: built there)
        self.index = index
        self.v = feed_mm_min / 60000.0
        self.a = a_max_mm_s2 / 1e6
        self.rapid = RAPID_FACTOR * self.v
        self.profile = profile
        #: mm/ms, the slowest a stage may cut (0: the paper's stages as they are): below it a stage is
        #: cut at speed and waited out off the blade (``lifted_stage``)
        self.min_feed = 0.0
        self.stages: list[dict] = []
        #: the per-pair figures of this plan (cumulative lengths, tight corners, sync maps and pieces),
        #: computed once and shared by the builds of the safety rounds (core.schedule.steps)
        self.memo = memo
        #: the state at the start of each collaborative path (by path index): a later round whose
        #: first changed margin is at that path resumes there instead of building everything again
        self.snapshots: dict[int, tuple] = {}
        self.resume: tuple | None = None
        self.margins: dict[int, int] = {}
        #: each pair's region codes per point, by path index (set by the build)
        self.regions: dict[int, np.ndarray] = {}
        tips = np.concatenate([np.vstack([p.left_tip, p.right_tip]) for p in plan.pairs])
        centre = 0.5 * (tips.min(axis=0) + tips.max(axis=0))
        self.tip_x = float(tips[:, 0].max())
        zmin, zmax = tips[:, 2].min(), tips[:, 2].max()
        self.home = {
            "left": (np.array([centre[0], centre[1], zmin - HOME_CLEARANCE]), np.array([0.0, 0.0, -1.0])),
            "right": (np.array([centre[0], centre[1], zmax + HOME_CLEARANCE]), np.array([0.0, 0.0, 1.0]))}
        self.cut = {s: Cutter(s, *self.home[s]) for s in ("left", "right")}
        #: path -> why its speed stage cannot keep a_max (the build then stands for no schedule)
        self.failed_stages: dict[int, str] = {}

    def snapshot(self, key: int, k: int, step: int, start: int, moving: bool) -> None:
        """Record the state before collaborative path ``key`` (the k-th): the move lists are only ever
        appended to, so their lengths mark it."""
        cuts = {s: (c.moves, len(c.moves), c.t, c.tip, c.axis) for s, c in self.cut.items()}
        self.snapshots[key] = (k, step, start, moving, self.stages, len(self.stages), cuts)

    def restore(self, snap: tuple) -> tuple[int, int, int, bool]:
        """Take the state of a snapshot (copies of the list prefixes); returns (k, step, start, moving)."""
        k, step, start, moving, stages, n_stages, cuts = snap
        self.stages = list(stages[:n_stages])
        for s, (moves, n, t, tip, axis) in cuts.items():
            c = self.cut[s]
            c.moves, c.t, c.tip, c.axis = list(moves[:n]), t, tip, axis
        return k, step, start, moving

    # -- primitives ------------------------------------------------------------------------------
    def stretch(self, side: str, pair, i: int, j: int):
        """Tips, axes and regions of a cutter's own path from pair index i to j (inclusive)."""
        tips = getattr(pair, f"{side}_tip")[i:j + 1]
        axes = getattr(pair, f"{side}_axis")[i:j + 1]
        return tips, axes, self.regions[pair.index][i:j + 1]

    def pair_memo(self, pair) -> dict:
        """The memo's figures of one pair, kept by its path index (ScheduleMemory.forget drops them)."""
        return self.memo.setdefault("pairs", {}).setdefault(pair.index, {})

    def cum(self, side: str, pair, i: int, j: int) -> np.ndarray:
        """(j - i + 1,) mm: cumulative lengths along a cutter's own path from pair index i to j (the
        whole path's, computed once per pair and side)."""
        memo = self.pair_memo(pair)
        if side not in memo:
            memo[side] = cumulative_length(getattr(pair, f"{side}_tip"))
        full = memo[side]
        return full[i:j + 1] - full[i]

    def length(self, side: str, pair, i: int, j: int) -> float:
        """mm along a cutter's own path from pair index i to j (0 unless j > i)."""
        return float(self.cum(side, pair, i, j)[-1]) if j > i else 0.0

    def cut_stretch(self, side, pair, i, j, v_a, v_b, step) -> None:
        if j <= i:
            return
        tips, axes, reg = self.stretch(side, pair, i, j)
        cum = self.cum(side, pair, i, j)
        law = ramp_law(float(cum[-1]), self.v, self.a, v_a, v_b)
        self.cut[side].add(law, tips, axes, MoveTag(step, pair.index, True, reg), cum)

    def corners(self, side: str, pair) -> np.ndarray:
        """Pair indices where a cutter stops on its own path (core.schedule.motion.tight_corners), computed
        once per pair and side."""
        memo, key = self.pair_memo(pair), ("corners", side)
        if key not in memo:
            memo[key] = tight_corners(getattr(pair, f"{side}_tip"))
        return memo[key]

    def cut_from_rest(self, side, pair, i, j, step) -> None:
        """Pair indices i..j from rest to rest, stopping at every tight corner on the way."""
        self.cut_with_stops(side, pair, i, j, 0.0, 0.0, step)

    def stops(self, side, pair, i: int, j: int, v_a: float, v_b: float) -> list[int]:
        """i, the tight corners strictly between i and j at which a cutter going from speed v_a at i
        to v_b at j stops, j. Corners closer to i than it takes to stop from v_a (or closer to j
        than it takes to reach v_b from rest) at a_max are passed at speed: a hand-over speed is
        the stage's, and refusing the plan there would be worse than the corner."""
        c = self.corners(side, pair)
        c = _stoppable(c[(c > i) & (c < j)], i, lambda: self.cum(side, pair, i, j), v_a, v_b, self.a)
        return [i, *(int(k) for k in c), j]

    def cut_with_stops(self, side, pair, i, j, v_a, v_b, step) -> None:
        """Pair indices i..j from speed v_a to v_b, stopping at the tight corners on the way (each
        piece its own move)."""
        stops = self.stops(side, pair, i, j, v_a, v_b)
        for a, b in zip(stops[:-1], stops[1:], strict=True):
            self.cut_stretch(side, pair, a, b, v_a if a == i else 0.0, v_b if b == j else 0.0, step)

    def single_path(self, side, pair, step, first: bool) -> None:
        """Machine one whole path single-sided, coming from the previous path (or from zero)."""
        tips, axes, _ = self.stretch(side, pair, 0, len(pair.u) - 1)
        self.travel(side, tips[0], axes[0], step, pair.index, "idle" if first else "turn",
                    lift=HOME_CLEARANCE if first else TURN_LIFT)
        self.cut_from_rest(side, pair, 0, len(pair.u) - 1, step)

    # -- symmetric phase -----------------------------------------------------------------------------
    def symmetric(self, pair, i, j, v_a, v_b, step) -> None:
        """Both cutters from pair index i to j together: a master law on the larger of the two steps,
        each cutter's own distance a function of the master's (core.schedule.motion.sync_map), so that they
        start and end the stretch at the same instants and keep within a fraction of the sync window
        of the same pair index in between. The master's ramps keep to (1 - SYNC_ACCEL_SHARE) a_max:
        the rest is the maps' share."""
        if j <= i:
            return
        for a, b, va, vb in self.sync_pieces(pair, i, j, v_a, v_b):  # rest to rest between tight corners
            master, maps = self.sync_maps(pair, a, b)
            law = ramp_law(float(master[-1]), self.v, self.a * (1.0 - SYNC_ACCEL_SHARE), va, vb)
            for side in ("left", "right"):
                tips, axes, reg = self.stretch(side, pair, a, b)
                own = self.cum(side, pair, a, b)
                self.cut[side].add(MappedLaw(law, maps[side]), tips, axes, MoveTag(step, pair.index, True, reg), own)

    def sync_pieces(self, pair, i: int, j: int, v_a: float,
                    v_b: float) -> list[tuple[int, int, float, float]]:
        """The pieces (a, b, master speed at a, at b) of a symmetrical stretch i..j entered at master
        speed v_a and left at v_b: split at the tight corners of either cutter's path (both stop
        there) except those closer to i than the master needs to stop from v_a, or closer to j than
        it needs to reach v_b from rest (passed at speed: the stages before and after are timed for
        these speeds; a stage can only slow down); a last piece from rest too short to reach v_b
        leaves at the highest speed it can reach (the stage after it starts from that)."""
        memo, key = self.pair_memo(pair), ("pieces", i, j, v_a, v_b)
        if key in memo:
            return memo[key]
        a_m = self.a * (1.0 - SYNC_ACCEL_SHARE)
        c = np.union1d(self.corners("left", pair), self.corners("right", pair))
        c = _stoppable(c[(c > i) & (c < j)], i, lambda: self.sync_maps(pair, i, j)[0], v_a, v_b, a_m)
        stops = [i, *(int(k) for k in c), j]
        pieces = []
        for a, b in zip(stops[:-1], stops[1:], strict=True):
            va, vb = (v_a if a == i else 0.0), (v_b if b == j else 0.0)
            if va == 0.0 and vb > 0.0:  # the speed reached over the piece: its ramp distance inverted
                length = float(self.sync_maps(pair, a, b)[0][-1])
                vb = min(vb, 0.999 * float(np.sqrt(2.0 * length * a_m / SMOOTH_PEAK)))
            pieces.append((a, b, va, vb))
        memo[key] = pieces
        return pieces

    def sync_maps(self, pair, i: int, j: int):
        """The master's cumulative distance over pair indices i..j (the larger of the two steps) and
        each cutter's sync_map, computed once per stretch."""
        memo, key = self.pair_memo(pair), ("sync", i, j)
        if key not in memo:
            cl, cr = self.cum("left", pair, i, j), self.cum("right", pair, i, j)
            master = np.concatenate([[0.0], np.cumsum(np.maximum(np.diff(cl), np.diff(cr)))])
            w = sync_window(self.v, self.a)
            memo[key] = (master, {"left": sync_map(master, cl, w), "right": sync_map(master, cr, w)})
        return memo[key]

    def own_speed(self, pair, k, side, lo: int, hi: int, v_a: float, v_b: float) -> float:
        """A cutter's speed at pair index k, mm/ms, as the symmetrical stretch lo..hi (entered at
        master speed v_a, left at v_b: the arguments of ``symmetric``) that k ends (k == hi) or starts
        (k == lo) gives it: the master's speed there times the slope of the cutter's sync_map. The
        stage or cutting move on the other side of k ends or starts at this speed, so the speed is
        continuous across the hand-over."""
        if hi <= lo:  # no stretch: the ratio of the nearest interval
            a, b = max(min(k, len(pair.u) - 1) - 1, 0), max(min(k, len(pair.u) - 1), 1)
            cl, cr = self.cum("left", pair, a, b), self.cum("right", pair, a, b)
            top = max(cl[-1], cr[-1])
            return self.v * float((cl if side == "left" else cr)[-1] / top) if top > 0 else 0.0
        pieces = self.sync_pieces(pair, lo, hi, v_a, v_b)  # the piece that ends or starts at k
        a, b, va, vb = pieces[-1] if k == hi else pieces[0]
        master, maps = self.sync_maps(pair, a, b)
        if master[-1] <= 0:
            return 0.0
        return (vb if k == hi else va) * float(maps[side].derivative()(master[-1] if k == hi else 0.0))

    def stage(self, side, pair, i, j, v0, duration, step, ahead: bool = False) -> dict:
        """A speed stage over a cutter's own stretch i..j lasting ``duration`` ms: the paper's
        (core.schedule.sigmoid.speed_stage), or, where that would cut below the minimum feed or break
        a_max, the stretch cut at speed with the time waited off the blade (``lifted_stage``: waiting
        ``ahead`` of the paper's stage or behind it)."""
        tips, axes, reg = self.stretch(side, pair, i, j)
        cum = self.cum(side, pair, i, j)
        length = float(cum[-1])
        if j <= i or length <= 0:
            self.cut[side].wait_until(self.cut[side].t + duration, step, pair.index, "variable")
            return {"kind": "wait", "length_mm": 0.0}
        try:
            st = speed_stage(length, v0, duration, self.a, self.profile)
        except PlanningError as exc:
            st, failed = None, exc
        if (st is None or st.v_low < self.min_feed) and self.min_feed > 0:
            rec = self.lifted_stage(side, pair, i, j, v0, duration, step, ahead)
            if rec is not None:
                return rec
        if st is None:
            # the build goes on at a constant speed over the stretch, to find every such path at once;
            # the schedule is then refused (PathScheduleError): the planner machines them single-sided
            self.failed_stages.setdefault(pair.index, f"path {pair.index}: {failed}")
            v = length / duration
            self.cut[side].add(RampLaw(length, v, v, v, 0.0, duration, 0.0), tips, axes,
                               MoveTag(step, pair.index, True, reg), cum)
            return {"kind": "refused", "length_mm": round(length, 6)}
        self.cut[side].add(st, tips, axes, MoveTag(step, pair.index, True, reg), cum)
        return {"kind": st.kind, "length_mm": round(length, 6), "duration_ms": round(duration, 3),
                "peak_accel_mm_s2": round(st.peak_accel * 1e6, 3),
                "peak_jerk_mm_s3": (round(st.peak_jerk * 1e9, 3) if np.isfinite(st.peak_jerk) else "inf")}

    def lifted_stage(self, side, pair, i, j, v0, duration, step, ahead: bool) -> dict | None:
        """The stage i..j (entered and left at v0, lasting ``duration`` ms) without cutting slowly: the
        cutter cuts at v0 to a point x, stops there, backs off STAGE_LIFT mm and waits, comes down
        onto x and cuts on, reaching v0 again by j exactly ``duration`` ms after it began. The paper's
        stage runs at v0 at most, so with x the first point after i the stop from v0 reaches (not
        ``ahead``) the tip is behind the stage's at every instant, and with x the last point before j
        from which the start to v0 fits (``ahead``) it is ahead of it: the other cutter, ahead of it
        (or behind it) on its way, keeps at least the stage's spacing. None where the stretch is too
        short for the stop and the start, or the duration for the moves."""
        cum = self.cum(side, pair, i, j)
        ramp = stop_distance(v0, self.a) * (1.0 + 1e-9)
        # the first point the stop from v0 reaches, or the last from which the start to v0 fits
        x = int(np.searchsorted(cum, cum[-1] - ramp, side="right")) - 1 if ahead else int(np.searchsorted(cum, ramp))
        if not 0 < x < len(cum) - 1 or cum[x] < ramp or cum[-1] - cum[x] < ramp:
            return None
        before = ramp_law(float(cum[x]), v0, self.a, v0, 0.0)
        after = ramp_law(float(cum[-1] - cum[x]), v0, self.a, 0.0, v0)
        air = ramp_law(STAGE_LIFT, self.rapid, self.a)
        wait = duration - before.duration - after.duration - 2.0 * air.duration
        if wait < 0.0:
            return None
        tips, axes, reg = self.stretch(side, pair, i, j)
        c = self.cut[side]
        end = c.t + duration
        c.add(before, tips[:x + 1], axes[:x + 1], MoveTag(step, pair.index, True, reg[:x + 1]), cum[:x + 1])
        seat, axis = c.tip.copy(), c.axis.copy()
        off = seat + STAGE_LIFT * self.backoff(seat, axis)
        c.add(air, [seat, off], [axis, axis], MoveTag(step, pair.index, False, "variable"))
        c.wait_until(end - after.duration - air.duration, step, pair.index, "variable")
        c.add(air, [off, seat], [axis, axis], MoveTag(step, pair.index, False, "variable"))
        c.add(after, tips[x:], axes[x:], MoveTag(step, pair.index, True, reg[x:]), cum[x:] - cum[x])
        return {"kind": "lifted", "length_mm": round(float(cum[-1]), 6), "duration_ms": round(duration, 3),
                "lifted_at_point": i + x, "wait_ms": round(wait, 3), "peak_accel_mm_s2": round(self.a * 1e6, 3),
                "peak_jerk_mm_s3": "inf"}


def _stoppable(corners: np.ndarray, i: int, cum, v_a: float, v_b: float, a: float) -> np.ndarray:
    """The corners (pair indices inside i..j) a cutter entering at speed v_a and leaving at v_b can
    stop at with acceleration a: those at least a ramp's distance from either end where the speed
    there is not zero (the others are passed at speed). ``cum()``: the cumulative distance over
    i..j (mm; called only when needed)."""
    if corners.size == 0 or (v_a <= 0 and v_b <= 0):
        return corners
    dist = cum()
    at = dist[corners - i]
    return corners[(at >= stop_distance(v_a, a)) & (dist[-1] - at >= stop_distance(v_b, a))]


def cut_duration(b: MoveBuilder, side, pair, i, j, v_a, v_b) -> float:
    """How long MoveBuilder.cut_with_stops takes over pair indices i..j."""
    if j <= i:
        return 0.0
    stops = b.stops(side, pair, i, j, v_a, v_b)
    return sum(ramp_law(b.length(side, pair, a, e), b.v, b.a, v_a if a == i else 0.0,
                        v_b if e == j else 0.0).duration for a, e in zip(stops[:-1], stops[1:], strict=True))


def turn(b: MoveBuilder, side, to_pair, step, wait: float = 0.0) -> None:
    """Turning path to the start of ``to_pair``; ``wait`` ms spent backed off before moving across."""
    tips, axes, _ = b.stretch(side, to_pair, 0, 0)
    c = b.cut[side]
    pts, axs = b.turn_path(side, c.tip, c.axis, tips[0], axes[0])
    for k in range(len(pts) - 1):
        length = float(np.linalg.norm(pts[k + 1] - pts[k]))
        if length > 1e-12:
            c.add(ramp_law(length, b.rapid, b.a), pts[k:k + 2], axs[k:k + 2],
                  MoveTag(step, to_pair.index, False, "turn"))
        if k == 0 and wait > 0:
            c.wait_until(c.t + wait, step, to_pair.index, "turn")


def turn_duration(b: MoveBuilder, side, from_pair, to_pair) -> float:
    ends = (getattr(from_pair, f"{side}_tip")[-1], getattr(from_pair, f"{side}_axis")[-1],
            getattr(to_pair, f"{side}_tip")[0], getattr(to_pair, f"{side}_axis")[0])
    pts, _ = b.turn_path(side, *ends)
    return sum(ramp_law(float(np.linalg.norm(pts[k + 1] - pts[k])), b.rapid, b.a).duration
               for k in range(len(pts) - 1) if np.linalg.norm(pts[k + 1] - pts[k]) > 1e-12)
