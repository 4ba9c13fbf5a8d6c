"""The machine clock (core.machine.timing, core.machine.caps): its rate against brute force and numerical
integration, the chord caps against exact geometry, and plans whose rows lie on the controller's period,
whose axis tables keep every speed and acceleration limit and whose straight lines between rows keep
the chord tolerance, checked on the tables and the planned motion themselves."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad

from core.machine.caps import AIR_CHORD_TOL, chord_length
from core.machine.model import AXES, load_machine, machine_to_toml
from core.machine.tables import SLOWED_BELOW, SLOWED_FOR, AxisTable, check_limits
from core.machine.timing import _at_machine_times, _clock, _cone, _durations, _inside
from core.records import ENFORCED_LIMITS, PlanParameters

from ...conftest import plan_on


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


def test_machine_times_map_to_their_instants_on_the_clock():
    """core.machine.timing._at_machine_times against numerical integration of the clock: each machine
    time is read at the schedule instant where the clock (s linear in schedule time between the grid's
    instants) shows it, to 1e-10 ms; a time past the clock's end is the schedule's end."""
    rng = np.random.default_rng(4)
    n = 300
    tau = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-3, 0.5, n - 1))])
    s = rng.uniform(0.01, 1.0, n)

    def rate(x, j):
        return s[j] + (s[j + 1] - s[j]) * (x - tau[j]) / (tau[j + 1] - tau[j])

    clock = _clock(tau, s)
    ref = np.concatenate([[0.0], np.cumsum([quad(lambda x, i=i: 1.0 / rate(x, i), tau[i], tau[i + 1],
                                                 epsabs=1e-14, epsrel=1e-13)[0] for i in range(n - 1)])])
    np.testing.assert_allclose(clock, ref, rtol=1e-10, atol=1e-12)
    t = np.sort(rng.uniform(0.0, clock[-1], 500))
    at = _at_machine_times(tau, s, clock, np.append(t, clock[-1] + 1.0))
    assert at[-1] == tau[-1] and (np.diff(at) >= 0).all()
    for x, a in zip(t, at[:-1], strict=True):
        j = min(int(np.searchsorted(tau, a, side="right")) - 1, n - 2)
        inside = quad(lambda y, j=j: 1.0 / rate(y, j), tau[j], a, epsabs=1e-14, epsrel=1e-13)[0]
        assert abs(ref[j] + inside - x) <= 1e-10


def _farthest_from_chord(path: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    e = b - a
    u = np.clip((path - a) @ e / (e @ e), 0.0, 1.0)
    return float(np.linalg.norm(a + u[:, None] * e - path, axis=1).max())


def test_chord_length_keeps_the_tolerance_at_a_corner_and_on_an_arc():
    """A chord of the length chord_length gives strays from the path by at most the tolerance, at
    its worst placement: across one corner between long segments (every split of the chord over the
    corner), and along a circle drawn as a fine polyline; and it is not far inside it (at most 2x
    shorter than the longest chord that keeps the tolerance)."""
    tol = 1e-3
    for theta in (0.01, 0.3, 1.0, 2.0, 3.0):
        h = 10.0
        c = float(chord_length(np.array([theta]), np.array([h]), tol)[0])
        d0, d1 = np.array([1.0, 0.0]), np.array([np.cos(theta), np.sin(theta)])
        worst = 0.0
        for a_share in np.linspace(0.0, 1.0, 41):  # (c is the path length of the chord's two ends)
            a_pt, b_pt = -a_share * c * d0, (1 - a_share) * c * d1
            worst = max(worst, _farthest_from_chord(np.zeros((1, 2)), a_pt, b_pt))
        assert worst <= tol * (1 + 1e-9) and worst >= 0.5 * tol, (theta, worst)
    for radius in (0.5, 5.0, 50.0):
        h = 0.01
        theta = h / radius
        c = float(chord_length(np.array([theta]), np.array([h]), tol)[0])
        phi = np.linspace(0.0, c / radius, 2001)
        arc = radius * np.column_stack([np.cos(phi), np.sin(phi)])
        dev = _farthest_from_chord(arc, arc[0], arc[-1])
        assert dev <= tol * (1 + 1e-3) and dev >= 0.5 * tol, (radius, dev)


def _slow_machine(factor: float):
    m = load_machine(None)
    limits = {name: dataclasses.replace(m.limits.axis(name),
                                        max_accel_mm_s2=m.limits.axis(name).max_accel_mm_s2 * factor)
              for name in AXES}
    return dataclasses.replace(m, limits=dataclasses.replace(m.limits, **limits))


@pytest.fixture(scope="module")
def timed_runs(tmp_path_factory, sample_paths):
    params = PlanParameters(dr=4.0)
    paths = sample_paths(dr=4.0)
    slow_toml = tmp_path_factory.mktemp("machine") / "slow.toml"
    slow_toml.write_text(machine_to_toml(_slow_machine(0.2)))
    normal = plan_on(paths, params=params, axes=True)
    slow = plan_on(paths, params=params, axes=True, machine=str(slow_toml))
    assert slow.machine.limits == _slow_machine(0.2).limits  # (the toml round trip keeps the slow limits)
    return normal, slow, paths


def test_every_row_lies_on_the_period(timed_runs):
    for res in timed_runs[:2]:
        t = res.timeline.t
        k = np.arange(len(t))
        assert np.array_equal(t, np.round(k * res.period, 6))
        for side in ("left", "right"):
            assert np.array_equal(res.axes[side].t, t)


def test_axis_tables_keep_speed_and_acceleration_limits(timed_runs):
    for res in timed_runs[:2]:
        m = res.machine
        assert not res.limit_findings, [str(f) for f in res.limit_findings[:5]]
        for side in ("left", "right"):
            tab = res.axes[side]
            t, v = tab.t, tab.velocities
            acc = np.abs(np.diff(v, axis=0)) / np.diff(t)[:, None] * 1e6
            for k, name in enumerate(AXES):
                lim = m.limits.axis(name)
                assert acc[:, k].max() <= lim.max_accel_mm_s2 * (1 + 1e-9)
                assert np.abs(v[:, k]).max() * 1000.0 <= lim.max_speed_mm_s * (1 + 1e-9)


def test_lower_acceleration_limits_slow_the_job_and_bind(timed_runs):
    normal, slow, _ = timed_runs
    assert slow.timeline.t[-1] > normal.timeline.t[-1] * 1.01
    # the lower limit is used: somewhere an axis accelerates above the slow machine's limit in the
    # normal plan, and the slow plan keeps below it everywhere
    worst = max(float((np.abs(np.diff(normal.axes[s].velocities, axis=0)) / np.diff(normal.axes[s].t)[:, None]
                       * 1e6 / np.array([slow.machine.limits.axis(a).max_accel_mm_s2 for a in AXES])).max())
                for s in ("left", "right"))
    assert worst > 1.0
    # both plans are the same schedule on different clocks: the tip spacing's minimum differs only by
    # where the rows fall
    assert slow.figures["min_tip_spacing_mm"] == pytest.approx(normal.figures["min_tip_spacing_mm"], abs=1e-3)


def test_an_acceleration_jump_is_a_blocking_finding():
    m = load_machine(None)
    t = np.array([0.0, 10.0, 20.0, 30.0])
    values = np.zeros((4, 6))
    vel = np.zeros((4, 6))
    vel[2:, 1] = 0.01  # y jumps from 0 to 10 mm/s in 10 ms: 1000 mm/s^2 > 500
    found = check_limits(m, AxisTable("left", t, values, vel))
    assert [(f.axis, f.kind) for f in found] == [("y", "acceleration")]
    assert found[0].value == pytest.approx(1000.0) and found[0].t_ms == 10.0
    assert "acceleration" in ENFORCED_LIMITS


def test_rows_are_the_motion_at_their_instants_on_the_clock(timed_runs):
    """Row k is the schedule's motion at the instant the clock reads k * period: the instants run from
    the schedule's start to its end, never faster than the schedule's own time (s <= 1) and never back;
    the CL rows are the schedule sampled at those instants."""
    for res in timed_runs[:2]:
        warp = res.warp
        tau, s, t = warp.schedule_t, warp.scale, res.timeline.t
        assert tau[0] == 0.0 and tau[-1] == pytest.approx(res.schedule.duration, abs=1e-9)
        mean = np.diff(tau) / np.diff(t)
        assert (mean >= 0).all() and (mean <= 1.0 + 1e-9).all() and (s <= 1.0).all()
        rng = np.random.default_rng(1)
        idx = rng.choice(len(t), 2000, replace=False)
        left, right = res.schedule.sample(tau[idx])
        assert np.abs(left.tips - res.timeline.left.tips[idx]).max() < 1e-12
        assert np.abs(right.axes - res.timeline.right.axes[idx]).max() < 1e-12


def test_straight_lines_between_rows_keep_the_chord_tolerance(timed_runs):
    """Between two rows the planned path (both cutters' tips and ball centres at 15 instants between
    the rows' own) stays within the chord tolerance of the straight line between them: on every
    interval where the path turns (the rows' chords turn by more than 1e-4 rad), measured here on the
    motion itself; and plan.json's figure reports at most the tolerance. Between two rows of moves
    that do not cut (in the air) the tolerance is AIR_CHORD_TOL."""
    for res in timed_runs[:2]:
        tol = res.figures["machine"]["chord"]["tolerance_mm"]
        air_tol = max(tol, AIR_CHORD_TOL)
        assert 0.0 <= res.figures["machine"]["chord"]["largest_deviation_mm"] <= tol
        tau = res.warp.schedule_t
        r = res.plan.params.tool_radius
        worst = 0.0
        for side in ("left", "right"):
            smp = getattr(res.timeline, side)
            in_air = ~smp.cutting[:-1] & ~smp.cutting[1:]
            d = np.diff(smp.tips, axis=0)
            c = np.linalg.norm(d, axis=1)
            u = d / np.where(c > 0, c, 1.0)[:, None]
            turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1.0, 1.0))
            k = np.flatnonzero((np.maximum(np.append(turn, 0.0), np.append(0.0, turn)) > 1e-4) & (c > 0))
            f = np.linspace(0.0, 1.0, 17)[1:-1]
            mid = tau[k][:, None] + (tau[k + 1] - tau[k])[:, None] * f[None, :]
            got = res.schedule.table(side).sample(mid.ravel())
            for pts, at in ((smp.tips, got.tips), (smp.tips + r * smp.axes, got.tips + r * got.axes)):
                a, b = np.repeat(pts[k], len(f), axis=0), np.repeat(pts[k + 1], len(f), axis=0)
                e = b - a
                w = np.clip(np.einsum("ij,ij->i", at - a, e) / np.maximum(np.einsum("ij,ij->i", e, e), 1e-300), 0, 1)
                dev = np.linalg.norm(a + w[:, None] * e - at, axis=1)
                allowed = np.repeat(np.where(in_air[k], air_tol, tol), len(f))
                worst = max(worst, float((dev / allowed).max(initial=0.0)))
        assert worst <= 1.05, worst


def test_the_clock_says_what_it_slows_the_job_for(timed_runs):
    """Each row's reason (TimeWarp.slowed_for) is set exactly where the clock runs below SLOWED_BELOW;
    the rows slowed for the chord tolerance are where a cutter's path turns; the machine with a fifth of
    the accelerations is slowed for its axes over more of its job."""
    for res in timed_runs[:2]:
        why, s = res.warp.slowed_for, res.warp.scale
        assert why is not None and len(why) == len(res.timeline.t)
        assert np.array_equal(why != 0, s < SLOWED_BELOW)
        chord = np.flatnonzero(why == SLOWED_FOR.index("chord"))
        assert chord.size
        turning = np.zeros(len(why), bool)
        for side in ("left", "right"):
            tips = getattr(res.timeline, side).tips
            d = np.diff(tips, axis=0)
            c = np.linalg.norm(d, axis=1)
            u = d / np.where(c > 0, c, 1.0)[:, None]
            turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1.0, 1.0)) > 1e-4
            for lag in range(-3, 4):  # (the turn within three rows of it)
                turning[1:-1] |= np.roll(turn, lag)
        assert turning[chord].mean() > 0.9
    normal, slow, _ = timed_runs
    axes = SLOWED_FOR.index("axes")
    assert (slow.warp.slowed_for == axes).mean() > (normal.warp.slowed_for == axes).mean()


def test_each_machine_alone_would_run_at_least_as_fast(timed_runs):
    """TimeWarp.own_scale: each machine's own caps allow at least the shared rate at every row (the
    shared clock is the lower of the two), and on the slow machine, whose axes slow the job over much
    more of it, the rate each machine alone would allow is well above the shared one over some rows
    (where the other machine sets the pace)."""
    for res in timed_runs[:2]:
        warp = res.warp
        own = warp.own_scale
        assert set(own) == {"left", "right"}
        for side in ("left", "right"):
            assert len(own[side]) == len(warp.t)
            assert (own[side] >= warp.scale - 1e-6).all(), side
            assert (own[side] <= 1.0).all()
        both = np.minimum(own["left"], own["right"])
        # where neither machine is slowed by the other, the shared rate is the lower of their own
        assert np.median(np.abs(both - warp.scale)) < 1e-3
        assert max((own[side] > warp.scale + 0.2).mean() for side in ("left", "right")) > 0.001


def test_tips_keep_a_max_along_the_path(timed_runs):
    """On the machine clock a tip's speed along the path is the schedule's (from its speed laws) times
    the rate; between every two rows its mean acceleration stays within a_max, for both the shipped
    machine and the slow one."""
    for res in timed_runs[:2]:
        warp, t = res.warp, res.timeline.t
        a_max = res.plan.params.a_max / 1e6
        for side in ("left", "right"):
            v = res.schedule.speeds(side, warp.schedule_t) * warp.scale
            acc = np.abs(np.diff(v)) / np.diff(t)
            assert acc.max() <= a_max * (1 + 1e-6), (side, acc.max() * 1e6)


def test_the_job_is_the_same_without_the_axis_tables(timed_runs):
    """--no-axes writes the CL tables of the same machine-timed job."""
    normal, _, paths = timed_runs
    bare = plan_on(paths, params=normal.plan.params, axes=False)
    assert bare.axes is None
    assert np.array_equal(bare.timeline.t, normal.timeline.t)
    assert np.array_equal(bare.timeline.left.tips, normal.timeline.left.tips)
    assert bare.figures["total_time_s"] == normal.figures["total_time_s"]


def test_verify_finds_a_row_off_the_period(timed_runs, tmp_path):
    """bladecam verify reads the period from plan.json and finds a row moved off t = k * period (both CL
    tables moved alike, so that the two still share one column)."""
    from core.output.writer import write_result
    from core.verify.check import verify

    out = tmp_path / "plan"
    write_result(timed_runs[0], out)
    assert verify(out).findings == []
    for name in ("left_cl.csv", "right_cl.csv"):
        lines = (out / name).read_text().split("\n")
        cells = lines[500].split(",")
        cells[0] = f"{float(cells[0]) + 0.25:.6f}"
        lines[500] = ",".join(cells)
        (out / name).write_text("\n".join(lines))
    found = verify(out).findings
    assert any("off the period" in f for f in found), found[:5]
