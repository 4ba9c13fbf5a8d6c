"""The feed override: both machines slowed together so that every axis keeps its speed and its
acceleration limit (SPEC.md section 9; docs/DECISIONS.md, "Axis accelerations").

The schedule is timed for the tool tips. Round the blade's edges the heads swing (the tool axes turn
by tens of degrees over a fraction of a millimetre of path), and the axes would have to move far
faster than they can. ``retime`` slows the schedule's clock: row i of the drive tables is the
schedule's motion at its instant ``tau[i]``, reached at the new time ``t[i]``, the clock running at
``s = d tau / dt <= 1``. Both machines share s, so every instant of the collaborative schedule, and
with it every tip spacing and clearance, is kept.

What is bounded, on the table as written (the rows a controller executes):
- speed: |v| <= RETIME_MARGIN * max_speed at every row, v = the derivative of the motion;
- acceleration: |v[i+1] - v[i]| / (t[i+1] - t[i]) <= max_accel between every two rows (the mean
  acceleration between two rows' velocities; velocities jump at the polyline's vertices, so this is
  the acceleration a controller stepping from row to row sees, and it is what ``bladecam verify``
  recomputes from the file);
- rows at most ``period`` ms apart;
- the tips' acceleration along the path within a_max: the schedule's own s^2 times as much plus
  what the scale's changes add (v ds/dt); where the schedule itself accelerates at a_max the scale
  holds still.
The scale is found on the rows directly. In schedule time the axis velocities are D (the derivative
at tau); on the new clock they are D s, and between two rows the acceleration is about
|D[i+1] - D[i]| s^2 / (tau[i+1] - tau[i]) (``_Caps``) plus D ds/dt, which the scale's slope
bound |ds/dtau| <= K keeps below SCALE_SHARE of the limit (|D s| <= v_max, |ds/dt| = |ds/dtau| s).
Intervals that the slowing stretches beyond ``period`` are split; the caps are then found again on
the finer rows, until no interval is too long and the table as written keeps every limit.
"""

from __future__ import annotations

import numpy as np

from core.errors import Cancelled
from core.machine.model import AXES, Machine
from core.machine.postprocess import AxisTable, TimeWarp, axis_motion
from core.schedule.timeline import Insertion, Timeline
from core.util.parallel import ROW_BLOCK, SIDES, blocks, per_side, worth_threads
from core.util.rowwise import row_max

#: speeds and accelerations are aimed this far inside the limits
RETIME_MARGIN = 0.97
#: the tips' acceleration along the path is aimed this far inside a_max (0.9 made the default job
#: 128.1 min instead of 122.9: the scale holds still wherever the schedule accelerates above it)
TIP_MARGIN = 0.97
#: share of each axis's acceleration limit left to the changes of the speed scale
SCALE_SHARE = 0.2
#: intervals too long are split into pieces of at most this share of the period
SPLIT_SHARE = 0.85
#: rounds of splitting and checking at most
ROUNDS = 20


def _limits(machine: Machine) -> tuple[np.ndarray, np.ndarray]:
    """(12,) speed limits mm/ms and (12,) acceleration limits mm/ms^2: left's six axes, then right's."""
    v = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES]) / 1000.0
    a = np.array([machine.limits.axis(a).max_accel_mm_s2 for a in AXES]) / 1e6
    return np.tile(v, 2), np.tile(a, 2)


def _rows_max(values: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(n,) the largest |values[i, k]| * scale[k] of each row, computed in blocks of rows (two
    threads for long columns)."""
    out = np.empty(len(values))

    def block(lo: int) -> None:
        b = np.abs(values[lo:lo + ROW_BLOCK])
        b *= scale
        out[lo:lo + ROW_BLOCK] = row_max(b)

    blocks(len(values), block, parallel=worth_threads(len(values)))
    return out


class _Derivatives:
    """The axis derivatives (12 per row) of the column while the override adds rows: the first rows'
    and the added ones kept apart, with where each row of the merged column comes from; the (n, 12)
    column itself is built only when asked for (``merged``), not every round."""

    def __init__(self, first: np.ndarray):
        self.first = first
        self.source = np.arange(len(first))     # merged row -> row of (first, then the added ones)
        self._added = np.empty((0, first.shape[1]))
        self._merged = first

    def insert(self, ins, new: np.ndarray) -> None:
        start = len(self.first) + len(self._added)
        self._added = np.concatenate([self._added, new])
        self.source = ins.merge(self.source, np.arange(start, start + len(new)))
        self._merged = None

    def _gather(self, src: np.ndarray) -> np.ndarray:
        """(m, 12) the rows src of (first, then the added ones)."""
        n0 = len(self.first)
        out = np.empty((len(src), self.first.shape[1]))
        first = src < n0
        out[first] = self.first[src[first]]
        out[~first] = self._added[src[~first] - n0]
        return out

    def rows(self, idx: np.ndarray) -> np.ndarray:
        """(m, 12) the merged column's rows idx."""
        return self._gather(self.source[idx])

    def merged(self) -> np.ndarray:
        if self._merged is None:
            self._merged = self._gather(self.source)
        return self._merged


class _Caps:
    """The per-row and per-interval bounds on the scale, kept up to date as rows are added (only the
    intervals next to new rows are computed again):
    - speed (n,): the largest s with every axis speed |D s| <= v_aim at the row;
    - acc (n - 1,): the largest s with |D[i+1] - D[i]| s^2 / dtau <= a_aim over the interval;
    - rate (n - 1,): how fast s^2 may change per ms of schedule time over the interval: the axis
      accelerations of the change, D ds/dt = D (d s^2/dtau) / 2, within SCALE_SHARE of their
      limits (D the larger at the interval's two rows); and for the tips, whose acceleration on the
      new clock is s^2 a + v ds/dt (a, v: the schedule's own tip acceleration along the path and tip
      speed, ``tips`` (n, 2) mm/ms at the rows, both cutters), within TIP_MARGIN of a_tip with
      s <= c (the interval's other caps, at most 1): |d s^2/dtau| <= 2 (TIP_MARGIN a_tip - c^2 |a|) / v
      (zero where the schedule itself accelerates near the limit at full speed: the scale does not
      change there)."""

    def __init__(self, tau, deriv, tips, v_aim, a_aim, a_lim, a_tip):
        self.v_aim, self.a_aim, self.a_lim, self.a_tip = v_aim, a_aim, a_lim, a_tip
        self.speed = self._speed(deriv)
        n = len(tau)
        self.acc, self.rate = np.empty(n - 1), np.empty(n - 1)

        def block(lo: int) -> None:  # (in blocks of rows: no (n, 12) temporaries; two threads)
            hi = min(lo + ROW_BLOCK, n - 1)
            self.acc[lo:hi], self.rate[lo:hi] = self._intervals(tau, deriv[lo:hi], deriv[lo + 1:hi + 1], tips,
                                                                slice(lo, hi), slice(lo + 1, hi + 1))

        blocks(n - 1, block, parallel=worth_threads(n))

    def _speed(self, deriv):
        return np.minimum(1.0 / np.maximum(_rows_max(deriv, 1.0 / self.v_aim), 1e-300), 1.0)

    def _intervals(self, tau, d0, d1, tips, i0, i1):
        """The intervals from rows i0 to rows i1 (index arrays, or two slices), d0 and d1 the axis
        derivatives at those rows."""
        dtau = tau[i1] - tau[i0]
        r = row_max(np.abs(d1 - d0) * (1.0 / self.a_aim))     # a = r a_aim s^2 / dtau
        acc = np.sqrt(dtau / np.maximum(r, 1e-300))
        # the axes' share for the scale's changes: min over axes of C a_lim / |D| = C / max(|D| / a_lim)
        d = np.maximum(np.abs(d0), np.abs(d1)) * (1.0 / self.a_lim)
        allowed = 2.0 * RETIME_MARGIN * SCALE_SHARE / np.maximum(row_max(d), 1e-300)
        v = row_max(np.maximum(tips[i0], tips[i1]))
        a = row_max(np.abs(tips[i1] - tips[i0])) / np.maximum(dtau, 1e-300)
        c = np.minimum(np.maximum(self.speed[i0], self.speed[i1]), np.minimum(acc, 1.0))  # s <= c here
        tip = 2.0 * np.maximum(TIP_MARGIN * self.a_tip - c * c * a, 0.0) / np.maximum(v, 1e-300)
        return acc, np.minimum(allowed, tip)

    def insert(self, ins, tau, deriv, tips, deriv_new) -> None:
        """Rows added (core.schedule.timeline.Insertion ``ins``); tau and tips: the merged columns, deriv: a
        _Derivatives holding the merged rows."""
        is_new = ins.is_new
        self.speed = ins.merge(self.speed, self._speed(deriv_new))
        old = np.cumsum(~is_new) - 1                                # merged row -> old row
        touch = is_new[:-1] | is_new[1:]
        acc, rate = np.empty(len(tau) - 1), np.empty(len(tau) - 1)
        keep = np.flatnonzero(~touch)
        acc[keep], rate[keep] = self.acc[old[keep]], self.rate[old[keep]]
        idx = np.flatnonzero(touch)

        def block(lo: int) -> None:  # (in blocks of the touched intervals; two threads)
            i = idx[lo:lo + ROW_BLOCK]
            acc[i], rate[i] = self._intervals(tau, deriv.rows(i), deriv.rows(i + 1), tips, i, i + 1)

        blocks(len(idx), block, parallel=worth_threads(len(idx)))
        self.acc, self.rate = acc, rate

    def cap(self) -> np.ndarray:
        """(n,) the largest scale at each row: its speed bound and both neighbouring intervals'."""
        cap = self.speed.copy()
        cap[:-1] = np.minimum(cap[:-1], self.acc)
        cap[1:] = np.minimum(cap[1:], self.acc)
        return cap


def _cone(cap: np.ndarray, tau: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """The largest s <= cap (at increasing tau) whose square changes by at most ``rate[i]`` per ms
    over interval i (|d s^2 / dtau| <= rate), clipped to [1e-12, 1]."""
    # the integral of the rate; a step of s^2 above 1 is no bound (s^2 is in [0, 1]): clipped there,
    # so that the integral stays small enough to keep the digits of s^2 (a tip at rest has no bound)
    g = np.concatenate([[0.0], np.cumsum(np.minimum(rate * np.diff(tau), 1.0))])
    u = np.minimum(cap, 1.0) ** 2
    fwd = np.minimum.accumulate(u - g) + g
    bwd = np.minimum.accumulate((u + g)[::-1])[::-1] - g
    return np.sqrt(np.clip(np.minimum(np.minimum(fwd, bwd), u), 1e-24, 1.0))  # (u: round-off of +- g)


def _durations(tau: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(n - 1,) new-clock length of each interval: the integral of dtau / s with s linear in tau."""
    dt = np.diff(tau)
    s0, s1 = s[:-1], s[1:]
    flat = np.abs(s1 - s0) <= 1e-9 * s0
    with np.errstate(divide="ignore", invalid="ignore"):
        # (log1p: log(s1 / s0) of a ratio near 1 lost 1e-8 of the interval, 1e-7 ms over a period)
        return np.where(flat, dt / (0.5 * (s0 + s1)),
                        dt * np.log1p((s1 - s0) / s0) / np.where(flat, 1.0, s1 - s0))


def _inside(tau: np.ndarray, s: np.ndarray, j: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Schedule times x ms of the new clock into intervals ``j`` (s linear in tau)."""
    t0, dt = tau[j], tau[j + 1] - tau[j]
    s0, s1 = s[j], s[j + 1]
    k = (s1 - s0) / dt                      # ds/dtau
    flat = np.abs(s1 - s0) <= 1e-9 * s0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        step = np.where(flat, 0.5 * (s0 + s1) * x, s0 * np.expm1(k * x) / np.where(flat, 1.0, k))
    return np.clip(t0 + step, t0, tau[j + 1])


def _written(tau, s, deriv, a_lim, v_aim):
    """The table as it would be written at scale s: new times (on the 1e-6 ms grid), and per interval
    / row the worst acceleration / speed as a share of its aim (the velocities are deriv * s; computed
    in blocks of rows)."""
    t_new = np.round(np.concatenate([[0.0], np.cumsum(_durations(tau, s))]), 6)
    n = len(tau)
    over_a, over_v = np.empty(n - 1), np.empty(n)
    inv_a, inv_v = 1.0 / (a_lim * RETIME_MARGIN), 1.0 / v_aim

    def block(lo: int) -> None:
        hi = min(lo + ROW_BLOCK + 1, n)              # (one row more: the interval to the next block)
        vel = deriv[lo:hi] * s[lo:hi, None]
        step = np.abs(vel[1:] - vel[:-1])
        step *= inv_a
        over_a[lo:hi - 1] = row_max(step)
        np.abs(vel, out=vel)
        vel *= inv_v
        over_v[lo:min(lo + ROW_BLOCK, n)] = row_max(vel[:min(ROW_BLOCK, hi - lo)])

    blocks(n, block, parallel=worth_threads(n))
    over_a /= np.diff(t_new)
    return t_new, over_a, over_v


def _gathered(tau, tau0, values, added):
    """The first rows' axis values (at tau0) and each round's added ones, in the order of the final
    column tau (every row's instant is distinct: added rows lie strictly inside intervals)."""
    batches = [(np.searchsorted(tau, tau0), values)] + [(np.searchsorted(tau, add), q) for add, q in added]
    out = np.empty((len(tau), values.shape[1]))
    filled = np.zeros(len(tau), bool)
    for at, q in batches:
        out[at] = q
        filled[at] = True
    if not filled.all() or sum(len(at) for at, _ in batches) != len(tau):  # (two rows at one instant)
        raise RuntimeError("feed override: the rows' instants are not distinct")
    return out


def _at_written_times(tau: np.ndarray, s: np.ndarray, t_new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The schedule instants (and the scale there) of the written times t_new, which are the new
    clock's times of the rows tau rounded to the 1e-6 ms grid: each row moves along the clock (s
    linear in tau between the rows) by its rounding, into the interval after it or before it."""
    n = len(tau)
    if n < 2:
        return tau, s
    dur = _durations(tau, s)
    eps = t_new - np.concatenate([[0.0], np.cumsum(dur)])
    j = np.clip(np.where(eps >= 0, np.arange(n), np.arange(n) - 1), 0, n - 2)
    x = np.clip(np.where(j == np.arange(n), eps, dur[j] + eps), 0.0, dur[j])
    tau_w = _inside(tau, s, j, x)
    return tau_w, s[j] + (s[j + 1] - s[j]) * (tau_w - tau[j]) / (tau[j + 1] - tau[j])


def retime(machine: Machine, schedule, timeline, period: float, a_max: float, cancel=None):
    """The feed override (module docstring). ``a_max`` (mm/ms^2): the tips' acceleration bound along
    the path, which sets how fast the scale may change where the tips move.
    Returns (Timeline on the new clock, TimeWarp, {side: AxisTable}), the tables' velocities the
    derivative of the motion on the new clock. The new times are rounded to the tables' 1e-6 ms grid,
    and the CL rows are the motion at exactly those times (the schedule instant of each row moves by
    the rounding times the scale)."""
    tau = timeline.t.astype(float)
    end = float(tau[-1])
    samples = {"left": timeline.left, "right": timeline.right}
    v_lim, a_lim = _limits(machine)
    v_aim = RETIME_MARGIN * v_lim
    a_aim = RETIME_MARGIN * (1.0 - SCALE_SHARE) * a_lim

    def evaluate(times, smp):
        def side_motion(side):
            return axis_motion(machine, side, schedule.table(side), times, smp[side].tips, smp[side].axes,
                               end=end)

        motion = per_side(side_motion, parallel=worth_threads(len(times)))
        return (np.hstack([motion[side][0] for side in SIDES]),
                np.hstack([motion[side][1] for side in SIDES]))

    def tip_speeds(times):
        v = per_side(lambda side: schedule.speeds(side, times),
                     parallel=worth_threads(len(times)))
        return np.column_stack([v[side] for side in SIDES])

    values, first = evaluate(tau, samples)
    tau0, added = tau, []
    tips = tip_speeds(tau)
    caps = _Caps(tau, first, tips, v_aim, a_aim, a_lim, a_max)
    deriv = _Derivatives(first)
    lowered = np.ones(len(tau))  # extra caps from rounds whose written table still broke a limit
    for _round in range(ROUNDS):
        if cancel is not None and cancel():
            raise Cancelled()
        s = _cone(np.minimum(caps.cap(), lowered), tau, caps.rate)
        dur = _durations(tau, s)
        long = np.flatnonzero(dur > period * (1.0 + 1e-9))
        if long.size:
            # split them evenly on the new clock, a little finer than the period, so that the
            # next rounds' slowing seldom needs more rows
            pieces = np.ceil(dur[long] / (SPLIT_SHARE * period) - 1e-9).astype(int)
            j = np.repeat(long, pieces - 1)
            m = np.repeat(pieces, pieces - 1)
            first = np.cumsum(pieces - 1) - (pieces - 1)
            i = np.arange(len(j)) - np.repeat(first, pieces - 1) + 1
            splits = _inside(tau, s, j, i / m * dur[j])
            # (no minimum gap in schedule time: where the clock is slowed a thousandfold, rows a
            # period apart are microseconds apart on the schedule's clock)
            add = np.unique(splits[(splits > tau[j] + 1e-9) & (splits < tau[j + 1] - 1e-9)])
            if add.size:
                lm, rm = schedule.sample(add)
                q_add, d_add = evaluate(add, {"left": lm, "right": rm})
                ins = Insertion.of(tau, add)
                tau = ins.merge(tau, add)
                deriv.insert(ins, d_add)
                tips = ins.merge(tips, tip_speeds(add))
                caps.insert(ins, tau, deriv, tips, d_add)
                lowered = ins.merge(lowered, np.ones(len(add)))
                added.append((add, q_add))  # (the axis values are merged once, at the end)
                continue
        t_new, over_a, over_v = _written(tau, s, deriv.merged(), a_lim, v_aim)
        if over_a.max(initial=0.0) <= 1.0 and over_v.max(initial=0.0) <= 1.0 + 1e-12:
            break
        bad = np.flatnonzero(over_a > 1.0)
        f = np.ones(len(tau))
        np.minimum.at(f, bad, 0.97 / np.sqrt(over_a[bad]))
        np.minimum.at(f, bad + 1, 0.97 / np.sqrt(over_a[bad]))
        f = np.minimum(f, np.where(over_v > 1.0, 0.999 / np.maximum(over_v, 1e-300), 1.0))
        lowered = np.minimum(lowered, s * f)
    else:  # out of rounds: the table as it stands (check_limits reports what it still breaks)
        s = _cone(np.minimum(caps.cap(), lowered), tau, caps.rate)
        t_new, _, _ = _written(tau, s, deriv.merged(), a_lim, v_aim)
    vel = deriv.merged() * s[:, None]
    values = _gathered(tau, tau0, values, added)
    # the CL rows: the motion at the instant of each row's written (rounded) time, so that speeds and
    # accelerations recomputed from the rows are those of the motion (rows microseconds apart, off
    # by up to 5e-7 ms each, read as 200 mm/s^2 of tip acceleration on the BladeX mesh); the shift
    # moves a row by < 1e-7 mm, far below the axis values' 1e-6 mm, which stay as computed
    tau, s = _at_written_times(tau, s, t_new)
    left, right = schedule.sample(tau)
    warp = TimeWarp(t_new, tau, s)
    tables = {side: AxisTable(side, t_new, values[:, 6 * k:6 * k + 6], vel[:, 6 * k:6 * k + 6])
              for k, side in enumerate(("left", "right"))}
    return Timeline(t_new, left, right), warp, tables
