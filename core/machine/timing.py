"""The machine clock: the job as the two machines run it, every row on the controller's fixed period.

The schedule (core.schedule.steps) times the tool tips: the feed, a_max and the paper's speed stages.
Round the blade's edges the heads swing and the path turns sharply, and the machines must go slower
than that: no axis may pass its speed or acceleration limit, and the straight line the controller
moves along between two rows must stay within the chord tolerance of the planned path. The machine
clock runs the schedule's own time tau at a rate s = d tau / dt <= 1, shared by both machines, so every
instant of the collaborative schedule (its synchronisation points, every tip spacing and clearance)
is kept while the job slows where either machine needs it.

The rate is planned as CNC look-ahead does, forward and backward over the job: the largest s under
each instant's cap (core.machine.caps: the tip speed each cutter's polyline allows where it is,
divided by the schedule's speed there), whose changes keep within the share of the axis and tip
accelerations left to them (``_cone``). The caps are found on a grid of schedule instants, refined
where the job slows so that no grid interval spans much more than a period of the machine's time. The
rows are then the instants t = k * period of the machine's clock, every one of them (one column for
both machines); the axis tables and the chord deviations are checked on those rows as written, and
where an estimate fell short the rate is lowered there and the rows are made again.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.errors import Cancelled
from core.machine.caps import (
    AIM,
    AIR_CHORD_TOL,
    CHORD_AIM,
    SCALE_SHARE,
    SegmentCaps,
    axis_limits,
    segment_caps,
)
from core.machine.model import Machine
from core.machine.tables import SLOWED_BELOW, SLOWED_FOR, AxisTable, TimeWarp, axis_excess, axis_motion
from core.schedule.motion import Samples
from core.schedule.movetable import MAPPED, RAMP
from core.schedule.steps import Schedule
from core.schedule.timeline import Timeline
from core.util.parallel import SIDES, per_side, worth_threads
from core.util.polyline import ball_centres, interval_turns, sagitta
from core.util.rowwise import row_norm

#: the tips' acceleration along the path is aimed this far inside a_max
TIP_AIM = 0.97
#: grid intervals longer than this many periods of machine time are split, into at most SPLIT_AT_MOST
#: pieces a round
REFINE_ABOVE = 1.5
SPLIT_AT_MOST = 16
#: rounds of grid refinement, and of checking the rows as written
REFINE_ROUNDS = 8
CHECK_ROUNDS = 12
#: row intervals whose estimated chord deviation is above this share of the tolerance are measured
MEASURE_SHARE = 0.1


@dataclass(frozen=True)
class MachineTiming:
    """The job on the machine clock: the time column (t = k * period, both cutters), the warp from it to
    the schedule's time, both axis tables on it, and the chord figures plan.json reports."""

    timeline: Timeline
    warp: TimeWarp
    tables: dict
    chord: dict


def _cone(cap: np.ndarray, tau: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """The largest s <= cap (n,) at increasing tau whose square changes by at most ``rate[i]`` per ms over
    interval i (|d s^2 / dtau| <= rate), clipped to [1e-12, 1]: a forward and a backward pass."""
    # the integral of the rate; a step of s^2 above 1 is no bound (s^2 is in [0, 1]): clipped there,
    # so that the integral keeps the digits of s^2
    g = np.concatenate([[0.0], np.cumsum(np.minimum(rate * np.diff(tau), 1.0))])
    u = np.minimum(cap, 1.0) ** 2
    fwd = np.minimum.accumulate(u - g) + g
    bwd = np.minimum.accumulate((u + g)[::-1])[::-1] - g
    return np.sqrt(np.clip(np.minimum(np.minimum(fwd, bwd), u), 1e-24, 1.0))


def _durations(tau: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(n - 1,) machine time of each interval: the integral of dtau / s with s linear in tau."""
    dt = np.diff(tau)
    s0, s1 = s[:-1], s[1:]
    flat = np.abs(s1 - s0) <= 1e-9 * s0
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(flat, dt / (0.5 * (s0 + s1)),
                        dt * np.log1p((s1 - s0) / s0) / np.where(flat, 1.0, s1 - s0))


def _inside(tau: np.ndarray, s: np.ndarray, j: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The schedule instants x ms of machine time into intervals j (s linear in tau there)."""
    t0, dt = tau[j], tau[j + 1] - tau[j]
    s0, s1 = s[j], s[j + 1]
    k = (s1 - s0) / dt
    flat = np.abs(s1 - s0) <= 1e-9 * s0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        step = np.where(flat, 0.5 * (s0 + s1) * x, s0 * np.expm1(k * x) / np.where(flat, 1.0, k))
    return np.clip(t0 + step, t0, tau[j + 1])


def _ranges(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The concatenation of arange(a[k], b[k]) over k (b >= a)."""
    n = b - a
    return np.repeat(a, n) + np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)


def _over_ranges(values: np.ndarray, i: np.ndarray, ufunc) -> np.ndarray:
    """(n - 1,) ufunc-reduction of values over each closed range i[k]..i[k + 1] (i (n,) nondecreasing)."""
    ext = np.append(values, values[-1] if len(values) else 0.0)
    part = ufunc.reduceat(ext, i)[:-1]
    return ufunc(part, values[i[1:]])


def _passed(values: np.ndarray, i: np.ndarray) -> np.ndarray:
    """(n - 1,) the least of values (one per vertex) over the vertices i[k] + 1 .. i[k + 1] passed between
    instants k and k + 1 (i: the segment at each instant, nondecreasing); inf where none is passed."""
    ext = np.append(values, np.inf)
    part = np.minimum.reduceat(ext, i + 1)[:-1]
    return np.where(i[1:] > i[:-1], part, np.inf)


class _Grid:
    """Schedule instants tau (n,) with, per cutter, the schedule's tip speed and the polyline segment
    at each, and per interval the cap on s, the part of it the chord tolerance sets, and the bound on
    how fast s^2 may change over it; ``refine`` splits intervals, evaluating the schedule at the new
    instants only."""

    def __init__(self, schedule: Schedule, caps: dict[str, SegmentCaps], tau: np.ndarray, a_tip: float,
                 period: float):
        self.schedule, self.caps, self.a_tip, self.period = schedule, caps, a_tip, period
        self.tau = tau
        self.v, self.seg = self._evaluate(tau)
        self.lowered = np.ones(len(tau))
        self._caps()

    def _evaluate(self, tau: np.ndarray) -> tuple[dict, dict]:
        sch = self.schedule
        got = per_side(lambda side: (sch.speeds(side, tau), sch.table(side).segment_at(tau)),
                       parallel=worth_threads(len(tau)))
        return {side: got[side][0] for side in SIDES}, {side: got[side][1] for side in SIDES}

    def _passes(self) -> None:
        """Per cutter and interval, what does not depend on the rate: the speeds and caps of the
        segments and vertices passed, the junctions' kept apart (``_intervals`` spreads them)."""
        self.passes = {}
        for side in SIDES:
            c, i = self.caps[side], self.seg[side]
            if len(c.segment) == 0:
                continue
            inner = np.where(c.junction, np.inf, c.vertex), np.where(c.junction, np.inf, c.chord)
            at_junction = np.where(c.junction, c.vertex, np.inf), np.where(c.junction, c.chord, np.inf)
            j_vertex, j_chord = _passed(at_junction[0], i), _passed(at_junction[1], i)
            k = np.flatnonzero(np.isfinite(j_vertex) | np.isfinite(j_chord))
            self.passes[side] = {
                "segment": np.minimum(_over_ranges(c.segment, i, np.minimum), _passed(inner[0], i)),
                "chord": _passed(inner[1], i), "slope": _over_ranges(c.slope, i, np.maximum),
                "junctions": k, "j_vertex": j_vertex[k], "j_chord": j_chord[k]}

    def _intervals(self, spread: np.ndarray | None = None) -> None:
        n = len(self.tau)
        cap, rate, chord_cap = np.ones(n - 1), np.full(n - 1, np.inf), np.ones(n - 1)
        self.own = {side: (np.ones(n - 1), np.full(n - 1, np.inf)) for side in SIDES}
        tau = self.tau
        dtau = np.maximum(np.diff(tau), 1e-300)
        for side, got in self.passes.items():
            v = self.v[side]
            tip, chord, slope = got["segment"].copy(), got["chord"].copy(), got["slope"]
            k = got["junctions"]
            # a junction's caps hold while a row's chord can reach across it: over a period of the
            # machine's time either side of where it is passed, period * s of the schedule's, s taken
            # from the rate without the spread (which only lowers it)
            reach = 0.0 if spread is None else self.period * np.maximum(spread[k], spread[k + 1])
            lo = np.maximum(np.searchsorted(tau, tau[k] - reach, side="right") - 1, 0)
            hi = np.minimum(np.searchsorted(tau, tau[k + 1] + reach, side="left") - 1, n - 2)
            idx, count = _ranges(lo, hi + 1), hi + 1 - lo
            np.minimum.at(tip, idx, np.repeat(got["j_vertex"], count))
            np.minimum.at(chord, idx, np.repeat(got["j_chord"], count))
            vmax = np.maximum(v[:-1], v[1:])
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                acc = np.abs(np.diff(v)) / dtau
                # the axes' acceleration: the path's own turning at the speed, plus the schedule's
                # acceleration along it through dq/ds, within their share together (harmonic sum)
                turning = np.where(vmax > 0, tip / vmax, np.inf)
                along = np.sqrt((1.0 - SCALE_SHARE) * AIM / (slope * acc))
                s_cap = np.minimum(1.0 / np.sqrt(1.0 / turning ** 2 + 1.0 / along ** 2), 1.0)
                s_chord = np.where(vmax > 0, np.minimum(chord / vmax, 1.0), 1.0)
                axes = 2.0 * AIM * SCALE_SHARE / (slope * vmax)
                tips = 2.0 * np.maximum(TIP_AIM * self.a_tip - s_cap * s_cap * acc, 0.0) / vmax
            own_rate = np.where(vmax > 0, np.minimum(axes, tips), np.inf)
            self.own[side] = (s_cap, own_rate)
            cap, chord_cap = np.minimum(cap, s_cap), np.minimum(chord_cap, s_chord)
            rate = np.minimum(rate, own_rate)
        self.cap, self.chord_cap, self.rate = cap, chord_cap, rate

    def refine(self) -> bool:
        """Split each interval longer than REFINE_ABOVE periods of machine time evenly into pieces of
        about a period, at most SPLIT_AT_MOST (False when there is none)."""
        period = self.period
        dur = _durations(self.tau, self.scale())
        long = np.flatnonzero(dur > REFINE_ABOVE * period)
        if long.size == 0:
            return False
        # (a few pieces a round: the caps of the pieces are found again, less tight than their
        # interval's, and most intervals need fewer pieces than its duration said)
        pieces = np.minimum(np.ceil(dur[long] / period), SPLIT_AT_MOST).astype(np.int64)
        j = np.repeat(long, pieces - 1)
        k = _ranges(np.ones(len(long), np.int64), pieces)
        new = self.tau[j] + (self.tau[j + 1] - self.tau[j]) * k / np.repeat(pieces, pieces - 1)
        v, seg = self._evaluate(new)
        at = j + 1  # (np.insert: before index j + 1, in the order given)
        self.tau = np.insert(self.tau, at, new)
        for side in SIDES:
            self.v[side] = np.insert(self.v[side], at, v[side])
            self.seg[side] = np.insert(self.seg[side], at, seg[side])
        self.lowered = np.ones(len(self.tau))
        self._caps()
        return True

    def _caps(self) -> None:
        """The intervals' caps: the vertices' own first, then the junctions' spread over the rows'
        reach at that rate."""
        self._passes()
        self._intervals()
        self._intervals(spread=self.scale())

    def settle(self) -> None:
        """Drop what only the refinement needs (the speeds, segments and passes at the instants): the
        checks lower the caps found and take the look-ahead again, nothing more."""
        self.v = self.seg = self.passes = None

    def rows_cap(self) -> np.ndarray:
        """(n,) the cap at each instant: both neighbouring intervals', and what the checks lowered."""
        c = np.ones(len(self.tau))
        c[:-1] = self.cap
        c[1:] = np.minimum(c[1:], self.cap)
        return np.minimum(c, self.lowered)

    def scale(self) -> np.ndarray:
        return _cone(self.rows_cap(), self.tau, self.rate)

    def own_scale(self, side: str) -> np.ndarray:
        """(n,) the rate one machine's own caps and speed changes would allow at the instants, were it
        timed alone (what the checks lowered counts for both: it is not known which one broke)."""
        cap, rate = self.own[side]
        c = np.ones(len(self.tau))
        c[:-1] = cap
        c[1:] = np.minimum(c[1:], cap)
        return _cone(np.minimum(c, self.lowered), self.tau, rate)


def _clock(tau: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(n,) the machine time of each schedule instant tau (s on them)."""
    return np.concatenate([[0.0], np.cumsum(_durations(tau, s))])


def _at_machine_times(tau: np.ndarray, s: np.ndarray, clock: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The schedule instants of machine times t (the clock's end and after: the schedule's end)."""
    j = np.clip(np.searchsorted(clock, t, side="right") - 1, 0, len(tau) - 2)
    out = _inside(tau, s, j, np.clip(t - clock[j], 0.0, clock[j + 1] - clock[j]))
    out[t >= clock[-1]] = tau[-1]
    return out


def _rows(tau: np.ndarray, s: np.ndarray, clock: np.ndarray, period: float
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows t = k * period (rounded to the tables' 1e-6 ms) up to the end of the job on the clock
    (s on the instants tau, ``clock`` their machine times), their schedule instants and the rate
    there (s linear in tau)."""
    t = np.round(np.arange(int(np.ceil(clock[-1] / period - 1e-9)) + 1) * period, 6)
    tau_rows = _at_machine_times(tau, s, clock, t)
    j = np.clip(np.searchsorted(tau, tau_rows, side="right") - 1, 0, len(tau) - 2)
    frac = np.clip((tau_rows - tau[j]) / np.maximum(tau[j + 1] - tau[j], 1e-300), 0.0, 1.0)
    return t, tau_rows, s[j] + (s[j + 1] - s[j]) * frac


def _chord_estimate(smp: Samples, r: float) -> np.ndarray:
    """(n - 1,) an estimate of how far the planned motion strays from the straight line between two
    rows: the chord times the larger turn at its two ends over 8, tips and ball centres."""
    est = np.zeros(len(smp.tips) - 1)
    for pts in (smp.tips, ball_centres(smp.tips, smp.axes, r)):
        est = np.maximum(est, 2.0 * sagitta(*interval_turns(pts)))
    return est


def _off_chord(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(m,) distance of points p from the segments a-b (m, 3)."""
    e = b - a
    ee = np.einsum("ij,ij->i", e, e)
    u = np.clip(np.einsum("ij,ij->i", p - a, e) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
    return row_norm(a + u[:, None] * e - p)


def _chord_deviation(schedule: Schedule, side: str, smp: Samples, k: np.ndarray, tau_mid: np.ndarray,
                     r: float) -> np.ndarray:
    """(m,) how far one cutter's planned path at the instants tau_mid (between rows k and k + 1) lies from
    the straight line between the two rows, tips and ball centres (a distance from the line, not from
    its midpoint: a cutter slowing down is not off its path)."""
    mid = schedule.table(side).sample(tau_mid)
    dev = _off_chord(mid.tips, smp.tips[k], smp.tips[k + 1])
    centres = ball_centres(smp.tips, smp.axes, r)
    return np.maximum(dev, _off_chord(ball_centres(mid.tips, mid.axes, r), centres[k], centres[k + 1]))


@dataclass
class _Check:
    """The rows of one round as written, checked: the grid's rate and clock they were made on, the
    axis motion per side (values, derivative in schedule time), per row interval the worst share of an
    axis limit (``over``), the chord deviation of the intervals that cut or touch a cutting move
    (measured where the estimate comes near the tolerance, else the estimate), and every interval's
    deviation as a share of its tolerance (``chord_share``: in the air, AIR_CHORD_TOL)."""

    grid_scale: np.ndarray
    clock: np.ndarray
    t: np.ndarray
    tau: np.ndarray
    s: np.ndarray
    samples: dict
    motion: dict
    over: np.ndarray
    chord: np.ndarray
    chord_share: np.ndarray


def _check(machine: Machine, schedule: Schedule, grid: _Grid, period: float, r: float,
           chord_tol: float) -> _Check:
    s = grid.scale()
    clock = _clock(grid.tau, s)
    t, tau_rows, s_rows = _rows(grid.tau, s, clock, period)
    v_lim, a_lim = axis_limits(machine)

    def motion(side: str):
        smp, tip_rate, axis_rate = schedule.table(side).sample_with_rates(tau_rows)
        return smp, axis_motion(machine, side, smp.tips, smp.axes, tip_rate, axis_rate)

    both_sides = per_side(motion, parallel=worth_threads(len(t)))
    smp = {side: both_sides[side][0] for side in SIDES}
    got = {side: both_sides[side][1] for side in SIDES}
    over = axis_excess([got[side][1] for side in SIDES], s_rows, period, v_lim, a_lim)
    chord, ratio = np.zeros(len(t) - 1), np.zeros(len(t) - 1)
    for side in SIDES:
        cutting = smp[side].cutting
        # (a row interval between two rows of moves that do not cut is in the air: core.machine.caps)
        tol = np.where(cutting[:-1] | cutting[1:], chord_tol, max(chord_tol, AIR_CHORD_TOL))
        dev = _chord_estimate(smp[side], r)
        k = np.flatnonzero(dev > MEASURE_SHARE * tol)
        if k.size:
            tau_mid = _at_machine_times(grid.tau, s, clock, 0.5 * (t[k] + t[k + 1]))
            dev[k] = _chord_deviation(schedule, side, smp[side], k, tau_mid, r)
        chord = np.maximum(chord, np.where(tol == chord_tol, dev, 0.0))
        ratio = np.maximum(ratio, dev / tol)
    return _Check(s, clock, t, tau_rows, s_rows, smp, got, over, chord, ratio)


def _lower(grid: _Grid, rows: _Check, f: np.ndarray) -> None:
    """Lower the rate by the factors f (one per row interval, < 1 where a limit broke) over those
    intervals and their neighbours (the next round's rows fall elsewhere)."""
    k = np.flatnonzero(f < 1.0)
    n, last = len(grid.tau), len(rows.t) - 1
    g0 = np.clip(np.searchsorted(grid.tau, rows.tau[np.maximum(k - 1, 0)], side="right") - 1, 0, n - 1)
    g1 = np.clip(np.searchsorted(grid.tau, rows.tau[np.minimum(k + 2, last)], side="left"), 0, n - 1)
    idx = _ranges(g0, g1 + 1)
    np.minimum.at(grid.lowered, idx, np.repeat(f[k], g1 + 1 - g0) * rows.grid_scale[idx])


def _first_instants(schedule: Schedule, period: float) -> np.ndarray:
    """The grid's first instants: every period of the schedule's time, and where each move starts and
    each speed ramp reaches its cruise, so that between two instants a cutter's speed rises, falls
    or dips (a ramp, a speed stage) but never peaks inside: the larger speed at the two ends bounds
    it (a rest-to-rest move of a few micrometres between tight corners lies between two instants)."""
    end = schedule.duration
    if end <= 0:
        return np.array([0.0, 1e-9])
    marks: list = [np.arange(0.0, end, period), [end]]
    for side in SIDES:
        tab = schedule.table(side)
        ramps = np.isin(tab.kind, (RAMP, MAPPED))
        marks += [tab.t0, (tab.t0 + tab.p[:, 4])[ramps], (tab.t0 + tab.p[:, 4] + tab.p[:, 5])[ramps]]
    tau = np.unique(np.concatenate(marks))
    return tau[(tau >= 0.0) & (tau <= end)]


def time_for_machines(machine: Machine, schedule: Schedule, period: float, tool_radius: float, a_tip: float,
                      chord_tol: float, cancel=None) -> MachineTiming:
    """The job on the machine clock (module docstring). ``period`` ms, ``a_tip`` mm/ms^2 (a_max),
    ``chord_tol`` mm. The axis tables' velocities are the derivative of the motion on the clock."""

    def stop():
        if cancel is not None and cancel():
            raise Cancelled()

    caps = per_side(lambda side: segment_caps(machine, side, schedule.table(side), tool_radius, period,
                                              chord_tol, schedule.feed / 60000.0))
    grid = _Grid(schedule, caps, _first_instants(schedule, period), a_tip, period)
    for _ in range(REFINE_ROUNDS):
        stop()
        if not grid.refine():
            break
    grid.settle()
    for _ in range(CHECK_ROUNDS):
        stop()
        rows = _check(machine, schedule, grid, period, tool_radius, chord_tol)
        bad_a, bad_c = rows.over > 1.0, rows.chord_share > 1.0
        if not (bad_a.any() or bad_c.any()):
            break
        f = np.ones(len(rows.t) - 1)
        f[bad_a] = AIM / np.sqrt(rows.over[bad_a])
        f[bad_c] = np.minimum(f[bad_c], CHORD_AIM / rows.chord_share[bad_c])
        _lower(grid, rows, f)
    t, s_rows = rows.t, rows.s
    for side in SIDES:  # (the derivative in schedule time becomes the velocity on the clock, in place)
        np.multiply(rows.motion[side][1], s_rows[:, None], out=rows.motion[side][1])
    tables = {side: AxisTable(side, t, *rows.motion[side]) for side in SIDES}
    worst = int(np.argmax(rows.chord)) if len(rows.chord) else 0
    dur = np.diff(rows.clock)
    chord_cut = (grid.chord_cap < 1.0) & (grid.chord_cap <= grid.cap * (1 + 1e-9))
    chord_fig = {"tolerance_mm": chord_tol,
                 "largest_deviation_mm": round(float(rows.chord.max(initial=0.0)), 6),
                 "largest_deviation_at_ms": round(float(t[worst]), 3),
                 "feed_cut_for_it_s": round(float(dur[chord_cut].sum()) / 1000.0, 3)}
    timeline = Timeline(t, rows.samples["left"], rows.samples["right"])
    own = {side: np.minimum(np.interp(rows.tau, grid.tau, grid.own_scale(side)), 1.0) for side in SIDES}
    return MachineTiming(timeline, TimeWarp(t, rows.tau, s_rows, _slowed_for(grid, rows), own), tables, chord_fig)


def _slowed_for(grid: _Grid, rows: _Check) -> np.ndarray:
    """(n,) int8 per row, indices into SLOWED_FOR: where the clock runs below SLOWED_BELOW, the chord
    tolerance where it set the cap of the grid interval the row lies in, else the axes (their speeds
    and accelerations, with the look-ahead that keeps their share of the speed changes)."""
    j = np.clip(np.searchsorted(grid.tau, rows.tau, side="right") - 1, 0, len(grid.cap) - 1)
    chord = (grid.chord_cap[j] < 1.0) & (grid.chord_cap[j] <= grid.cap[j] * (1.0 + 1e-9))
    why = np.where(chord, SLOWED_FOR.index("chord"), SLOWED_FOR.index("axes")).astype(np.int8)
    return np.where(rows.s < SLOWED_BELOW, why, np.int8(0)).astype(np.int8)
