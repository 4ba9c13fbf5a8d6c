"""The XYZ-3RPS post-processor: tilt limit, axis tables on the machine clock, limits; checked against
forward kinematics, central differences and the plan without the axis tables."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.machine.kinematics import forward_kinematics
from core.machine.model import AXES, load_machine
from core.machine.reach import TILT_MARGIN_DEG, limit_tilt, spindle_direction
from core.machine.tables import check_limits
from core.records import PlanParameters
from core.schedule.safety import tip_spacing

from ...conftest import COARSE_ARGS, cli, plan_on


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)), min_size=1, max_size=30),
       st.floats(5.0, 80.0))
def test_limit_tilt_keeps_ball_centres_and_reaches_the_limit(vecs, limit):
    axes = np.array(vecs, float)
    keep = np.linalg.norm(axes, axis=1) > 1e-3
    if not keep.any():
        return
    axes = axes[keep] / np.linalg.norm(axes[keep], axis=1)[:, None]
    tips = np.random.default_rng(1).normal(0, 50, (len(axes), 3))
    spindle = np.array([0.0, 0.0, -1.0])
    new_tips, new_axes, changed = limit_tilt(tips, axes, 1.5, spindle, limit)
    tilt = np.degrees(np.arccos(np.clip(new_axes @ spindle, -1, 1)))
    assert tilt.max() <= limit + 1e-9
    np.testing.assert_allclose(new_tips + 1.5 * new_axes, tips + 1.5 * axes, atol=1e-12)
    np.testing.assert_array_equal(new_axes[~changed], axes[~changed])
    np.testing.assert_allclose(tilt[changed], limit, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(new_axes, axis=1), 1.0, atol=1e-12)


@pytest.fixture(scope="module")
def machine_run(sample_paths):
    params = PlanParameters(dr=4.0)
    paths = sample_paths(dr=4.0)
    plain = plan_on(paths, params=params)
    full = plan_on(paths, params=params, axes=True)
    return plain, full


def test_axis_tables_reproduce_the_cl_by_forward_kinematics(machine_run):
    _, res = machine_run
    m = res.machine
    for side in ("left", "right"):
        tab = res.axes[side]
        s = getattr(res.timeline, side)
        tips, axes = forward_kinematics(m, side, tab.values)
        assert np.linalg.norm(tips - s.tips, axis=1).max() < 1e-6
        assert np.arccos(np.clip((axes * s.axes).sum(1), -1, 1)).max() < 1e-7
        tilt = np.degrees(np.arccos(np.clip(s.axes @ spindle_direction(m, side), -1, 1)))
        assert tilt.max() <= m.max_tilt_deg - TILT_MARGIN_DEG + 1e-6


def test_machine_clock_keeps_speeds_and_the_schedule_instants(machine_run):
    plain, res = machine_run
    m = res.machine
    assert not res.blocking_findings
    for side in ("left", "right"):
        v = np.abs(res.axes[side].velocities) * 1000.0
        for k, name in enumerate(AXES):
            assert v[:, k].max() <= m.limits.axis(name).max_speed_mm_s + 1e-9
    # the job only gets longer than the schedule at the feed, and every row is the schedule's motion
    # at its own instant, so the tip spacing along the machine clock matches the schedule sampled there
    assert res.timeline.t[-1] >= res.schedule.duration
    assert np.array_equal(plain.timeline.t, res.timeline.t)  # (the same job without the axis tables)
    ref_l, ref_r = res.schedule.sample(res.warp.schedule_t)
    np.testing.assert_allclose(res.timeline.left.tips, ref_l.tips, atol=1e-12)
    at, _ = tip_spacing(res.timeline.left.tips, res.timeline.right.tips)
    at_ref, _ = tip_spacing(ref_l.tips, ref_r.tips)
    np.testing.assert_allclose(at, at_ref, atol=1e-12)
    assert at.min() >= res.plan.params.h_safe - 1e-6


def test_velocities_are_the_derivative_of_the_displacements(machine_run):
    _, res = machine_run
    for side in ("left", "right"):
        tab = res.axes[side]
        t, x, v = tab.t, tab.values, tab.velocities
        cd = (x[2:] - x[:-2]) / (t[2:] - t[:-2])[:, None]
        diff = np.abs(v[1:-1] - cd)
        tol = 0.02 * np.abs(v).max(axis=0) + 1e-5
        assert ((diff <= tol).mean(axis=0) >= 0.99).all()


def test_cli_axes_files_verify_and_limits_refuse(coarse_plan, tmp_path, capsys):
    """Every plan writes the machines' axis tables (SPEC.md section 10) unless --no-axes."""
    out, res = coarse_plan  # (the sample's coarse plan, written by the command line once per session)
    assert res.returncode == 0, res.stderr
    assert {p.name for p in out.iterdir()} >= {"left_axes.csv", "right_axes.csv", "machine.toml"}
    bare = tmp_path / "bare"
    res = cli(capsys, "plan", *COARSE_ARGS, "--no-axes", "--out", bare)
    assert res.returncode == 0, res.stderr
    assert {p.name for p in bare.iterdir()} == {"pairs.csv", "left_cl.csv", "right_cl.csv", "plan.json", "tool.toml",
                                               "blade.stl"}
    head = (out / "left_axes.csv").read_text().splitlines()[:2]
    assert head[0] == "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3"
    assert len(head[1].split(",")) == 13
    ver = cli(capsys, "verify", out)
    assert "fk_error_mm" in ver.stdout
    assert "forward kinematics misses" not in ver.stdout and "stroke" not in ver.stdout
    # a machine whose x stroke is too short: refused, nothing written, unless --force
    small = tmp_path / "small.toml"
    text = (out / "machine.toml").read_text()
    start = text.index("[limits.x]")
    small.write_text(text[:start] + text[start:].replace("min_mm = -300", "min_mm = -5", 1)
                     .replace("max_mm = 300", "max_mm = 5", 1))
    assert load_machine(small).limits.x.max_mm == 5
    bad = tmp_path / "bad"
    # (a travel far beyond the stroke is refused before planning, with --force too: no plan can run)
    for force in ((), ("--force",)):
        res = cli(capsys, "plan", *COARSE_ARGS, "--machine", small, *force, "--out", bad)
        assert res.returncode == 2 and "x axis would need" in res.stderr and "checked before planning" in res.stderr
        assert "longer strokes" in res.stderr and "Lower the feed" not in res.stderr  # (a stroke: the feed cannot help)
        assert not bad.exists()
    res = cli(capsys, "plan", "--no-axes", "--machine", small, "--out", tmp_path / "y")
    # (the job is timed for the machine with or without its axis tables: refused alike)
    assert res.returncode == 2 and "x axis would need" in res.stderr
    assert not (tmp_path / "y").exists()
    broken = tmp_path / "broken.toml"
    broken.write_text(text.replace("gauge_length_mm", "gauge_len_mm"))
    res = cli(capsys, "plan", "--axes", "--machine", broken, "--out", tmp_path / "x")
    assert res.returncode != 0 and "gauge_length_mm" in res.stderr and "Traceback" not in res.stderr


def test_check_limits_finds_the_worst_three_per_axis_and_kind():
    """check_limits against a row-by-row reading of a random table that breaks every limit: for each
    axis (in order x .. d3) and kind (stroke, speed, acceleration), the three worst rows, worst first."""
    from core.machine.tables import AxisTable

    m = load_machine(None)
    rng = np.random.default_rng(0)
    n = 400
    t = np.cumsum(rng.uniform(0.5, 2, n))
    vals, vel = rng.normal(scale=200, size=(n, 6)), rng.normal(scale=0.2, size=(n, 6))
    got = [(f.axis, f.kind, f.t_ms, f.value) for f in check_limits(m, AxisTable("left", t, vals, vel))]
    want = []
    for k, name in enumerate(AXES):
        lim = m.limits.axis(name)
        rows = {"stroke": [], "speed": [], "acceleration": []}
        for i in range(n):
            x = vals[i, k]
            if x < lim.min_mm or x > lim.max_mm:
                rows["stroke"].append((max(lim.min_mm - x, x - lim.max_mm), i, x))
            if abs(vel[i, k]) * 1000 > lim.max_speed_mm_s:
                rows["speed"].append((abs(vel[i, k]) * 1000 - lim.max_speed_mm_s, i, vel[i, k] * 1000))
            if i < n - 1:
                a = (vel[i + 1, k] - vel[i, k]) / (t[i + 1] - t[i]) * 1e6
                if abs(a) > lim.max_accel_mm_s2:
                    rows["acceleration"].append((abs(a) - lim.max_accel_mm_s2, i, a))
        for kind in ("stroke", "speed", "acceleration"):
            for _, i, x in sorted(rows[kind], key=lambda r: -r[0])[:3]:
                want.append((name, kind, t[i], x))
    assert len(got) == len(want) == 6 * 3 * 3
    for g, w in zip(got, want, strict=True):
        assert g[:3] == w[:3] and abs(g[3] - w[3]) <= 1e-9 * max(1.0, abs(w[3])), (g, w)


def test_check_limits_and_peaks_on_a_table_within_limits_but_one_row():
    """A table inside every limit but for one speed row and one stroke row: exactly those two findings
    (check_limits searches the rows only where an extreme is beyond the limit), and the peaks
    plan.json reports equal a row-by-row reading."""
    from core.machine.tables import AxisTable, peaks

    m = load_machine(None)
    rng = np.random.default_rng(1)
    n = 500
    t = np.cumsum(rng.uniform(5, 10, n))
    lims = [m.limits.axis(a) for a in AXES]
    mid = np.array([(lim.min_mm + lim.max_mm) / 2 for lim in lims])
    half = np.array([(lim.max_mm - lim.min_mm) / 2 for lim in lims])
    vals = mid + rng.uniform(-0.5, 0.5, (n, 6)) * half
    vmax = np.array([lim.max_speed_mm_s for lim in lims]) / 1000.0
    amax = np.array([lim.max_accel_mm_s2 for lim in lims]) / 1e6
    vel = np.cumsum(rng.uniform(-1, 1, (n, 6)) * amax * 0.01, axis=0)
    vel = np.clip(vel, -0.5 * vmax, 0.5 * vmax)
    vals[123, 2] = lims[2].max_mm + 0.25                    # z beyond its stroke at one row
    vel[300, 4] = 1.1 * vmax[4]                             # d2 too fast at one row (and the jump to it
    table = AxisTable("right", t, vals, vel)
    got = [(f.axis, f.kind, f.t_ms) for f in check_limits(m, table)]
    acc = np.diff(vel, axis=0) / np.diff(t)[:, None] * 1e6
    want = [("z", "stroke", t[123]), ("d2", "speed", t[300])]
    want += [("d2", "acceleration", t[i]) for i in np.argsort(-np.abs(acc[:, 4]))[:3]  # too sudden)
             if abs(acc[i, 4]) > lims[4].max_accel_mm_s2]
    assert sorted(got) == sorted(want)
    pk = peaks(table)
    for k, name in enumerate(AXES):
        assert pk[name]["min_mm"] == round(min(vals[i, k] for i in range(n)), 4)
        assert pk[name]["max_mm"] == round(max(vals[i, k] for i in range(n)), 4)
        assert pk[name]["peak_speed_mm_s"] == round(max(abs(vel[i, k]) for i in range(n)) * 1000.0, 4)
        assert pk[name]["peak_accel_mm_s2"] == round(max(abs(acc[i, k]) for i in range(n - 1)), 2)


def test_check_limits_still_searches_a_column_with_a_nan():
    """A NaN in a column (two rows at one written time give 0/0) does not hide that axis's findings."""
    from core.machine.tables import AxisTable

    m = load_machine(None)
    n = 50
    t = np.arange(n, dtype=float) * 10.0
    t[20] = t[19]  # one acceleration is 0/0
    vals = np.zeros((n, 6))
    vel = np.zeros((n, 6))
    vel[30:, 0] = 0.9 * m.limits.axis("x").max_speed_mm_s / 1000.0  # a jump: too sudden for x
    with np.errstate(invalid="ignore"):
        found = [(f.axis, f.kind, f.t_ms) for f in check_limits(m, AxisTable("left", t, vals, vel))]
    assert ("x", "acceleration", t[29]) in found


@pytest.mark.parametrize("n", [1, 2, 63, 64, 65, 999, 3077])
def test_table_extremes_equal_numpy_reductions(monkeypatch, n):
    """AxisTable.extremes (rows reduced 64 at a time side by side, block by block) and its
    accelerations (derived on demand) equal numpy's plain column reductions and differences
    exactly, over block boundaries, with a NaN acceleration (two rows at one time) and velocities that
    are a slice of a wider array."""
    import core.machine.tables as pp
    from core.machine.tables import AxisTable, column_range

    monkeypatch.setattr(pp, "ROW_BLOCK", 1000)
    rng = np.random.default_rng(n)
    t = np.cumsum(rng.uniform(0.5, 2, n))
    wide = rng.normal(size=(n, 12))  # (a table's columns are a slice of both sides' array)
    wide[:, :6] *= 50
    wide[:, 6:] *= 0.1
    vals, vel = wide[:, :6], wide[:, 6:]
    assert n == 1 or not vel.flags.c_contiguous
    if n > 1000:
        t[1500] = t[1499]  # 0/0 and x/0 in the second block
        vel[1500, 2] = vel[1499, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        acc = np.diff(vel, axis=0) / np.diff(t)[:, None] if n > 1 else np.zeros((1, 6))
        table = AxisTable("left", t, vals, vel)
        ex = table.extremes
        want = {"min": vals.min(axis=0), "max": vals.max(axis=0),
                "speed": np.maximum(vel.max(axis=0), -vel.min(axis=0)),
                "accel": np.maximum(acc.max(axis=0), -acc.min(axis=0))}
        for key, value in want.items():
            assert np.array_equal(ex[key], value, equal_nan=True), (key, ex[key], value)
        if n > 1:
            assert np.array_equal(table.accelerations(), acc, equal_nan=True)
        else:
            assert table.accelerations().shape == (0, 6)
    lo, hi = column_range(vals)
    assert np.array_equal(lo, vals.min(axis=0)) and np.array_equal(hi, vals.max(axis=0))


def test_axis_motion_errors_name_rows_of_the_whole_column(monkeypatch):
    """axis_motion works in blocks of rows; an unreachable pose is still named by its row in the
    whole column (in the message and on the error)."""
    import core.machine.tables as pp
    from core.errors import MachineError

    monkeypatch.setattr(pp, "ROW_BLOCK", 16)
    m = load_machine(None)
    d = spindle_direction(m, "left")
    n = 60
    tips = np.zeros((n, 3))
    axes = np.tile(d, (n, 1))
    tilted = np.cross(d, [1.0, 0.0, 0.0])
    tilted /= np.linalg.norm(tilted)
    axes[41] = tilted  # 90 degrees from the spindle: beyond any head's reach
    with pytest.raises(MachineError) as err:
        pp.axis_motion(m, "left", tips, axes, np.zeros((n, 3)), np.zeros((n, 3)))
    assert "at samples 41" in str(err.value) and list(err.value.samples) == [41]


@pytest.mark.parametrize("n", [1, 2, 40, 64, 65, 200])
def test_axis_excess_is_the_worst_share_over_both_tables(monkeypatch, n):
    """axis_excess in blocks of rows (a block size that does not divide the rows) equals the share of
    the limits computed over whole columns: per interval, the largest |dv| / (period a_lim) and
    (|v| / v_lim)^2 at its two rows, over both tables, v being the velocities times the rate."""
    import core.machine.tables as pp

    monkeypatch.setattr(pp, "ROW_BLOCK", 16)
    rng = np.random.default_rng(n)
    tables = [rng.normal(size=(n, 6)) * 0.05 for _ in range(2)]
    rate = rng.uniform(0.1, 1.0, n)
    v_lim, a_lim, period = rng.uniform(0.02, 0.05, 6), rng.uniform(1e-4, 5e-4, 6), 12.0
    want = np.zeros(max(n - 1, 0))
    for vel in tables:
        v = vel * rate[:, None]
        for i in range(n - 1):
            acc = np.abs(v[i + 1] - v[i]) / (period * a_lim)
            speed = max((np.abs(v[i]) / v_lim).max(), (np.abs(v[i + 1]) / v_lim).max())
            want[i] = max(want[i], acc.max(), speed**2)
    np.testing.assert_array_equal(pp.axis_excess(tables, rate, period, v_lim, a_lim), want)
