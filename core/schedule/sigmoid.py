"""Sigmoid deformation curve (paper section 6, Eq. 22-25; SPEC.md sections 7 and 8) and speed stages.

Units: mm, ms, mm/ms, mm/ms^2 (a_max from mm/s^2 is divided by 1e6 by the caller).

Eq. 22: V(t) = K_V / (1 + e^(K_a (t - K_T))) + K on [0, 2 K_T], mirrored on [2 K_T, 4 K_T], with
K = K_V e^(-K_a K_T) / (1 + e^(-K_a K_T)) = K_V sigma(-a), a = K_a K_T. So V(0) = V(4 K_T) = K_V and
V(2 K_T) = 2 K. The logistic part is point-symmetric about t = K_T, hence the exact displacement
L = 2 K_T (K_V + 2 K) and the closed form K = (L / (2 K_T) - K_V) / 2, K_a = ln((K_V - K) / K) / K_T,
valid for L / (4 K_V) < K_T < L / (2 K_V): the mean speed lies strictly between K_V / 2 and K_V.

Findings (tested in tests/core/schedule/test_sigmoid.py):
- Eq. 23 as printed gives antiderivatives without their constants: the first branch is
  -(K_V/K_a) ln(1 + e^(K_a K_T)) at t = 0, not 0, and the two branches do not join at 2 K_T (they
  differ by 2 (K_V/K_a) ln(1 + e^(-a))). `SigmoidStage.distance` adds the constants (see there).
- Eq. 24 does not vanish at the true K_a (nor does its root give the length L); the consistent
  equation is 2 K_T K_V (1 + 2 sigma(-K_a K_T)) = L, whose root is the closed form above.
- At a fixed length the peak acceleration K_V K_a / 4 (Eq. 25) grows with the duration: with
  u = K_V duration / L in (1, 2), K_V K_a / 4 = (K_V^2 / L) f(u), f(u) = ln((3u - 2) / (2 - u)) / u,
  and f' > 0 (u^2 f' = 4u / ((3u - 2)(2 - u)) - ln((3u - 2) / (2 - u)), whose minimum, at u = 4/3,
  is 4 - ln 3 > 0). A longer duration means a deeper dip, so the paper's remedy ("increase the
  variable speed time") lowers the acceleration only if the stage is lengthened in space too (at a
  fixed ratio u the peak scales as 1 / length). `max_sigmoid_duration` gives the binding bound.

`speed_stage` is the schedule's single entry point: the paper's stage where it suffices, else the
ramp + plateau / dwell extension of core.schedule.profiles, or a PlanningError that says what to change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np
from scipy.special import expit

from core.errors import PlanningError
from core.schedule.laws import rows, sigmoid_distance, sigmoid_speed
from core.schedule.profiles import (
    LogisticRamp,
    PlateauStage,
    SepticRamp,
    logistic_jerk_shape,
    solve_increasing,
)
from core.util.spline import find_root

PROFILES = ("sigmoid", "smooth")
#: steepness range of the logistic ramps of a sigmoid dwell (the paper's curve cannot reach 0): the
#: steepest a <= A_CAP within a_max (A_CAP = 6: the acceleration at the ramp ends is 1% of its peak)
A_MIN, A_CAP = 1.0, 6.0
_REL = 1e-12  # |v0 duration - length| below this (relative): a constant-speed stage


class Stage(Protocol):
    """What every speed stage offers (SigmoidStage, PlateauStage). t in ms, s in mm, (k,) arrays."""

    @property
    def kind(self) -> str: ...
    @property
    def duration(self) -> float: ...
    @property
    def length(self) -> float: ...
    @property
    def peak_accel(self) -> float: ...
    @property
    def peak_jerk(self) -> float: ...
    @property
    def v_low(self) -> float: ...
    def speed(self, t: np.ndarray) -> np.ndarray: ...
    def distance(self, t: np.ndarray) -> np.ndarray: ...
    def accel(self, t: np.ndarray) -> np.ndarray: ...
    def time_at_distance(self, s: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class SigmoidStage:
    """The paper's sigmoid deformation curve (Eq. 22), exactly.

    K_V : mm/ms, entry and exit speed; K_T : ms, a quarter of the duration; K_a : 1/ms, > 0;
    K : mm/ms, floor constant, = K_V / (1 + e^(K_a K_T)) (checked to 1e-9). Methods are vectorised
    over t (ms) or s (mm); outside [0, 4 K_T] the cutter runs on at K_V. At t = 2 K_T the second
    half's value is used (right-hand); the acceleration jumps at 0, 2 K_T and 4 K_T (accel_jumps).
    """

    K_V: float
    K_T: float
    K_a: float
    K: float
    kind: ClassVar[str] = "sigmoid"

    def __post_init__(self) -> None:
        if not (self.K_V > 0 and self.K_T > 0 and self.K_a > 0 and self.K > 0):
            raise PlanningError(f"sigmoid stage: K_V, K_T, K_a, K must be > 0, got {self}")
        k = self.K_V * float(expit(-self.K_a * self.K_T))
        if abs(k - self.K) > 1e-9 * self.K_V:
            raise PlanningError(
                f"sigmoid stage: K = {self.K!r} breaks Eq. 22 (K_V e^-a / (1 + e^-a) = {k!r})")

    @classmethod
    def from_length(cls, length: float, v0: float, duration: float) -> SigmoidStage:
        """length mm, v0 = K_V mm/ms, duration = 4 K_T ms -> the stage with that exact displacement.

        K = (L / (2 K_T) - K_V) / 2, K_a = ln((K_V - K) / K) / K_T (as log1p((K_V - 2K) / K) / K_T).
        Raises PlanningError unless L / (4 K_V) < K_T < L / (2 K_V), naming the broken bound.
        """
        length, v0, duration = (_positive(n, x) for n, x in (("length", length), ("v0", v0),
                                                               ("duration", duration)))
        k_t, lo, hi = duration / 4, length / (4 * v0), length / (2 * v0)
        span = f"the admissible durations 4 K_T are ({4 * lo:.9g}, {4 * hi:.9g}) ms"
        if not k_t > lo:
            raise PlanningError(
                f"sigmoid stage: K_T = {k_t:.9g} ms is not above L / (4 K_V) = {lo:.9g} ms: covering "
                f"{length:.9g} mm in {duration:.9g} ms needs a mean speed >= K_V = {v0:.9g} mm/ms; {span}")
        if not k_t < hi:
            raise PlanningError(
                f"sigmoid stage: K_T = {k_t:.9g} ms is not below L / (2 K_V) = {hi:.9g} ms: Eq. 22 can at "
                f"most halve the mean speed; {span} (speed_stage extends it with a plateau or dwell)")
        k = (length / (2 * k_t) - v0) / 2
        drop = (4 * v0 * k_t - length) / (2 * k_t)  # K_V - 2 K, without cancellation
        return cls(v0, k_t, float(np.log1p(drop / k)) / k_t, k)

    @property
    def duration(self) -> float:
        """ms, 4 K_T."""
        return 4 * self.K_T

    @property
    def length(self) -> float:
        """mm, 2 K_T (K_V + 2 K)."""
        return 2 * self.K_T * (self.K_V + 2 * self.K)

    @property
    def v_low(self) -> float:
        """mm/ms, the minimum speed 2 K at t = 2 K_T."""
        return 2 * self.K

    @property
    def peak_accel(self) -> float:
        """mm/ms^2, K_V K_a / 4 (Eq. 25), at t = K_T and 3 K_T."""
        return self.K_V * self.K_a / 4

    @property
    def peak_smooth_jerk(self) -> float:
        """mm/ms^3, max |dA/dt| away from the jumps: K_a^2 K_V / (6 sqrt 3) if a >= ln(2 + sqrt 3)."""
        return self.K_a**2 * self.K_V * logistic_jerk_shape(self.K_a * self.K_T)

    @property
    def peak_jerk(self) -> float:
        """mm/ms^3: infinite, the acceleration jumps at 0, 2 K_T and 4 K_T."""
        return float("inf")

    @property
    def accel_jumps(self) -> tuple[tuple[float, float], ...]:
        """((time ms, signed jump mm/ms^2), ...): -j at 0, +2j at 2 K_T, -j at 4 K_T,
        j = K_a K_V sigma(a) sigma(-a) = K_a K (K_V - K) / K_V."""
        j = self.K_a * self.K * (self.K_V - self.K) / self.K_V
        return ((0.0, -j), (2 * self.K_T, 2 * j), (4 * self.K_T, -j))

    def as_plateau(self) -> PlateauStage:
        """The same curve as a PlateauStage (tied logistic ramps of 2 K_T, no plateau)."""
        return PlateauStage(self.K_V, 2 * self.K, 2 * self.K_T, 0.0, LogisticRamp(self.K_a * self.K_T))

    def _halves(self, t: np.ndarray):
        d = self.duration
        return (t >= 0) & (t < 2 * self.K_T), (t >= 2 * self.K_T) & (t <= d), t < 0

    def _rows(self, n: int) -> np.ndarray:
        return rows((self.K_V, self.K_T, self.K_a, self.K, self.length, 0.0, 0.0), n)

    def speed(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms: Eq. 22 (core.schedule.laws.sigmoid_speed)."""
        t = np.asarray(t, float)
        inside = sigmoid_speed(self._rows(t.size), t.ravel()).reshape(t.shape)
        return np.where((t >= 0) & (t <= self.duration), inside, self.K_V)

    def _first_half_distance(self, t: np.ndarray) -> np.ndarray:
        """(k,) ms in [0, 2 K_T] -> (k,) mm: (K_V / K_a) [ln(1 + e^a) - ln(1 + e^(a - K_a t))] + K t."""
        t = np.asarray(t, float)
        return sigmoid_distance(self._rows(t.size), t.ravel()).reshape(t.shape)

    def distance(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm from the stage start (Eq. 23 with its constants,
        core.schedule.laws.sigmoid_distance).

        With I_1, I_2 the two branches of Eq. 23 as printed:
          t in [0, 2 K_T]:      D(t) = I_1(t) - I_1(0)
                                     = (K_V/K_a) [ln(1 + e^(K_a K_T)) - ln(1 + e^(-K_a (t - K_T)))] + K t
          t in [2 K_T, 4 K_T]:  D(t) = I_2(t) + K_V K_T - (K_V/K_a) ln(1 + e^(-K_a K_T))
                                     = L - D(4 K_T - t)   (by symmetry; evaluated so)
        D(0) = 0, D(2 K_T) = L / 2, D(4 K_T) = L = 2 K_T (K_V + 2 K). Outside: on at K_V.
        """
        t = np.asarray(t, float)
        d, total = self.duration, self.length
        tc = np.clip(t, 0.0, d)
        inside = sigmoid_distance(self._rows(tc.size), tc.ravel()).reshape(t.shape)
        return np.where(t < 0, self.K_V * t, np.where(t > d, total + self.K_V * (t - d), inside))

    def accel(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms^2.

        -K_a K_V sigma'(K_a (t - K_T)) on the first half, +K_a K_V sigma'(K_a (t - 3 K_T)) on the second.
        """
        t = np.asarray(t, float)
        h1, h2, _ = self._halves(t)
        s1, s2 = expit(self.K_a * (t - self.K_T)), expit(self.K_a * (t - 3 * self.K_T))
        c = self.K_a * self.K_V
        return np.select([h1, h2], [-c * s1 * (1 - s1), c * s2 * (1 - s2)], 0.0)

    def jerk(self, t: np.ndarray) -> np.ndarray:
        """(k,) float, ms -> (k,) float, mm/ms^3: -+K_a^2 K_V sigma''(x) inside, +-inf at the jumps."""
        t = np.asarray(t, float)
        h1, h2, _ = self._halves(t)
        s1, s2 = expit(self.K_a * (t - self.K_T)), expit(self.K_a * (t - 3 * self.K_T))
        c = self.K_a**2 * self.K_V
        out = np.select([h1, h2], [-c * s1 * (1 - s1) * (1 - 2 * s1), c * s2 * (1 - s2) * (1 - 2 * s2)], 0.0)
        for tj, jump in self.accel_jumps:
            out = np.where(t == tj, np.copysign(np.inf, jump), out)
        return out

    def time_at_distance(self, s: np.ndarray) -> np.ndarray:
        """(k,) float, mm -> (k,) float, ms with distance(t) = s (monotone solve, to round-off)."""
        s = np.asarray(s, float)
        shape, s = s.shape, s.ravel()
        d, total, half = self.duration, self.length, 2 * self.K_T
        out = np.where(s < 0, s / self.K_V, d + (s - total) / self.K_V)
        inside = (s >= 0) & (s <= total)
        if inside.any():
            si = s[inside]
            first = si <= total / 2
            target = np.where(first, si, total - si)
            u = solve_increasing(self._first_half_distance, self.speed, target, half, total)
            out[inside] = np.where(first, u, d - u)
        return out.reshape(shape)


def paper_eq24_residual(K_a: np.ndarray, L: float, K_V: float, K_T: float) -> np.ndarray:
    """(k,) float, 1/ms -> (k,) float, mm: the left side of the paper's printed Eq. 24,

    2 K_V ln(1 + e^(K_a K_T)) - (0.5 L + K_V K_T) K_a + 2 K_V K_T / (1 + e^(K_a K_T)).

    Finding: it does NOT vanish at the K_a of the stage that covers L (SigmoidStage.from_length),
    and its own root gives a stage of another length; use `exact_length_residual`.
    """
    a = np.asarray(K_a, float) * K_T
    return 2 * K_V * np.logaddexp(0.0, a) - (0.5 * L + K_V * K_T) * np.asarray(K_a, float) \
        + 2 * K_V * K_T * expit(-a)


def exact_length_residual(K_a: np.ndarray, L: float, K_V: float, K_T: float) -> np.ndarray:
    """(k,) float, 1/ms -> (k,) float, mm: 2 K_T K_V (1 + 2 / (1 + e^(K_a K_T))) - L, the consistent
    form of Eq. 24 (Eq. 22 integrated over [0, 4 K_T] minus L). Its root is the closed-form K_a."""
    return 2 * K_T * K_V * (1 + 2 * expit(-np.asarray(K_a, float) * K_T)) - L


def sigmoid_peak_accel(length: np.ndarray, v0: np.ndarray, duration: np.ndarray) -> np.ndarray:
    """(k,) mm, mm/ms, ms -> (k,) float, mm/ms^2: K_V K_a / 4 of the paper's stage (Eq. 25).

    = (v0 / duration) ln((3u - 2) / (2 - u)), u = v0 duration / length; nan outside 1 < u < 2.
    """
    length, v0, duration = (np.asarray(x, float) for x in (length, v0, duration))
    u = v0 * duration / length
    ok = (u > 1) & (u < 2)
    uu = np.where(ok, u, 1.5)
    return np.where(ok, v0 / duration * np.log1p(4 * (uu - 1) / (2 - uu)), np.nan)


def max_sigmoid_duration(length: float, v0: float, a_max: float) -> float:
    """mm, mm/ms, mm/ms^2 -> ms: the longest duration whose paper's stage keeps K_V K_a / 4 <= a_max.

    The peak grows with the duration (module docstring), so every duration in
    (length / v0, max_sigmoid_duration] is admissible and within a_max, and none above it.
    Solved for eps = u - 1 in [0, 1) by Brent's method.
    """
    length, v0, a_max = _positive("length", length), _positive("v0", v0), _positive("a_max", a_max)
    c = a_max * length / v0**2

    def g(e: float) -> float:
        return float(np.log1p(4 * e / (1 - e))) - c * (1 + e)

    hi = 1 - 1e-12
    e = hi if g(hi) <= 0 else find_root(g, 0.0, hi, xtol=1e-15)
    return (1 + e) * length / v0


def _positive(name: str, x: float) -> float:
    x = float(x)
    if not (np.isfinite(x) and x > 0):
        raise PlanningError(f"speed stage: {name} must be a positive finite number, got {x!r}")
    return x


def _gentlest_ramp(u: float) -> float:
    """u = v0 duration / length > 1 -> theta = ramp_time v0 / length minimising the peak of the tied
    sigmoid ramps, a / (2 theta), a = log1p(2 (u - 1) / (1 - theta)), over 0 < theta <= min(u/2, 1).

    With k = 2 (u - 1) and f(theta) = log1p(k / (1 - theta)) the peak f / (2 theta) has the
    derivative's sign of h(theta) = theta f'(theta) - f(theta), f' = k / ((1 - theta)(1 - theta + k)):
    h < 0 near 0 and h increases (h' = theta f'' > 0, f convex), so the minimum is the root of h, or
    the upper bound when h stays negative there."""
    top = min(u / 2, 1 - 1e-9)
    k = 2 * (u - 1)

    def h(th: float) -> float:
        return th * k / ((1 - th) * (1 - th + k)) - float(np.log1p(k / (1 - th)))

    lo = top * 1e-6
    if h(top) <= 0:
        return top
    if h(lo) >= 0:
        return lo
    return find_root(h, lo, top, xtol=1e-13 * top)


def _dwell_steepness(c: float) -> float | None:
    """c = a_max length / v0^2 -> the steepest logistic a in [A_MIN, A_CAP] with (a/2)/tanh(a/2) <= c."""
    def g(a: float) -> float:
        return a / 2 / np.tanh(a / 2) - c
    if g(A_CAP) <= 0:
        return A_CAP
    if g(A_MIN) > 0:
        return None
    return find_root(g, A_MIN, A_CAP, xtol=1e-14)


def _candidates(length: float, v0: float, duration: float, a_max: float, profile: str):
    """Yield the stages to try, most preferred first (see speed_stage)."""
    u = v0 * duration / length
    ramp = _gentlest_ramp(u) * length / v0
    if profile == "sigmoid":
        if u < 2:
            try:
                paper = SigmoidStage.from_length(length, v0, duration)
            except PlanningError:  # u within round-off of 2
                paper = None
            if paper is not None:
                yield paper
        yield PlateauStage.from_ramp_time(length, v0, duration, min(ramp, duration / 2))
        if u >= 2 - _REL:
            a = _dwell_steepness(a_max * length / v0**2 * (1 - _REL))
            ramp = min(length / v0, duration / 2)
            yield PlateauStage(v0, 0.0, ramp, duration - 2 * ramp, LogisticRamp(a or A_MIN))
        return
    shape = SepticRamp()
    if u <= 2:  # the dip over the whole duration is the gentlest smooth stage here
        yield PlateauStage.from_ramp_time(length, v0, duration, duration / 2, shape)
        return
    yield PlateauStage.from_ramp_time(length, v0, duration, ramp, shape)
    q = shape.max_slope * (v0 * duration - length) / (a_max * (1 - _REL))
    disc = duration**2 - 4 * q
    if disc > 0:
        ramp = 2 * q / (duration + np.sqrt(disc))  # the shortest ramp within a_max
        if ramp < length / v0 * (1 - _REL):
            yield PlateauStage.from_ramp_time(length, v0, duration, ramp, shape)
            return
    yield PlateauStage(v0, 0.0, length / v0, max(duration - 2 * length / v0, 0.0), shape)


def _plan(length: float, v0: float, duration: float, a_max: float, profile: str):
    """Checked inputs -> (the first candidate within a_max or None, the candidates that failed)."""
    u = v0 * duration / length
    if u <= 1 + _REL:
        return PlateauStage(length / duration, length / duration, 0.0, duration, SepticRamp()), []
    tried: list = []
    for stage in _candidates(length, v0, duration, a_max, profile):
        if stage.peak_accel <= a_max:
            return stage, tried
        tried.append(stage)
    return None, tried


def speed_stage(length: float, v0: float, duration: float, a_max: float, profile: str = "sigmoid") -> Stage:
    """Cover `length` mm in `duration` ms, entering and leaving at v0 mm/ms, with |accel| <= a_max mm/ms^2.

    profile "sigmoid": the paper's SigmoidStage (kind "sigmoid") when 1 < u < 2 (u = v0 duration /
    length) and its peak K_V K_a / 4 <= a_max; else tied-logistic ramps (exact halves of Eq. 22) and
    a plateau, with the ramp time that minimises the peak acceleration ("sigmoid+plateau"); else,
    for u >= 2, logistic ramps down to a dwell at v = 0 ("sigmoid+dwell", steepest a <= A_CAP
    within a_max). profile "smooth": septic ramps (finite jerk) over the same waypoints: the full
    dip for u <= 2 ("smooth"), for u > 2 the sigmoid's plateau waypoints, ramps lengthened (lower
    plateau) only as a_max requires, down to a dwell ("smooth+plateau", "smooth+dwell").
    u = 1 (to 1e-12): a constant-speed stage (kind "constant", speed length / duration).
    Never fails for u >= 1 if a_max >= 1.455 v0^2 / length (sigmoid; the best plateau at u = 2) or
    a_max >= 35/16 v0^2 / length (smooth; its dwell).

    Raises PlanningError if u < 1 (faster than v0 on average: never needed by the schedule), on
    bad inputs, or when no stage keeps the peak acceleration <= a_max; the message gives the
    remedy (min_duration when a longer duration helps, else a longer stage or a lower feed).
    """
    length, v0 = _positive("length", length), _positive("v0", v0)
    duration, a_max = _positive("duration", duration), _positive("a_max", a_max)
    if profile not in PROFILES:
        raise PlanningError(f"speed stage: profile must be one of {PROFILES}, got {profile!r}")
    u = v0 * duration / length
    if u < 1 - _REL:
        raise PlanningError(
            f"speed stage: {length:.9g} mm in {duration:.9g} ms needs a mean speed of "
            f"{length / duration:.9g} mm/ms, above the entry speed v0 = {v0:.9g} mm/ms; a stage only slows "
            f"down: give it at least {length / v0:.9g} ms")
    stage, tried = _plan(length, v0, duration, a_max, profile)
    if stage is not None:
        return stage
    p = min(s.peak_accel for s in tried)
    dwell = 2 * length / v0
    hint = (f"a dwell works from {dwell:.9g} ms on (min_duration)"
            if u < 2 - _REL and _plan(length, v0, dwell, a_max, profile)[0] is not None else
            "a longer duration does not help (at a fixed length the peak grows with the duration); "
            f"lengthen the stage to >= {length * p / a_max:.6g} mm at the same speed ratio, lower the feed "
            f"below {v0 * np.sqrt(a_max / p) * 6e4:.6g} mm/min, or raise a_max")
    raise PlanningError(
        f"speed stage ({profile}): {length:.6g} mm in {duration:.6g} ms from {v0 * 6e4:.6g} mm/min (mean "
        f"{100 / u:.4g}% of the feed) needs a peak acceleration of {p * 1e6:.6g} mm/s^2 at least "
        f"({', '.join(s.kind for s in tried)}), above a_max = {a_max * 1e6:.6g} mm/s^2: {hint}")


def min_duration(length: float, v0: float, a_max: float, at_least: float = 0.0,
                 profile: str = "sigmoid") -> float:
    """mm, mm/ms, mm/ms^2, ms -> ms: the shortest duration >= at_least for which speed_stage succeeds.

    The paper's remedy for Eq. 25 is a longer stage; at a fixed length the peak acceleration of the
    sigmoid (and of the best plateau) grows with the duration instead, so the feasible durations are
    (length / v0, D_1] and, when a dwell is within a_max, every duration >= 2 length / v0 (the dwell's
    peak does not depend on the duration). Hence: at_least itself, else 2 length / v0, else a
    PlanningError saying to lengthen the stage in space (the peak scales as 1 / length at a fixed
    speed ratio), lower the feed or raise a_max. at_least <= length / v0 gives length / v0 (constant).
    """
    length, v0, a_max = _positive("length", length), _positive("v0", v0), _positive("a_max", a_max)
    start = max(float(at_least), length / v0)
    if not np.isfinite(start):
        raise PlanningError(f"speed stage: at_least must be a finite duration in ms, got {at_least!r}")
    if profile not in PROFILES:
        raise PlanningError(f"speed stage: profile must be one of {PROFILES}, got {profile!r}")
    for duration in (start, 2 * length / v0):
        if duration >= start and _plan(length, v0, duration, a_max, profile)[0] is not None:
            return duration
    speed_stage(length, v0, start, a_max, profile)  # raises with the remedy
    raise AssertionError("unreachable")  # pragma: no cover
