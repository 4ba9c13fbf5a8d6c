"""The feed override (core.machine.override): its scale against brute force and numerical integration, and
plans whose axis tables keep every speed and acceleration limit, checked on the tables themselves."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad

from core.blade.source import load_blade
from core.machine.model import AXES, load_machine, machine_to_toml
from core.machine.override import _cone, _durations, _inside
from core.machine.postprocess import AxisTable, check_limits
from core.paths.planning import plan_paths
from core.records import PlanParameters

from ..conftest import plan_on


def test_cone_is_the_largest_scale_below_the_caps_with_the_rate_bound():
    rng = np.random.default_rng(7)
    for _ in range(20):
        n = 60
        tau = np.cumsum(rng.uniform(0.01, 2.0, n))
        cap = rng.uniform(0.01, 1.3, n) ** 2
        rate = rng.uniform(0.001, 0.5, n - 1)
        s = _cone(cap, tau, rate)
        g = np.concatenate([[0.0], np.cumsum(rate * np.diff(tau))])
        # brute force: s_i^2 = min_j (min(cap_j, 1)^2 + |g_i - g_j|)
        brute = np.min(np.minimum(cap, 1.0)[None, :] ** 2 + np.abs(g[:, None] - g[None, :]), axis=1)
        np.testing.assert_allclose(s**2, brute, rtol=1e-12, atol=1e-13)
        assert (s <= np.minimum(cap, 1.0) + 1e-12).all()
        assert (np.abs(np.diff(s**2)) <= rate * np.diff(tau) + 1e-12).all()


def test_cone_keeps_its_digits_where_some_intervals_have_no_bound():
    """A tip at rest bounds nothing (rates of 1e300 and inf) and a schedule at its acceleration limit
    holds the scale (rate 0): the cone is still the brute-force one, small caps included (the
    integral of unbounded rates swamped s^2 and left scales of 1e-12 on the BladeX mesh)."""
    rng = np.random.default_rng(8)
    for _ in range(20):
        n = 80
        tau = np.cumsum(rng.uniform(1e-4, 2.0, n))
        cap = np.where(rng.random(n) < 0.2, 1e-3, rng.uniform(0.01, 1.0, n))
        rate = rng.uniform(0.001, 0.5, n - 1)
        rate[rng.random(n - 1) < 0.3] = 1e300
        rate[rng.random(n - 1) < 0.05] = np.inf
        rate[rng.random(n - 1) < 0.2] = 0.0
        s = _cone(cap, tau, rate)
        step = np.minimum(rate * np.diff(tau), 1.0)  # (s^2 cannot change by more than 1)
        brute = np.empty(n)
        for i in range(n):  # s_i^2 = min_j (cap_j^2 + the rate's integral between i and j)
            lo, hi = np.minimum(np.arange(n), i), np.maximum(np.arange(n), i)
            c = np.concatenate([[0.0], np.cumsum(step)])
            brute[i] = np.min(np.minimum(cap, 1.0) ** 2 + (c[hi] - c[lo]))
        np.testing.assert_allclose(s**2, np.maximum(brute, 1e-24), rtol=1e-9, atol=1e-14)


def test_durations_and_inside_against_numerical_integration():
    rng = np.random.default_rng(3)
    tau = np.cumsum(rng.uniform(0.1, 5.0, 30))
    s = rng.uniform(0.01, 1.0, 30)
    s[5] = s[4]  # a flat interval
    dur = _durations(tau, s)
    for i in range(len(tau) - 1):
        def rate(x, i=i):
            return s[i] + (s[i + 1] - s[i]) * (x - tau[i]) / (tau[i + 1] - tau[i])
        ref = quad(lambda x: 1.0 / rate(x), tau[i], tau[i + 1], epsabs=1e-13, epsrel=1e-12)[0]
        assert dur[i] == pytest.approx(ref, rel=1e-9)
        for frac in (0.25, 0.5, 0.9):
            at = _inside(tau, s, np.array([i]), np.array([frac * dur[i]]))[0]
            part = quad(lambda x: 1.0 / rate(x), tau[i], at, epsabs=1e-13, epsrel=1e-12)[0]
            assert part == pytest.approx(frac * ref, rel=1e-8)


def _slow_machine(factor: float):
    m = load_machine(None)
    limits = {name: dataclasses.replace(m.limits.axis(name),
                                        max_accel_mm_s2=m.limits.axis(name).max_accel_mm_s2 * factor)
              for name in AXES}
    return dataclasses.replace(m, limits=dataclasses.replace(m.limits, **limits))


@pytest.fixture(scope="module")
def override_runs(tmp_path_factory):
    blade = load_blade("sample")
    params = PlanParameters(dr=4.0)
    paths = plan_paths(blade, params)
    slow_toml = tmp_path_factory.mktemp("machine") / "slow.toml"
    slow_toml.write_text(machine_to_toml(_slow_machine(0.2)))
    normal = plan_on(paths, params=params, axes=True)
    slow = plan_on(paths, params=params, axes=True, machine=str(slow_toml))
    assert slow.machine.limits == _slow_machine(0.2).limits  # (the toml round trip keeps the slow limits)
    return normal, slow


def test_axis_tables_keep_speed_and_acceleration_limits(override_runs):
    for res in override_runs:
        m = res.machine
        assert not res.limit_findings, [str(f) for f in res.limit_findings[:5]]
        for side in ("left", "right"):
            tab = res.axes[side]
            t, v = tab.t, tab.velocities
            assert (np.diff(t) > 0).all() and np.diff(t).max() <= res.period * (1 + 1e-6) + 1e-6
            acc = np.abs(np.diff(v, axis=0)) / np.diff(t)[:, None] * 1e6
            for k, name in enumerate(AXES):
                lim = m.limits.axis(name)
                assert acc[:, k].max() <= lim.max_accel_mm_s2 * (1 + 1e-9)
                assert np.abs(v[:, k]).max() * 1000.0 <= lim.max_speed_mm_s * (1 + 1e-9)


def test_lower_acceleration_limits_slow_the_job_and_bind(override_runs):
    normal, slow = override_runs
    assert slow.timeline.t[-1] > normal.timeline.t[-1] * 1.01
    # the lower limit is used: somewhere an axis accelerates above the slow machine's limit in the
    # normal plan, and the slow plan keeps below it everywhere
    worst = max(float((np.abs(np.diff(normal.axes[s].velocities, axis=0)) / np.diff(normal.axes[s].t)[:, None]
                       * 1e6 / np.array([slow.machine.limits.axis(a).max_accel_mm_s2 for a in AXES])).max())
                for s in ("left", "right"))
    assert worst > 1.0
    # both plans are the same schedule on different clocks: the tip spacing's minimum differs only by
    # where the rows fall (they are not at the same instants)
    assert slow.figures["min_tip_spacing_mm"] == pytest.approx(normal.figures["min_tip_spacing_mm"], abs=1e-4)


def test_an_acceleration_jump_is_a_blocking_finding():
    m = load_machine(None)
    t = np.array([0.0, 10.0, 20.0, 30.0])
    values = np.zeros((4, 6))
    vel = np.zeros((4, 6))
    vel[2:, 1] = 0.01  # y jumps from 0 to 10 mm/s in 10 ms: 1000 mm/s^2 > 500
    found = check_limits(m, AxisTable("left", t, values, vel))
    assert [(f.axis, f.kind) for f in found] == [("y", "acceleration")]
    assert found[0].value == pytest.approx(1000.0) and found[0].t_ms == 10.0
    from core.records import ENFORCED_LIMITS

    assert "acceleration" in ENFORCED_LIMITS


def test_rows_are_the_motion_at_their_written_times(override_runs):
    """The written (rounded) times and the rows' schedule instants agree: the new-clock time between
    two rows' schedule instants, integrated numerically (the scale linear in schedule time between
    rows), is the difference of their written times to 1e-9 ms plus 1e-6 of it (the scale at a row
    moved across a kink of the scale is taken there again; more only where the instants' float
    spacing, over a slowed clock, is coarser), on the short intervals above all. Rounding the times alone (the
    instants left where they were) put rows up to 5e-7 ms off, which on rows microseconds apart read
    as hundreds of mm/s^2 of tip acceleration (BladeX mesh, bladecam verify)."""
    normal, _ = override_runs
    warp = normal.warp
    tau, s, t = warp.schedule_t, warp.scale, normal.timeline.t
    assert np.array_equal(t, np.round(t, 6))  # on the tables' grid
    rng = np.random.default_rng(1)
    dt = np.diff(t)
    short = np.flatnonzero(dt < 0.5)  # where a rounding of 5e-7 ms would be felt (1e-6 of the interval)
    assert short.size > 100
    picked = np.concatenate([rng.choice(short, min(short.size, 2000), replace=False),
                             rng.choice(len(t) - 1, 2000, replace=False)])
    for i in picked:
        a, b = tau[i], tau[i + 1]
        s0, s1 = s[i], s[i + 1]
        val, _ = quad(lambda x, a=a, b=b, s0=s0, s1=s1: 1.0 / (s0 + (s1 - s0) * (x - a) / (b - a)), a, b,
                      epsabs=1e-13, epsrel=1e-12)
        # (the instants' own float spacing, stretched by the slowed clock, is the floor)
        floor = 8.0 * np.spacing(b) / min(s[i], s[i + 1])
        assert abs(val - dt[i]) <= 1e-9 + 1e-6 * dt[i] + floor, (i, dt[i])
    # the CL rows are the motion at those instants
    idx = rng.choice(len(t), 2000, replace=False)
    left, right = normal.schedule.sample(tau[idx])
    assert np.abs(left.tips - normal.timeline.left.tips[idx]).max() < 1e-12
    assert np.abs(right.axes - normal.timeline.right.axes[idx]).max() < 1e-12


def test_tips_keep_a_max_along_the_path(override_runs):
    """On the new clock a tip's speed along the path is the schedule's (from its speed laws) times the
    scale; between every two rows its mean acceleration stays within a_max, for both the shipped
    machine and the slow one (whose override changes the scale much more)."""
    for res in override_runs:
        warp, t = res.warp, res.timeline.t
        a_max = res.plan.params.a_max / 1e6
        for side in ("left", "right"):
            v = res.schedule.speeds(side, warp.schedule_t) * warp.scale
            acc = np.abs(np.diff(v)) / np.diff(t)
            assert acc.max() <= a_max * (1 + 1e-6), (side, acc.max() * 1e6)


def test_written_times_map_to_their_instants_on_the_clock():
    """core.machine.override._at_written_times against numerical integration of the clock: each row's new
    instant is where the clock (s linear in schedule time between the original rows) reads the
    row's rounded time, to 1e-10 ms, whether the rounding moved it forwards or backwards, across
    the scale's kinks; the first and last rows stay within the column (a last time rounded up past
    the end keeps the end)."""
    from core.machine.override import _at_written_times

    rng = np.random.default_rng(4)
    n = 300
    tau = np.cumsum(rng.uniform(1e-3, 0.5, n)) - 1e-3
    tau[0] = 0.0
    s = rng.uniform(0.01, 1.0, n)
    pieces = [quad(lambda x, i=i: 1.0 / (s[i] + (s[i + 1] - s[i]) * (x - tau[i]) / (tau[i + 1] - tau[i])),
                   tau[i], tau[i + 1], epsabs=1e-14, epsrel=1e-13)[0] for i in range(n - 1)]
    clock = np.concatenate([[0.0], np.cumsum(pieces)])       # the new clock at the original rows
    t_new = np.round(clock, 6)
    tau_w, s_w = _at_written_times(tau, s, t_new)
    assert np.all(np.diff(tau_w) > 0) and tau_w[0] == 0.0 and tau_w[-1] <= tau[-1]
    for i in range(n):
        if t_new[i] > clock[-1]:  # the end rounded up: the row stays at the end (the job is over)
            assert i == n - 1 and tau_w[i] == tau[-1]
            continue
        j = min(int(np.searchsorted(tau, tau_w[i], side="right")) - 1, n - 2)
        inside = quad(lambda x, j=j: 1.0 / (s[j] + (s[j + 1] - s[j]) * (x - tau[j]) / (tau[j + 1] - tau[j])),
                      tau[j], tau_w[i], epsabs=1e-14, epsrel=1e-13)[0]
        assert abs(clock[j] + inside - t_new[i]) <= 1e-10, i
        # the scale reported at the row is the clock's there
        assert abs(s_w[i] - (s[j] + (s[j + 1] - s[j]) * (tau_w[i] - tau[j]) / (tau[j + 1] - tau[j]))) < 1e-12
