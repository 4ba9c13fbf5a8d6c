"""Sigmoid deformation curve (Eq. 22-25) and the speed stages built on it (core.schedule.sigmoid, speed_profiles)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from core.errors import PlanningError
from core.schedule.profiles import LogisticRamp, PlateauStage, SepticRamp
from core.schedule.sigmoid import (
    SigmoidStage,
    exact_length_residual,
    max_sigmoid_duration,
    min_duration,
    paper_eq24_residual,
    sigmoid_peak_accel,
    speed_stage,
)

V0 = 2000 / 6e4  # 2000 mm/min in mm/ms
L = 20.0  # mm
A_MAX = 500 / 1e6  # 500 mm/s^2 in mm/ms^2
UNIT = V0**2 / L  # the natural acceleration scale, mm/ms^2


def paper(u, length=L, v0=V0):
    return SigmoidStage.from_length(length, v0, u * length / v0)


def integrate(stage, t):
    """Displacement by adaptive quadrature of the speed, split at the stage's corners."""
    corners = [c for c in (0.5 * stage.duration, getattr(stage, "ramp_time", 0.0),
                           stage.duration - getattr(stage, "ramp_time", 0.0)) if 0 < c < t]
    return quad(lambda x: float(stage.speed(np.array([x]))[0]), 0.0, t, points=corners or None,
                limit=400, epsabs=0.0, epsrel=1e-13)[0]


def fine(stage, n=200_001):
    t = np.linspace(0.0, stage.duration, n)
    return t, stage.speed(t)


STAGES = {
    "sigmoid": lambda: speed_stage(L, V0, 1.6 * L / V0, A_MAX),
    "sigmoid+plateau": lambda: speed_stage(L, V0, 3.5 * L / V0, A_MAX),
    "sigmoid+dwell": lambda: speed_stage(L, V0, 3.5 * L / V0, 1.8 * UNIT),
    "smooth": lambda: speed_stage(L, V0, 1.6 * L / V0, A_MAX, "smooth"),
    "smooth+plateau": lambda: speed_stage(L, V0, 3.5 * L / V0, A_MAX, "smooth"),
    "smooth+dwell": lambda: speed_stage(L, V0, 3.5 * L / V0, 35 / 16 * UNIT * (1 + 1e-14), "smooth"),
}


@pytest.mark.parametrize("kind", STAGES)
def test_speed_stage_kinds(kind):
    assert STAGES[kind]().kind == kind


# --- Eq. 22 -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("u", [1.05, 1.3, 1.6, 1.9, 1.999])
def test_eq22_entry_exit_floor_and_continuity(u):
    s = paper(u)
    kt = s.K_T
    v = s.speed(np.array([0.0, 2 * kt, 4 * kt]))
    assert v[0] == pytest.approx(s.K_V, rel=1e-14) and v[2] == pytest.approx(s.K_V, rel=1e-14)
    assert v[1] == pytest.approx(2 * s.K, rel=1e-12)
    # both halves of Eq. 22 give 2K at 2 K_T: V is continuous there
    left = s.K_V / (1 + np.exp(s.K_a * (2 * kt - kt))) + s.K
    right = s.K_V / (1 + np.exp(s.K_a * (3 * kt - 2 * kt))) + s.K
    assert left == pytest.approx(right, rel=1e-14) == pytest.approx(v[1], rel=1e-12)
    eps = 1e-9 * s.duration
    assert s.speed(np.array([2 * kt - eps]))[0] == pytest.approx(v[1], rel=1e-6, abs=1e-12)
    # the minimum of the whole curve is 2K, at 2 K_T
    t, vv = fine(s)
    assert vv.min() >= 2 * s.K * (1 - 1e-12)
    assert abs(t[np.argmin(vv)] - 2 * kt) <= s.duration / 1e5
    # K as printed in Eq. 22
    a = s.K_a * kt
    assert s.K == pytest.approx(s.K_V * np.exp(-a) / (1 + np.exp(-a)), rel=1e-12)


# --- Eq. 23 and 24 ------------------------------------------------------------------------------------
@pytest.mark.parametrize("u", [1.01, 1.25, 1.5, 1.75, 1.99])
def test_closed_form_gives_exact_length_and_eq24_does_not(u):
    s = paper(u)
    assert s.length == pytest.approx(L, rel=1e-14)
    assert s.duration == pytest.approx(u * L / V0, rel=1e-15)
    assert exact_length_residual(s.K_a, L, s.K_V, s.K_T) == pytest.approx(0.0, abs=1e-12 * L)
    # the paper's printed Eq. 24 is not zero at the true K_a (SPEC.md section 8) ...
    r = paper_eq24_residual(s.K_a, L, s.K_V, s.K_T)
    assert abs(r) > 1e-3 * L
    # ... and where it is zero, the stage has another length
    from scipy.optimize import brentq

    ka = np.linspace(1e-4, 50, 20001) / s.K_T
    res = paper_eq24_residual(ka, L, s.K_V, s.K_T)
    flips = np.nonzero(np.sign(res[:-1]) != np.sign(res[1:]))[0]
    for i in flips:
        root = brentq(paper_eq24_residual, ka[i], ka[i + 1], args=(L, s.K_V, s.K_T))
        k = s.K_V / (1 + np.exp(root * s.K_T))
        assert abs(2 * s.K_T * (s.K_V + 2 * k) - L) > 1e-3 * L


def test_eq23_needs_constants_of_integration():
    s = paper(1.4)
    kv, ka, kt, k = s.K_V, s.K_a, s.K_T, s.K

    def i1(t):  # Eq. 23 first branch as printed
        return -kv / ka * np.log1p(np.exp(-ka * (t - kt))) + k * t

    def i2(t):  # Eq. 23 second branch as printed
        return kv / ka * np.log1p(np.exp(-ka * (3 * kt - t))) + k * t

    assert abs(i1(0.0)) > 1e-3 * L  # not a displacement from the start
    assert abs(i1(2 * kt) - i2(2 * kt)) > 1e-3 * L  # the branches do not join
    t1, t2 = np.linspace(0, 2 * kt, 7), np.linspace(2 * kt, 4 * kt, 7)
    np.testing.assert_allclose(s.distance(t1), i1(t1) - i1(0.0), rtol=1e-12, atol=1e-12 * L)
    c2 = kv * kt - kv / ka * np.log1p(np.exp(-ka * kt))
    np.testing.assert_allclose(s.distance(t2), i2(t2) + c2, rtol=1e-12, atol=1e-12 * L)


@pytest.mark.parametrize("kind", STAGES)
def test_displacement_matches_quadrature(kind):
    s = STAGES[kind]()
    assert s.distance(np.array([0.0]))[0] == 0.0
    assert s.distance(np.array([s.duration]))[0] == pytest.approx(L, rel=1e-12)
    assert s.length == pytest.approx(L, rel=1e-12)
    for t in np.linspace(0, s.duration, 9)[1:]:
        assert s.distance(np.array([t]))[0] == pytest.approx(integrate(s, t), rel=1e-9)


@pytest.mark.parametrize("u", [1.0 + 1e-9, 1.0 + 1e-6, 2.0 - 1e-6])
def test_sigmoid_near_the_bounds_stays_exact(u):
    s = paper(u)
    assert s.distance(np.array([s.duration]))[0] == pytest.approx(L, rel=1e-12)
    assert s.distance(np.array([s.duration / 3]))[0] == pytest.approx(integrate(s, s.duration / 3), rel=1e-9)


# --- Eq. 25: acceleration and jerk ----------------------------------------------------------------------
@pytest.mark.parametrize("u", [1.1, 1.5, 1.9])
def test_peak_accel_is_kv_ka_over_4(u):
    s = paper(u)
    t, v = fine(s)
    num = np.abs(np.diff(v) / np.diff(t)).max()
    assert s.peak_accel == s.K_V * s.K_a / 4
    assert num == pytest.approx(s.peak_accel, rel=1e-6)
    assert s.accel(np.array([s.K_T]))[0] == pytest.approx(-s.peak_accel, rel=1e-14)
    assert s.accel(np.array([3 * s.K_T]))[0] == pytest.approx(s.peak_accel, rel=1e-14)
    assert sigmoid_peak_accel(L, V0, s.duration) == pytest.approx(s.peak_accel, rel=1e-12)


@pytest.mark.parametrize("kind", STAGES)
def test_accel_and_jerk_are_the_derivatives(kind):
    s = STAGES[kind]()
    t = np.linspace(0, s.duration, 4001)[1:-1]
    t = t[np.min(np.abs(t[:, None] - np.array([jt for jt, _ in getattr(s, "accel_jumps", ())] + [-1.0])),
                 axis=1) > 1e-4 * s.duration]
    h = 1e-6 * s.duration
    dv = (s.speed(t + h) - s.speed(t - h)) / (2 * h)
    np.testing.assert_allclose(s.accel(t), dv, atol=1e-6 * s.peak_accel)
    da = (s.accel(t + h) - s.accel(t - h)) / (2 * h)
    smooth_peak = getattr(s, "peak_smooth_jerk", s.peak_jerk)
    np.testing.assert_allclose(s.jerk(t), da, atol=1e-5 * smooth_peak)
    assert np.abs(s.jerk(t)).max() <= smooth_peak * (1 + 1e-9)


def test_sigmoid_accel_jumps_report_infinite_jerk():
    s = paper(1.5)
    kt = s.K_T
    jumps = dict(s.accel_jumps)
    j = s.K_a * s.K_V / (1 + np.exp(s.K_a * kt)) / (1 + np.exp(-s.K_a * kt))
    assert jumps[0.0] == pytest.approx(-j) and jumps[2 * kt] == pytest.approx(2 * j)
    assert jumps[4 * kt] == pytest.approx(-j)
    assert s.accel(np.array([0.0]))[0] == pytest.approx(-j, rel=1e-12)
    h = 1e-9 * s.duration
    step = s.accel(np.array([2 * kt + h]))[0] - s.accel(np.array([2 * kt - h]))[0]
    assert step == pytest.approx(2 * j, rel=1e-6)
    jerk = s.jerk(np.array([0.0, 2 * kt, 4 * kt]))
    assert list(jerk) == [-np.inf, np.inf, -np.inf]
    assert s.peak_jerk == np.inf and np.isfinite(s.peak_smooth_jerk)
    if s.K_a * kt >= np.log(2 + np.sqrt(3)):
        assert s.peak_smooth_jerk == pytest.approx(s.K_a**2 * s.K_V / (6 * np.sqrt(3)), rel=1e-12)


def test_peak_accel_grows_with_duration_at_fixed_length():
    d = np.linspace(1.0001, 1.9999, 2000) * L / V0
    p = sigmoid_peak_accel(L, V0, d)
    assert np.all(np.diff(p) > 0)
    assert np.isnan(sigmoid_peak_accel(L, V0, np.array([0.9, 2.0]) * L / V0)).all()
    # at a fixed speed ratio it scales as 1 / length: the remedy is a longer stage in space
    assert sigmoid_peak_accel(2 * L, V0, 2 * d) == pytest.approx(p / 2, rel=1e-12)


@pytest.mark.parametrize("c", [0.01, 0.5, 1.0, 3.0, 40.0])
def test_max_sigmoid_duration(c):
    a_max = c * UNIT
    d = max_sigmoid_duration(L, V0, a_max)
    assert L / V0 < d < 2 * L / V0
    if c < 20:
        assert SigmoidStage.from_length(L, V0, d).peak_accel == pytest.approx(a_max, rel=1e-9)
        assert SigmoidStage.from_length(L, V0, d * (1 + 1e-6)).peak_accel > a_max
    assert SigmoidStage.from_length(L, V0, d * (1 - 1e-9)).peak_accel <= a_max


# --- the extension --------------------------------------------------------------------------------------
def test_plateau_ramps_are_halves_of_eq22():
    s = speed_stage(L, V0, 3.5 * L / V0, A_MAX)
    assert s.kind == "sigmoid+plateau" and 0 < s.v_low < V0 / 2 and s.plateau_time > 0
    assert s.peak_accel <= A_MAX
    half = SigmoidStage(V0, s.ramp_time / 2, 2 * np.log((2 * V0 - s.v_low) / s.v_low) / s.ramp_time,
                        s.v_low / 2)
    t = np.linspace(0, s.ramp_time, 101)[:-1]
    np.testing.assert_allclose(s.speed(t), half.speed(t), rtol=1e-12)
    np.testing.assert_allclose(s.speed(s.duration - t), half.speed(half.duration - t), rtol=1e-12)
    np.testing.assert_allclose(s.distance(t), half.distance(t), rtol=1e-12, atol=1e-14)
    assert s.speed(np.array([s.ramp_time + s.plateau_time / 2]))[0] == s.v_low


def test_paper_stage_equals_its_plateau_form():
    s = paper(1.7)
    p = s.as_plateau()
    t = np.linspace(-10, s.duration + 10, 1001)
    for f in ("speed", "distance", "accel"):
        np.testing.assert_allclose(getattr(s, f)(t), getattr(p, f)(t), rtol=1e-11, atol=1e-15)
    assert p.peak_accel == pytest.approx(s.peak_accel, rel=1e-12)
    np.testing.assert_allclose(np.array(p.accel_jumps), np.array(s.accel_jumps), rtol=1e-12)


@pytest.mark.parametrize("profile", ["sigmoid", "smooth"])
def test_dwell_stops_and_covers_the_exact_length(profile):
    s = STAGES[f"{profile}+dwell"]()
    assert s.v_low == 0.0 and s.plateau_time > 0 and s.ramp_time == pytest.approx(L / V0)
    assert s.duration == pytest.approx(3.5 * L / V0, rel=1e-14)
    assert s.distance(np.array([s.duration]))[0] == pytest.approx(L, rel=1e-12)
    mid = s.ramp_time + np.linspace(0, s.plateau_time, 11)
    assert np.all(s.speed(mid) == 0) and np.allclose(s.distance(mid), L / 2, rtol=1e-14)
    t, v = fine(s)
    assert np.abs(np.diff(v) / np.diff(t)).max() <= s.peak_accel * (1 + 1e-9)
    assert s.peak_accel <= (1.8 if profile == "sigmoid" else 2.19) * UNIT
    # the dwell position maps to the start of the dwell
    assert s.time_at_distance(np.array([L / 2]))[0] == pytest.approx(s.ramp_time, rel=1e-12)


def test_smooth_profile_has_continuous_accel_and_finite_jerk():
    for s in (STAGES["smooth"](), STAGES["smooth+plateau"](), STAGES["smooth+dwell"]()):
        assert s.accel_jumps == () and np.isfinite(s.peak_jerk)
        t = np.linspace(-1.0, s.duration + 1.0, 400_001)
        a, j = s.accel(t), s.jerk(t)
        dt = t[1] - t[0]
        assert np.abs(np.diff(a)).max() <= s.peak_jerk * dt * (1 + 1e-6)  # no jump anywhere
        assert np.abs(np.diff(j)).max() <= 1e-3 * s.peak_jerk  # the jerk is continuous too
        assert np.abs(j).max() == pytest.approx(s.peak_jerk, rel=1e-4)
        assert np.abs(a).max() == pytest.approx(s.peak_accel, rel=1e-6)
        assert s.accel(np.array([0.0, s.duration])) == pytest.approx([0.0, 0.0], abs=1e-18)


def test_smooth_waypoints_follow_the_sigmoid():
    sig, smo = STAGES["sigmoid+plateau"](), STAGES["smooth+plateau"]()
    assert (smo.ramp_time, smo.v_low) == pytest.approx((sig.ramp_time, sig.v_low), rel=1e-12)
    tight = speed_stage(L, V0, 3.5 * L / V0, 0.95 * smo.peak_accel, "smooth")
    assert tight.kind == "smooth+plateau" and tight.ramp_time > smo.ramp_time and tight.v_low < smo.v_low
    assert tight.peak_accel == pytest.approx(0.95 * smo.peak_accel, rel=1e-9)
    assert tight.peak_accel <= 0.95 * smo.peak_accel


def test_ramp_shapes():
    tau = np.linspace(0, 1, 100_001)
    for shape in (LogisticRamp(0.3), LogisticRamp(4.0), LogisticRamp(30.0), SepticRamp()):
        s = shape.step(tau)
        assert s[0] == pytest.approx(0, abs=1e-15) and s[-1] == pytest.approx(1, abs=1e-14)
        np.testing.assert_allclose(s + shape.step(1 - tau), 1.0, atol=1e-14)
        assert shape.integral(np.array([1.0]))[0] == pytest.approx(0.5, rel=1e-13)
        assert np.abs(shape.slope(tau)).max() == pytest.approx(shape.max_slope, rel=1e-9)
        assert np.abs(shape.curvature(tau)).max() == pytest.approx(shape.max_curvature, rel=1e-5)
        i = [quad(lambda x: float(shape.step(np.array([x]))[0]), 0, x, epsabs=0, epsrel=1e-13)[0]
             for x in (0.2, 0.5, 0.9)]
        np.testing.assert_allclose(shape.integral(np.array([0.2, 0.5, 0.9])), i, rtol=1e-11)


# --- inverse --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", STAGES)
def test_time_at_distance_inverts_distance(kind):
    s = STAGES[kind]()
    x = np.linspace(0, L, 2001)
    t = s.time_at_distance(x)
    assert np.all(np.diff(t) > 0)
    np.testing.assert_allclose(s.distance(t), x, rtol=0, atol=1e-12 * L)
    tt = np.linspace(0, s.duration, 2001)
    moving = s.speed(tt) > 1e-3 * V0
    np.testing.assert_allclose(s.time_at_distance(s.distance(tt))[moving], tt[moving], rtol=0,
                               atol=1e-9 * s.duration)
    # outside the stage the cutter runs on at v0; shapes are kept
    out = s.time_at_distance(np.array([[-1.0, L + 1.0]]))
    assert out.shape == (1, 2) and out[0] == pytest.approx([-1 / V0, s.duration + 1 / V0], rel=1e-12)


# --- errors and min_duration ----------------------------------------------------------------------------
def test_from_length_names_the_broken_bound():
    with pytest.raises(PlanningError, match=r"not above L / \(4 K_V\).*admissible durations"):
        SigmoidStage.from_length(L, V0, 0.9 * L / V0)
    with pytest.raises(PlanningError, match=r"not below L / \(2 K_V\).*at most halve"):
        SigmoidStage.from_length(L, V0, 2.5 * L / V0)
    with pytest.raises(PlanningError, match="breaks Eq. 22"):
        SigmoidStage(V0, 100.0, 0.01, 0.3 * V0)


@pytest.mark.parametrize("args, match", [
    ((L, V0, 0.8 * L / V0, A_MAX), "above the entry speed"),
    ((-1.0, V0, 1000.0, A_MAX), "length must be a positive"),
    ((L, 0.0, 1000.0, A_MAX), "v0 must be a positive"),
    ((L, V0, np.nan, A_MAX), "duration must be a positive"),
    ((L, V0, 1000.0, -1.0), "a_max must be a positive"),
])
def test_bad_inputs_raise(args, match):
    with pytest.raises(PlanningError, match=match):
        speed_stage(*args)


def test_bad_profile_raises():
    with pytest.raises(PlanningError, match="profile"):
        speed_stage(L, V0, 2 * L / V0, A_MAX, profile="trapezoid")


def test_constant_stage_at_the_lower_bound():
    s = speed_stage(L, V0, L / V0, A_MAX)
    assert s.kind == "constant" and s.peak_accel == 0.0
    assert s.distance(np.array([s.duration]))[0] == pytest.approx(L, rel=1e-15)
    assert min_duration(L, V0, A_MAX) == pytest.approx(L / V0)


def test_a_max_too_low_says_what_to_do():
    with pytest.raises(PlanningError, match=r"mm/s\^2.*lengthen the stage to >= .* mm"):
        speed_stage(L, V0, 3.5 * L / V0, 1.0 * UNIT)
    with pytest.raises(PlanningError, match="lengthen the stage"):
        min_duration(L, V0, 1.0 * UNIT, at_least=1.9 * L / V0)


def test_min_duration():
    # feasible as asked
    assert min_duration(L, V0, A_MAX, at_least=3.5 * L / V0) == 3.5 * L / V0
    # a_max between the dwell's and the best plateau's peak: u = 1.95 fails, the dwell from u = 2 works
    a_max = 1.2 * UNIT
    with pytest.raises(PlanningError, match="a dwell works from"):
        speed_stage(L, V0, 1.95 * L / V0, a_max)
    d = min_duration(L, V0, a_max, at_least=1.95 * L / V0)
    assert d == pytest.approx(2 * L / V0)
    assert speed_stage(L, V0, d, a_max).kind == "sigmoid+dwell"


# --- properties -----------------------------------------------------------------------------------------
@settings(max_examples=150, deadline=None)
@given(length=st.floats(0.5, 400.0), v0=st.floats(1e-3, 1.0), u=st.floats(1.0, 40.0),
       c=st.floats(0.05, 200.0), profile=st.sampled_from(["sigmoid", "smooth"]))
def test_speed_stage_properties(length, v0, u, c, profile):
    duration, a_max = u * length / v0, c * v0**2 / length
    try:
        s = speed_stage(length, v0, duration, a_max, profile)
    except PlanningError as e:
        assert "a_max" in str(e)
        # guaranteed feasible above these (best plateau at u = 2; smooth dwell)
        assert c < (1.4550 if profile == "sigmoid" else 35 / 16) * (1 + 1e-9)
        # a longer duration helps only by reaching the dwell (u >= 2): min_duration finds it
        if u >= 2 or u < 2 - 1e-9:
            longer = duration * (1.5 if u >= 2 else (1 + 2 / u) / 2)
            with pytest.raises(PlanningError):
                speed_stage(length, v0, longer, a_max, profile)
        try:
            d = min_duration(length, v0, a_max, at_least=duration, profile=profile)
        except PlanningError as e2:
            assert "lengthen the stage" in str(e2)
        else:
            assert u < 2 and d == 2 * length / v0 and "a dwell works" in str(e)
            assert speed_stage(length, v0, d, a_max, profile).kind.endswith("+dwell")
        return
    assert s.duration == pytest.approx(duration, rel=1e-12)
    assert s.distance(np.array([s.duration]))[0] == pytest.approx(length, rel=1e-12)
    assert s.peak_accel <= a_max
    paper_ok = 1 + 1e-12 < u < 2 and sigmoid_peak_accel(length, v0, duration) <= a_max * (1 - 1e-9)
    if profile == "sigmoid" and paper_ok:
        assert isinstance(s, SigmoidStage)
    assert isinstance(s, (SigmoidStage, PlateauStage))
    t = np.linspace(0, s.duration, 20_001)
    v, x = s.speed(t), s.distance(t)
    assert v.min() >= 0 and v.max() <= v0 * (1 + 1e-12)
    assert np.diff(x).min() >= -1e-14 * length
    assert np.abs(np.diff(v) / np.diff(t)).max() <= a_max * (1 + 1e-9)
    mid = 0.5 * (t[1:] + t[:-1])
    dt = t[1] - t[0]  # midpoint rule; its error at a kink of the speed is <= a_max dt^2 / 4
    np.testing.assert_allclose(np.diff(x), s.speed(mid) * dt, rtol=1e-6, atol=a_max * dt**2 + 1e-12 * length)
    q = np.linspace(0, length, 501)
    np.testing.assert_allclose(s.distance(s.time_at_distance(q)), q, rtol=0, atol=1e-9 * length)


def test_gentlest_ramp_is_the_minimum_of_the_peak():
    """The ramp share from the root of the peak's derivative against a dense grid of the peak itself
    (and the upper bound where the peak keeps falling)."""
    from core.schedule.sigmoid import _gentlest_ramp

    for u in (1.001, 1.2, 1.5, 1.9, 2.0, 2.6, 5.0, 40.0):
        top = min(u / 2, 1 - 1e-9)
        th = np.linspace(top * 1e-6, top, 200001)
        peak = np.log1p(2 * (u - 1) / (1 - th)) / (2 * th)
        got = _gentlest_ramp(u)
        best = th[np.argmin(peak)]
        assert abs(got - best) <= 2 * (th[1] - th[0]), (u, got, best)
        assert np.log1p(2 * (u - 1) / (1 - got)) / (2 * got) <= peak.min() * (1 + 1e-12)
