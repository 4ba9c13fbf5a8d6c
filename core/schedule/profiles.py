"""Speed stages beyond the paper's Eq. 22: ramp, plateau or dwell, ramp (SPEC.md sections 7 and 8).

Units: mm, ms, mm/ms, mm/ms^2 (a_max from mm/s^2 is divided by 1e6 by the caller).

A stage starts and ends at the feed v0 and covers `length` in `duration`. The extended stage ramps
down from v0 to v_low in ramp_time, holds v_low for plateau_time, and ramps back up (mirror image):
v(t) = v0 - dv S(t / ramp_time) on the first ramp, dv = v0 - v_low, with a normalised step S(tau),
S(0) = 0, S(1) = 1, point-symmetric (S(1 - tau) = 1 - S(tau)). Symmetry makes every ramp cover
ramp_time (v0 + v_low) / 2 whatever its shape, so the waypoints alone fix the displacement exactly:

    length = ramp_time (v0 + v_low) + plateau_time v_low,   duration = 2 ramp_time + plateau_time.

Ramp shapes:
- LogisticRamp(a): a segment of the logistic function, S = (sigma(a(2 tau - 1)) - sigma(-a)) / tanh(a/2).
  With a = ln((2 v0 - v_low) / v_low) the two ramps are exactly the first and second half of the
  paper's Eq. 22 with K_V = v0, K = v_low / 2, K_T = ramp_time / 2 (kind "sigmoid+plateau"). The
  logistic never reaches 0, so a dwell (v_low = 0) takes a free steepness (kind "sigmoid+dwell").
  Acceleration jumps at the ramp ends (infinite jerk), like Eq. 22 itself.
- SepticRamp: S = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 (kind "smooth"). Speed slope, acceleration
  and jerk vanish at both ends: acceleration and jerk are continuous, the jerk is finite.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.special import expit

from core.errors import PlanningError
from core.schedule.laws import (
    plateau_distance,
    plateau_speed,
    rows,
    shape_integral,
    shape_step,
)

_EPS = np.finfo(float).eps
#: the logistic's third-derivative extremum sits at |x| = ln(2 + sqrt(3)) (sigma'' = 1/(6 sqrt(3)) there)
X_JERK = float(np.log(2.0 + np.sqrt(3.0)))


def logistic_jerk_shape(a: float) -> float:
    """Steepness a > 0 -> max |sigma''(x)| over |x| <= a, sigma'' = sigma (1 - sigma)(1 - 2 sigma)."""
    x = min(a, X_JERK)
    s = float(expit(x))
    return s * (1.0 - s) * (2.0 * s - 1.0)


def solve_increasing(dist, speed, target: np.ndarray, t_end: float, scale: float) -> np.ndarray:
    """(k,) float, mm, targets in [0, dist(t_end)] -> (k,) float, ms, times with dist(t) = target.

    dist, speed : vectorised callables, dist nondecreasing on [0, t_end] with derivative speed >= 0.
    Safeguarded Newton iteration inside a bisection bracket (bisection whenever a Newton step would
    leave the bracket or the speed is 0); stops at a residual below 2 eps scale, or a bracket or
    step below 2 eps t_end. Where the speed vanishes (the end of a ramp into a dwell) the time is
    only as well conditioned as sqrt(residual / accel); the distance residual stays at round-off.
    """
    target = np.asarray(target, float)
    lo, hi = np.zeros_like(target), np.full_like(target, t_end)
    d_end = float(dist(np.array([t_end]))[0])
    t = np.clip(target / d_end * t_end, 0.0, t_end) if d_end > 0 else np.zeros_like(target)
    ftol, ttol = 2 * _EPS * scale, 2 * _EPS * t_end
    done = np.zeros(target.shape, bool)
    for _ in range(200):
        f = dist(t) - target
        lo, hi = np.where(f <= 0, t, lo), np.where(f >= 0, t, hi)
        done |= (np.abs(f) <= ftol) | (hi - lo <= ttol)
        if done.all():
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = t - f / speed(t)
        bad = ~((tn > lo) & (tn < hi))
        tn = np.where(bad, 0.5 * (lo + hi), tn)
        done |= ~bad & (np.abs(tn - t) <= ttol)
        t = np.where(done, t, tn)
    return t


@dataclass(frozen=True)
class LogisticRamp:
    """A logistic step over tau in [0, 1]: S = (sigma(a(2 tau - 1)) - sigma(-a)) / tanh(a / 2).

    steepness : a > 0, dimensionless (the paper's K_a K_T). Accel jumps at both ends (S'(0) != 0).
    """

    steepness: float
    name: ClassVar[str] = "sigmoid"

    def _x(self, tau: np.ndarray) -> np.ndarray:
        return self.steepness * (2.0 * np.asarray(tau, float) - 1.0)

    def step(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S(tau) (core.schedule.laws.shape_step)."""
        return shape_step(np.asarray(tau, float), self.steepness, True)

    def integral(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) int_0^tau S, closed form (1/(2a)) ln((1 + e^x)/(1 + e^-a)) - tau sigma(-a)."""
        return shape_integral(np.asarray(tau, float), self.steepness, True)

    def slope(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S'(tau) = 2 a sigma'(x) / tanh(a / 2)."""
        a, s = self.steepness, expit(self._x(tau))
        return 2 * a * s * (1 - s) / np.tanh(a / 2)

    def curvature(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S''(tau) = 4 a^2 sigma''(x) / tanh(a / 2)."""
        a, s = self.steepness, expit(self._x(tau))
        return 4 * a * a * s * (1 - s) * (1 - 2 * s) / np.tanh(a / 2)

    @property
    def max_slope(self) -> float:
        """max S' = S'(1/2) = (a / 2) / tanh(a / 2)."""
        return float(self.slope(np.array([0.5]))[0])

    @property
    def max_curvature(self) -> float:
        """max |S''| on [0, 1] (at |x| = ln(2 + sqrt 3), or at the ends for a shallow ramp)."""
        a = self.steepness
        return 4 * a * a * logistic_jerk_shape(a) / float(np.tanh(a / 2))

    @property
    def end_slope(self) -> float:
        """S'(0) = S'(1): the acceleration jump at a ramp end is dv end_slope / ramp_time."""
        return float(self.slope(np.array([0.0]))[0])


@dataclass(frozen=True)
class SepticRamp:
    """The septic smoothstep S = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 over tau in [0, 1].

    S' = 140 tau^3 (1 - tau)^3, S'' = 420 tau^2 (1 - tau)^2 (1 - 2 tau): S', S'' and S''' vanish at
    both ends, so the speed is C3 and the stage's acceleration and jerk are continuous.
    """

    name: ClassVar[str] = "smooth"
    max_slope: ClassVar[float] = 35 / 16  # at tau = 1/2
    max_curvature: ClassVar[float] = 84 / (5 * np.sqrt(5))  # at 1 - 2 tau = 1/sqrt(5)
    end_slope: ClassVar[float] = 0.0

    def step(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S(tau) (core.schedule.laws.shape_step)."""
        return shape_step(np.asarray(tau, float), 0.0, False)

    def integral(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) int_0^tau S = 7 tau^5 - 14 tau^6 + 10 tau^7 - 2.5 tau^8."""
        return shape_integral(np.asarray(tau, float), 0.0, False)

    def slope(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S'(tau)."""
        t = np.asarray(tau, float)
        return 140 * (t * (1 - t)) ** 3

    def curvature(self, tau: np.ndarray) -> np.ndarray:
        """(k,) tau -> (k,) S''(tau)."""
        t = np.asarray(tau, float)
        return 420 * (t * (1 - t)) ** 2 * (1 - 2 * t)


Ramp = LogisticRamp | SepticRamp


@dataclass(frozen=True)
class PlateauStage:
    """Ramp down, plateau (or dwell) at v_low, ramp up: a speed stage from v0 back to v0.

    v0 : mm/ms, entry and exit speed; v_low : mm/ms, 0 <= v_low <= v0, plateau speed (0: dwell);
    ramp_time : ms, each ramp (0 only for the constant stage); plateau_time : ms, >= 0;
    shape : LogisticRamp or SepticRamp. All methods are vectorised over t (ms) or s (mm); outside
    [0, duration] the stage continues at the constant speed v0.
    kind : "sigmoid" / "smooth" (no plateau), "+plateau" (v_low > 0 held), "+dwell" (v_low = 0),
    "constant" (no ramps, v0 = v_low = length / duration).
    """

    v0: float
    v_low: float
    ramp_time: float
    plateau_time: float
    shape: Ramp

    def __post_init__(self) -> None:
        ok = 0.0 <= self.v_low <= self.v0 and self.ramp_time >= 0.0 and self.plateau_time >= 0.0
        if not ok or self.v0 <= 0 or self.ramp_time + self.plateau_time <= 0:
            raise PlanningError(
                f"speed stage: need 0 <= v_low <= v0, v0 > 0, ramp_time, plateau_time >= 0 and a positive "
                f"duration; got v0={self.v0!r}, v_low={self.v_low!r}, ramp_time={self.ramp_time!r}, "
                f"plateau_time={self.plateau_time!r}")

    @classmethod
    def from_ramp_time(cls, length: float, v0: float, duration: float, ramp_time: float,
                       shape: Ramp | None = None) -> PlateauStage:
        """Waypoints for the exact length in the exact duration with the given ramp time (ms).

        v_low = (length - ramp_time v0) / (duration - ramp_time), plateau_time = duration - 2 ramp_time.
        shape None: the paper's tied logistic, a = ln((2 v0 - v_low) / v_low) (needs v_low > 0).
        Needs 0 < ramp_time <= duration / 2, ramp_time <= length / v0 and length < v0 duration.
        """
        tol = 1 + 1e-12  # round-off at the bounds (a dip over the whole duration, a dwell)
        if not (0 < ramp_time <= duration / 2 * tol and ramp_time * v0 <= length * tol < v0 * duration * tol):
            raise PlanningError(
                f"speed stage: ramp time {ramp_time!r} ms cannot cover {length!r} mm in {duration!r} ms "
                f"from {v0!r} mm/ms: need 0 < ramp_time <= duration/2, ramp_time <= length/v0 and "
                "length < v0 * duration")
        ramp_time = min(ramp_time, duration / 2)
        v_low = min(max((length - ramp_time * v0) / (duration - ramp_time), 0.0), v0)
        if shape is None:
            if v_low <= 0:
                raise PlanningError("speed stage: the paper's sigmoid cannot ramp down to 0 (v_low = 0); "
                                    "use a dwell with a LogisticRamp of chosen steepness")
            shape = LogisticRamp(float(np.log1p(2 * (v0 - v_low) / v_low)))
        return cls(v0, v_low, ramp_time, max(duration - 2 * ramp_time, 0.0), shape)

    # --- summary numbers ---------------------------------------------------------------------------
    @property
    def kind(self) -> str:
        """'constant', '<shape>', '<shape>+plateau' or '<shape>+dwell'."""
        if self.ramp_time == 0:
            return "constant"
        if self.v_low == 0:
            return self.shape.name + "+dwell"
        return self.shape.name + ("+plateau" if self.plateau_time > 0 else "")

    @property
    def duration(self) -> float:
        """ms."""
        return 2 * self.ramp_time + self.plateau_time

    @property
    def dv(self) -> float:
        """mm/ms, v0 - v_low."""
        return self.v0 - self.v_low

    @property
    def ramp_length(self) -> float:
        """mm, covered by one ramp: ramp_time (v0 + v_low) / 2."""
        return self.ramp_time * (self.v0 - self.dv / 2)

    @property
    def length(self) -> float:
        """mm."""
        return 2 * self.ramp_length + self.v_low * self.plateau_time

    @property
    def peak_accel(self) -> float:
        """mm/ms^2, max |dv/dt| = dv max S' / ramp_time."""
        return self.dv * self.shape.max_slope / self.ramp_time if self.ramp_time > 0 else 0.0

    @property
    def peak_smooth_jerk(self) -> float:
        """mm/ms^3, max |d2v/dt2| inside the ramps (excluding the acceleration jumps)."""
        return self.dv * self.shape.max_curvature / self.ramp_time**2 if self.ramp_time > 0 else 0.0

    @property
    def accel_jumps(self) -> tuple[tuple[float, float], ...]:
        """((time ms, signed jump of acceleration mm/ms^2), ...): empty for a smooth or constant stage."""
        if self.ramp_time == 0 or self.shape.end_slope == 0 or self.dv == 0:
            return ()
        j = self.dv * self.shape.end_slope / self.ramp_time
        tr, d = self.ramp_time, self.duration
        if self.plateau_time == 0:
            return ((0.0, -j), (tr, 2 * j), (d, -j))
        return ((0.0, -j), (tr, j), (d - tr, j), (d, -j))

    @property
    def peak_jerk(self) -> float:
        """mm/ms^3: infinite if the acceleration jumps (logistic ramps), else the smooth peak."""
        return float("inf") if self.accel_jumps else self.peak_smooth_jerk

    # --- time functions ----------------------------------------------------------------------------
    def _pieces(self, t: np.ndarray):
        """Masks (first ramp, second ramp, plateau, before, after) and ramp times tau in [0, 1]."""
        tr, d = self.ramp_time, self.duration
        before, after = t < 0, t > d
        r1 = (t >= 0) & (t < tr)
        r2 = (t >= d - tr) & (t <= d) & ~r1 & (tr > 0)
        flat = ~(r1 | r2 | before | after)
        scale = tr if tr > 0 else 1.0
        return r1, r2, flat, before, after, np.clip(t / scale, 0, 1), np.clip((d - t) / scale, 0, 1)

    def _rows(self, n: int) -> np.ndarray:
        a = self.shape.steepness if isinstance(self.shape, LogisticRamp) else 0.0
        return rows((self.v0, self.v_low, self.ramp_time, self.plateau_time, a, self.length, self.ramp_length), n)

    def speed(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms (core.schedule.laws.plateau_speed; v0 outside)."""
        t = np.asarray(t, float)
        tc = np.clip(t, 0.0, self.duration).ravel()
        inside = plateau_speed(self._rows(tc.size), tc, isinstance(self.shape, LogisticRamp)).reshape(t.shape)
        return np.where((t >= 0) & (t <= self.duration), inside, self.v0)

    def distance(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm from the stage start: 0 at t = 0, length at duration
        (core.schedule.laws.plateau_distance; on at v0 outside)."""
        t = np.asarray(t, float)
        d, total = self.duration, self.length
        tc = np.clip(t, 0.0, d).ravel()
        inside = plateau_distance(self._rows(tc.size), tc, isinstance(self.shape, LogisticRamp)).reshape(t.shape)
        return np.where(t < 0, self.v0 * t, np.where(t > d, total + self.v0 * (t - d), inside))

    def accel(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms^2 (right-hand value at interior jumps)."""
        t = np.asarray(t, float)
        r1, r2, _, _, _, u1, u2 = self._pieces(t)
        k = self.dv / self.ramp_time if self.ramp_time > 0 else 0.0
        return np.select([r1, r2], [-k * self.shape.slope(u1), k * self.shape.slope(u2)], 0.0)

    def jerk(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms^3: smooth jerk, +-inf at the acceleration jumps."""
        t = np.asarray(t, float)
        r1, r2, _, _, _, u1, u2 = self._pieces(t)
        k = self.dv / self.ramp_time**2 if self.ramp_time > 0 else 0.0
        out = np.select([r1, r2], [-k * self.shape.curvature(u1), -k * self.shape.curvature(u2)], 0.0)
        for tj, jump in self.accel_jumps:
            out = np.where(t == tj, np.copysign(np.inf, jump), out)
        return out

    def time_at_distance(self, s: np.ndarray) -> np.ndarray:
        """(k,) float, mm -> (k,) float, ms with distance(t) = s (to round-off; see solve_increasing).

        Linear on the plateau, a monotone solve on the ramps (the second by symmetry,
        t = duration - t1(length - s)); at a dwell the earliest time (the dwell's start) is returned.
        """
        s = np.asarray(s, float)
        shape, s = s.shape, s.ravel()
        tr, d, total, d1 = self.ramp_time, self.duration, self.length, self.ramp_length
        out = np.where(s < 0, s / self.v0, d + (s - total) / self.v0)
        on1 = (s >= 0) & (s <= d1)
        on2 = (s >= total - d1) & (s <= total) & ~on1
        flat = (s > d1) & (s < total - d1)
        if tr > 0:
            def ramp_distance(u):  # (the first ramp: the stage's own distance and speed up to tr)
                return self.distance(np.clip(u, 0, tr))

            def ramp_speed(u):
                return self.speed(np.clip(u, 0, tr))
            for mask, target, sign in ((on1, s, 1.0), (on2, total - s, -1.0)):
                if mask.any():
                    u = solve_increasing(ramp_distance, ramp_speed, target[mask], tr, total)
                    u = np.where(target[mask] >= d1, tr, u)
                    out[mask] = u if sign > 0 else d - u
        if self.v_low > 0:
            out = np.where(flat, tr + (s - d1) / self.v_low, out)
        return out.reshape(shape)
