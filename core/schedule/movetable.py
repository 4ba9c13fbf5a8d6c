"""A cutter's whole move list as arrays: every law's distance and speed, the positions on the
polylines and the segment each instant lies on, for many times at once and with no Python loop over
moves (a job has about 10,000 moves and the time column 600,000 rows).

The laws of core.schedule.motion, core.schedule.profiles and core.schedule.sigmoid are evaluated here
from their parameters through core.schedule.laws, their one implementation (their own ``distance``
and ``speed`` methods use it too). A law of any other type is evaluated through its own methods,
one move at a time.

Units: mm, ms, mm/ms.
"""

from __future__ import annotations

from dataclasses import fields
from functools import partial

import numpy as np

from core.schedule.curve import derivative, evaluate, segment_rows, tangents
from core.schedule.laws import (
    knot_distance,
    knot_speed,
    plateau_distance,
    plateau_speed,
    ramp_distance,
    ramp_speed,
    sigmoid_distance,
    sigmoid_speed,
)
from core.schedule.motion import MappedLaw, Move, ProfileLaw, RampLaw, Samples, WaitLaw
from core.schedule.profiles import LogisticRamp, PlateauStage, SepticRamp
from core.schedule.sigmoid import SigmoidStage
from core.util.parallel import ROW_BLOCK, both
from core.util.rowwise import row_norm

WAIT, RAMP, PLATEAU_LOGISTIC, PLATEAU_SEPTIC, SIGMOID, MAPPED, OTHER, PROFILE = range(8)


class _Runs:
    """Per-move nondecreasing 1-D arrays (polyline lengths, sync-map breakpoints) laid end to end, with
    a search of a value inside one move's own array for many (move, value) pairs at once."""

    def __init__(self, arrays: list[np.ndarray]):
        self.size = np.array([len(a) for a in arrays], np.int64)
        self.off = np.concatenate([[0], np.cumsum(self.size)[:-1]]).astype(np.int64)
        self.x = np.concatenate(arrays) if arrays else np.empty(0)
        nz = self.size > 0
        first = np.zeros(len(arrays))
        last = np.zeros(len(arrays))
        first[nz] = self.x[self.off[nz]]
        last[nz] = self.x[self.off[nz] + self.size[nz] - 1]
        span = last - first
        # every move's values shifted into its own band, 1 apart from the next: one global sort order
        self.shift = np.concatenate([[0.0], np.cumsum(span + 1.0)[:-1]]) - first
        self.g = self.x + np.repeat(self.shift, self.size)
        self.first, self.last = first, last

    def segment(self, j: np.ndarray, s: np.ndarray) -> np.ndarray:
        """(k,) moves, (k,) values -> (k,) global index i of the segment x[i] <= s < x[i + 1] of each
        move's own array (clipped to its first and last segment; the moves need >= 2 values)."""
        lo, hi = self.off[j], self.off[j] + self.size[j] - 2
        s = np.clip(s, self.first[j], self.last[j])
        i = np.clip(np.searchsorted(self.g, s + self.shift[j], side="right") - 1, lo, hi)
        # the shifted search may be one off where s is within round-off of a value: settle it exactly
        i = np.where((s < self.x[i]) & (i > lo), i - 1, i)
        return np.where((s >= self.x[np.minimum(i + 1, len(self.x) - 1)]) & (i < hi), i + 1, i)


class MoveTable:
    """The arrays of a list of back-to-back moves (core.schedule.motion.Move)."""

    def __init__(self, moves: list[Move]):
        self.moves = moves
        n = len(moves)
        self.t0 = np.array([m.t0 for m in moves])
        self.dur = np.array([m.law.duration for m in moves])
        self.step = np.array([m.step for m in moves], np.int64)
        self.path = np.array([m.path for m in moves], np.int64)
        self.cutting = np.array([m.cutting for m in moves], bool)
        self.kind = np.full(n, OTHER, np.int64)
        self.p = np.zeros((n, 7))
        mapped = []
        knots = [np.empty(0)] * n
        for j, m in enumerate(moves):
            law = m.law
            if isinstance(law, WaitLaw):
                self.kind[j] = WAIT
            elif isinstance(law, ProfileLaw):
                self.kind[j] = PROFILE
                self.p[j, 0] = law.length
                knots[j] = law.t
            elif isinstance(law, RampLaw):
                self.kind[j] = RAMP
                self.p[j] = (law.length, law.v_a, law.v_c, law.v_b, law.t1, law.t_cruise, law.t2)
            elif isinstance(law, PlateauStage) and type(law.shape) in (LogisticRamp, SepticRamp):
                logistic = isinstance(law.shape, LogisticRamp)
                self.kind[j] = PLATEAU_LOGISTIC if logistic else PLATEAU_SEPTIC
                self.p[j] = (law.v0, law.v_low, law.ramp_time, law.plateau_time,
                             law.shape.steepness if logistic else 0.0, law.length, law.ramp_length)
            elif isinstance(law, SigmoidStage):
                self.kind[j] = SIGMOID
                self.p[j] = (law.K_V, law.K_T, law.K_a, law.K, law.length, 0.0, 0.0)
            elif isinstance(law, MappedLaw) and isinstance(law.master, RampLaw):
                self.kind[j] = MAPPED
                mm = law.master
                self.p[j] = (mm.length, mm.v_a, mm.v_c, mm.v_b, mm.t1, mm.t_cruise, mm.t2)
                mapped.append(j)
        #: the parameters as (7, n) rows: a gather of moves gives each parameter as a contiguous row
        self.pt = np.ascontiguousarray(self.p.T)
        # the sync maps of the mapped laws (piecewise cubics): breakpoints and the coefficients of each piece
        breaks = [np.empty(0)] * n
        coef = []
        for j in mapped:
            f = moves[j].law.f
            breaks[j] = f.x
            coef.append(np.vstack([f.c.T, np.zeros((1, 4))]))  # one row per breakpoint (last unused)
        self.pchip = _Runs(breaks)
        # the profile laws' knots: instants (searched per move), and distance, speed, acceleration after
        self.knots = _Runs(knots)
        prof = [moves[j].law for j in range(n) if self.kind[j] == PROFILE]
        self.knot_s = np.concatenate([p.s for p in prof]) if prof else np.empty(0)
        self.knot_v = np.concatenate([p.v for p in prof]) if prof else np.empty(0)
        self.knot_a = np.concatenate([np.append(p.a, 0.0) for p in prof]) if prof else np.empty(0)
        self.coef = np.concatenate(coef) if coef else np.empty((0, 4))
        # the polylines
        self.poly = _Runs([m.cum for m in moves])
        self.points = np.concatenate([m.points for m in moves])
        self.axes = np.concatenate([m.axes for m in moves])
        self.regions = np.concatenate([m.regions for m in moves])  # make_move: one code per vertex
        # per polyline segment k (vertex k to k + 1; across two moves where no sample falls): its
        # length, and the cubic Hermite coefficients of the tips and of the axes along it
        # (core.schedule.curve), side by side (one gather a row)
        self._seg = np.diff(self.poly.x)
        s_chain, size = self._chains()
        s_own = self.poly.x
        self._rows = np.ascontiguousarray(np.hstack([
            segment_rows(self.points, tangents(self.points, s_chain, size), s_own),
            segment_rows(self.axes, tangents(self.axes, s_chain, size), s_own)]))

    def _chains(self) -> tuple[np.ndarray, np.ndarray]:
        """(arc length along chains (n,), vertices per chain): a chain is a run of consecutive cutting
        moves of one path, each starting where the one before ends (a path cut in stretches), so that
        the curve's tangent is continuous where one stretch hands over to the next (the legs of a
        turn keep their corners: a cutter passes them at rest)."""
        size = self.poly.size
        n = len(size)
        if n == 0:
            return self.poly.x, size
        first, last = self.poly.off, self.poly.off + size - 1
        conn = np.zeros(n, bool)  # move j continues move j - 1
        if n > 1:
            ok = (size[1:] >= 2) & (size[:-1] >= 2) & self.cutting[1:] & self.cutting[:-1] & \
                (self.path[1:] == self.path[:-1])
            conn[1:] = ok & (row_norm(self.points[first[1:]] - self.points[np.maximum(last[:-1], 0)]) <= 1e-9)
        chain = np.cumsum(~conn) - 1
        length = self.poly.last - self.poly.first
        # each move's offset: the lengths of the moves before it in its chain
        before = np.cumsum(length) - length
        offset = before - before[np.flatnonzero(~conn)][chain]
        s_chain = self.poly.x + np.repeat(offset, size)
        return s_chain, np.bincount(chain, weights=size).astype(np.int64)

    # --- the laws ----------------------------------------------------------------------------------
    def owner(self, t: np.ndarray) -> np.ndarray:
        """(k,) ms -> (k,) the move each instant belongs to (the last one starting at or before it)."""
        return np.clip(np.searchsorted(self.t0, t, side="right") - 1, 0, len(self.t0) - 1)

    def distance(self, j: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """(k,) moves, (k,) ms from each move's start -> (k,) mm along its polyline."""
        return self._law(j, tau, 0)

    def speed(self, j: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """(k,) moves, (k,) ms from each move's start -> (k,) mm/ms along its polyline."""
        return self._law(j, tau, 1)

    def _law(self, j: np.ndarray, tau: np.ndarray, nu: int) -> np.ndarray:
        """Distance (nu = 0) or speed (nu = 1), one array operation per kind of law."""
        tau = np.clip(tau, 0.0, self.dur[j])
        out = np.zeros(len(j))  # WAIT stays 0
        kinds = self.kind[j]
        for k in np.flatnonzero(np.bincount(kinds)):  # (the kinds present: small codes)
            m = np.flatnonzero(kinds == k)
            jm, x = j[m], tau[m]
            if k in _CLOSED_FORMS:
                out[m] = _CLOSED_FORMS[k][nu](self.pt[:, jm], x)
            elif k == MAPPED:  # own = f(master): f' (master) * master speed
                p = self.pt[:, jm]
                out[m] = self._pchip(jm, ramp_distance(p, x), nu) * (ramp_speed(p, x) if nu else 1.0)
            elif k == PROFILE:
                i = self.knots.segment(jm, x)
                dx = x - self.knots.x[i]
                out[m] = (np.maximum(knot_speed(self.knot_v[i], self.knot_a[i], dx), 0.0) if nu else
                          np.minimum(knot_distance(self.knot_s[i], self.knot_v[i], self.knot_a[i], dx),
                                     self.p[jm, 0]))
            elif k == OTHER:
                out[m] = self._one_by_one(jm, x, "speed" if nu else "distance")
        return out

    def _pchip(self, j, s, nu: int) -> np.ndarray:
        """The mapped laws' sync map (nu = 0) or its derivative (nu = 1) at master distances s."""
        i = self.pchip.segment(j, s)
        h = s - self.pchip.x[i]
        c = self.coef[i]
        if nu == 0:
            return ((c[:, 0] * h + c[:, 1]) * h + c[:, 2]) * h + c[:, 3]
        return (3 * c[:, 0] * h + 2 * c[:, 1]) * h + c[:, 2]

    def _one_by_one(self, j, tau, method: str) -> np.ndarray:
        out = np.empty(len(j))
        for jj in np.unique(j):
            m = np.flatnonzero(j == jj)
            out[m] = getattr(self.moves[jj].law, method)(tau[m])
        return out

    # --- positions ---------------------------------------------------------------------------------
    def sample(self, t: np.ndarray) -> Samples:
        """(n,) ms -> the cutter's tips, axes, step, path, cutting flag and region at those instants."""
        return self._blocks(np.asarray(t, float), rates=False)[0]

    def sample_with_rates(self, t: np.ndarray) -> tuple[Samples, np.ndarray, np.ndarray]:
        """``sample`` and the derivatives of the tips (n, 3) mm/ms and of the unit axes (n, 3) 1/ms at
        those instants (the speed law times the direction of the segment each instant lies on)."""
        return self._blocks(np.asarray(t, float), rates=True)

    def _blocks(self, t: np.ndarray, rates: bool) -> tuple:
        """_sample in blocks of ROW_BLOCK instants (the temporaries of a time column stay a few MB)."""
        n = len(t)
        if n <= ROW_BLOCK:
            return self._sample(t, rates)
        first = self._sample(t[:ROW_BLOCK], rates)
        names = [f.name for f in fields(Samples)]
        out = {k: np.empty((n,) + getattr(first[0], k).shape[1:], getattr(first[0], k).dtype) for k in names}
        extra = [np.empty((n, 3)) for _ in first[1:]]
        for lo in range(0, n, ROW_BLOCK):
            part = first if lo == 0 else self._sample(t[lo:lo + ROW_BLOCK], rates)
            for k in names:
                out[k][lo:lo + ROW_BLOCK] = getattr(part[0], k)
            for dest, got in zip(extra, part[1:], strict=True):
                dest[lo:lo + ROW_BLOCK] = got
        return (Samples(**out), *extra)

    def _sample(self, t: np.ndarray, rates: bool) -> tuple:
        j = self.owner(t)
        x = t - self.t0[j]
        s = np.clip(self.distance(j, x), 0.0, self.poly.last[j])
        n = len(t)
        tips, axes = np.empty((n, 3)), np.empty((n, 3))
        region = np.empty(n, np.int64)
        extra = (np.zeros((n, 3)), np.zeros((n, 3))) if rates else ()
        single = self.poly.size[j] == 1
        if single.any():  # (moves standing at one point)
            i = self.poly.off[j[single]]
            tips[single], axes[single], region[single] = self.points[i], self.axes[i], self.regions[i]
        on = np.flatnonzero(~single) if single.any() else slice(None)
        if not single.all():
            jo, so = j[on], s[on]
            i = self.poly.segment(jo, so)
            seg = self._seg[i]
            f = np.where(seg > 0, (so - self.poly.x[i]) / np.where(seg > 0, seg, 1.0), 0.0)
            rows = self._rows[i]
            tips[on] = evaluate(rows[:, :12], f)
            w = evaluate(rows[:, 12:], f)
            norm = row_norm(w)
            unit = w / norm[:, None]
            axes[on] = unit
            region[on] = self.regions[np.where(f > 0.5, i + 1, i)]
            if rates:  # d/dt of tip and axis: the speed over the segment's length, along the curve
                v = self.speed(jo, x[on]) / np.where(seg > 0, seg, np.inf)
                extra[0][on] = v[:, None] * derivative(rows[:, :12], f)
                dw = v[:, None] * derivative(rows[:, 12:], f)
                extra[1][on] = (dw - unit * np.einsum("ij,ij->i", unit, dw)[:, None]) / norm[:, None]
        smp = Samples(tips, axes, self.step[j], self.path[j], self.cutting[j], region.astype(np.int8))
        return (smp, *extra)

    def segment_coefficients(self, i: np.ndarray) -> np.ndarray:
        """(k, 24) the Hermite coefficients of the tips (12) and the axes (12) of polyline segments i
        (core.schedule.curve.evaluate)."""
        return self._rows[i]

    def segment_at(self, t: np.ndarray) -> np.ndarray:
        """(n,) ms -> (n,) the polyline segment (global index: vertex i to i + 1) each instant lies on;
        a move standing at one point gives its vertex. Nondecreasing in t."""
        t = np.asarray(t, float)
        j = self.owner(t)
        out = self.poly.off[j].copy()
        on = np.flatnonzero(self.poly.size[j] >= 2)
        if on.size:
            jo = j[on]
            s = np.clip(self.distance(jo, t[on] - self.t0[jo]), 0.0, self.poly.last[jo])
            out[on] = self.poly.segment(jo, s)
        return np.minimum(out, max(len(self.points) - 2, 0))

    def speeds(self, t: np.ndarray) -> np.ndarray:
        """(n,) ms -> (n,) mm/ms: the tip speed along the path (the laws' derivative)."""
        j = self.owner(t)
        return self.speed(j, t - self.t0[j])


#: (distance, speed) of the laws evaluated from their parameters alone
_CLOSED_FORMS = {
    RAMP: (ramp_distance, ramp_speed),
    PLATEAU_LOGISTIC: (partial(plateau_distance, logistic=True), partial(plateau_speed, logistic=True)),
    PLATEAU_SEPTIC: (partial(plateau_distance, logistic=False), partial(plateau_speed, logistic=False)),
    SIGMOID: (sigmoid_distance, sigmoid_speed),
}


def build_tables(left: list[Move], right: list[Move]) -> tuple[MoveTable, MoveTable]:
    """The MoveTables of both cutters' move lists, built in two threads for long lists (their array
    work releases the GIL)."""
    return both(lambda: MoveTable(left), lambda: MoveTable(right), parallel=len(left) + len(right) > 200)
