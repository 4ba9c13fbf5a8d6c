"""The seven-step schedule on the sample blade (coarse dR to stay quick), checked from its samples."""

import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from core.blade.source import load_blade
from core.paths.planning import plan_paths
from core.records import PlanParameters
from core.schedule.figures import figures
from core.schedule.motion import ramp_law
from core.schedule.steps import build_schedule
from core.schedule.timeline import SafetyProfile

from ...conftest import BLADEX, CHECKS, COARSE_ARGS, Ran, cli, plan_on


@pytest.fixture(scope="module")
def plan(sample_paths):
    return sample_paths(dr=2.0)


@pytest.fixture(scope="module")
def collaborative(plan):
    res = plan_on(plan)  # (the schedule on the machine clock's rows, as core.planner.Planner plans it)
    return res.schedule, res.timeline


def _figures(tl, plan, sch):
    """plan.json's figures of a time column, on its SafetyProfile (as core.planner computes them)."""
    p = plan.params
    return figures(tl, plan, sch, SafetyProfile.of(tl, p.tool_radius, p.tool_length, p.h_safe))


def test_ramp_law_distance_and_acceleration():
    law = ramp_law(5.0, 1000 / 60000, 500 / 1e6, v_a=0.004, v_b=0.0)
    total = quad(lambda tau: float(law.speed(np.array([tau]))[0]), 0, law.duration, limit=200)[0]
    assert total == pytest.approx(5.0, abs=1e-9)
    tau = np.linspace(0, law.duration, 20001)
    v = law.speed(tau)
    a = np.abs(np.gradient(v, tau))
    assert a.max() <= 500 / 1e6 * 1.001 and v.max() <= 1000 / 60000 + 1e-12
    assert np.allclose(np.gradient(law.distance(tau), tau)[1:-1], v[1:-1], atol=1e-6)


def test_all_seven_steps_and_safe(collaborative, plan):
    sch, tl = collaborative
    steps = set(tl.left.step) | set(tl.right.step)
    assert steps == set(range(1, 8))
    fig = _figures(tl, plan, sch)
    assert fig["spacing_violations"] == 0 and fig["capsule_violations"] == 0
    assert fig["min_tip_spacing_mm"] >= plan.params.h_safe
    # independent recomputation of the spacing from the samples
    d = np.linalg.norm(tl.left.tips - tl.right.tips, axis=1)
    assert d.min() >= plan.params.h_safe - 1e-9
    assert 0 < fig["support"]["supported_cutting_share"] < 1


def test_synchronisation_points_reached_together(collaborative):
    """Every stage of one cutter ends exactly when the other cutter's route ends (E_vs with S_vl, E_vl
    with E_ss): the stage moves' end times coincide with an end of a move of the other cutter; the
    paper's stages, and those waited out off the blade (their last cut after the lift, the wait and
    the descent onto the point where the cutter stopped)."""
    sch, _ = collaborative
    ends = {"left": np.array([m.t1 for m in sch.left]), "right": np.array([m.t1 for m in sch.right])}
    n = lifted = 0
    for side, other in (("left", "right"), ("right", "left")):
        moves = getattr(sch, side)
        for k, m in enumerate(moves):
            after_wait = (k >= 3 and m.cutting and type(moves[k - 2].law).__name__ == "WaitLaw"
                          and not moves[k - 1].cutting and not moves[k - 3].cutting
                          and np.allclose(moves[k - 3].points[0], m.points[0])
                          and np.allclose(moves[k - 1].points[-1], m.points[0]))
            if m.step in (5, 6) and (hasattr(m.law, "kind") or after_wait):
                assert np.abs(ends[other] - m.t1).min() < 1e-6
                n += 1
                lifted += after_wait
    assert n > 10 and lifted > 5


def test_cl_files_pass_the_shared_check_and_symmetric_fails(tmp_path, capsys, coarse_plan):
    script = CHECKS / "check_cl.py"
    if not script.is_file():
        pytest.skip("shared checks not present")
    for mode, extra in (("collaborative", []), ("symmetric", ["--expect-violation"])):
        if mode == "collaborative":  # (the session's coarse plan: `bladecam plan COARSE_ARGS`)
            out, res = coarse_plan
        else:
            out = tmp_path / mode
            # (an unsafe plan is written only when forced)
            res = cli(capsys, "plan", *COARSE_ARGS, "--mode", mode, "--force", "--out", out)
        assert res.returncode == 0, res.stderr
        assert ("unsafe" in res.stderr) == (mode == "symmetric")
        chk = subprocess.run([sys.executable, str(script), str(out), "1.875", "1.5", "1000", "500", *extra],
                             capture_output=True, text=True, timeout=600)
        lines = chk.stdout.strip().splitlines()
        if mode == "symmetric":
            assert chk.returncode == 0, chk.stdout[-2000:]
            continue
        assert chk.returncode == 0, lines
        assert "steps [1, 2, 3, 4, 5, 6, 7]" in lines[-1]


def test_modes_and_bad_inputs(plan):
    from core.errors import PlanningError

    single = build_schedule(plan, "single")
    assert single.duration > 0
    with pytest.raises(PlanningError, match="mode"):
        build_schedule(plan, "diagonal")
    with pytest.raises(PlanningError, match="impossible"):
        build_schedule(plan, feed=1000, a_max=1e-9)


SOURCES = ["sample", "table", "bladex"]


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dr=st.sampled_from([3.0, 4.0, 5.0]), h_ratio=st.floats(1.0, 1.5), k_max=st.floats(0.1, 0.2),
       a_max=st.floats(300.0, 2000.0), feed=st.floats(500.0, 2000.0), source=st.sampled_from(SOURCES))
def test_property_collaborative_plans_are_safe(dr, h_ratio, k_max, a_max, feed, source, tmp_path_factory):
    _collaborative_plan_is_safe(dr, h_ratio, k_max, a_max, feed, source, tmp_path_factory)


@settings(max_examples=2, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(h_ratio=st.floats(1.0, 1.5), k_max=st.floats(0.1, 0.2), a_max=st.floats(300.0, 2000.0),
       feed=st.floats(500.0, 2000.0), source=st.sampled_from(SOURCES[:2]))
def test_property_collaborative_plans_are_safe_fast(h_ratio, k_max, a_max, feed, source, tmp_path_factory):
    """The property test above on fewer, coarser plans (make test; the full one is marked slow)."""
    _collaborative_plan_is_safe(5.0, h_ratio, k_max, a_max, feed, source, tmp_path_factory)


def _collaborative_plan_is_safe(dr, h_ratio, k_max, a_max, feed, source, tmp_path_factory):
    """Whatever the parameters and the blade source, the collaborative schedule keeps the tip spacing
    >= h_safe at and between samples and the tools apart (recomputed here from the samples), and
    bladecam verify finds nothing in the written plan."""
    from core.blade.source import sample_table_path

    if source == "bladex":
        if not (BLADEX / "upper.stl").is_file():
            return
        src, axis = f"{BLADEX / 'upper.stl'},{BLADEX / 'lower.stl'}", "x"
    elif source == "table":
        p = tmp_path_factory.mktemp("t") / "blade.csv"
        p.write_text(sample_table_path().read_text().replace("# diameter_mm: 458.72", "# diameter_mm: 400"))
        src, axis = str(p), "z"
    else:
        src, axis = "sample", "z"
    blade = load_blade(src, axis=axis)
    params = PlanParameters(dr=dr, h_safe=1.5 * h_ratio, k_max=k_max, feed=feed, a_max=a_max)
    plan_ = plan_paths(blade, params, workers=2)
    from core.errors import PlanningError

    try:
        res = plan_on(plan_, source=src, axis=axis)
    except PlanningError as exc:
        # a high feed with a low a_max can leave a stage or a stop too short to fit: the planner
        # refuses with the remedy (a lower feed or a higher a_max); anything else is a failure
        msg = str(exc)
        assert "a_max" in msg and ("lower the feed" in msg or "cannot change speed" in msg), msg
        assert feed / a_max > 3.0, msg  # only where the feed is high for the acceleration
        return
    sch, tl = res.schedule, res.timeline
    d = tl.left.tips - tl.right.tips
    at = np.linalg.norm(d, axis=1)
    e = d[1:] - d[:-1]
    s = np.clip(-(d[:-1] * e).sum(1) / np.maximum((e * e).sum(1), 1e-18), 0, 1)
    between = np.linalg.norm(d[:-1] + s[:, None] * e, axis=1)
    h = plan_.params.h_safe
    assert at.min() >= h - 1e-6 and between.min() >= h - 1e-6
    fig = _figures(tl, plan_, sch)
    assert fig["capsule_violations"] == 0
    steps = set(tl.left.step) | set(tl.right.step)
    assert {1, 2, 7} <= steps
    # and the independent re-check of the written files finds nothing
    from core.output.writer import write_result
    from core.verify.check import verify

    out = tmp_path_factory.mktemp("plan") / "out"
    write_result(res, out)
    rep = verify(out)
    assert rep.findings == [], rep.findings[:5]


def test_a_resumed_round_equals_a_fresh_build():
    """A later safety round resumes at the first path whose margin changed: the same moves and stage
    records as building the whole schedule again with those margins."""
    from core.schedule.steps import ScheduleMemory, ScheduleOptions, _build_once

    paths = plan_paths(load_blade("sample"), PlanParameters(dr=1.0, h_safe=2.2, k_max=0.12), workers=2)
    coll = [p.index for p, r in zip(paths.pairs, paths.regions, strict=True) if not r.is_tip]
    changed = {coll[len(coll) // 2], coll[-3]}
    options, memo = ScheduleOptions(), {}
    first, builder = _build_once(paths, options, ScheduleMemory({}, memo), (None, set()))
    margins = {key: 3 for key in changed}
    resumed, b2 = _build_once(paths, options, ScheduleMemory(margins, memo), (builder, changed))
    fresh, _ = _build_once(paths, options, ScheduleMemory(margins, {}), (None, set()))
    assert b2.resume is not None and resumed.stages == fresh.stages and resumed.duration == fresh.duration
    assert resumed.stages != first.stages  # the margins did change the hand-overs
    for a, b in ((resumed.left, fresh.left), (resumed.right, fresh.right)):
        assert [(m.t0, m.law.duration, m.step, m.path) for m in a] == [(m.t0, m.law.duration, m.step, m.path) for m in b]
        assert all(np.array_equal(x.points, y.points) for x, y in zip(a, b, strict=True))


def test_a_feed_whose_period_is_off_the_time_grid_verifies_clean(tmp_path):
    """Found by the property test in CI: at 1937.76 mm/min the row period dd / feed is not a multiple
    of the CL tables' 1e-6 ms grid, rows were sampled at k * period but written rounded, and over the
    6-microsecond intervals round the edges that read as 384 mm/s^2 at a constant feed (a_max 360).
    Every row lies at k * period rounded to the grid, and the written plan verifies clean."""
    from core.output.writer import write_result
    from core.verify.check import verify

    feed, a_max = 1937.7648373234938, 360.0
    plan_ = plan_paths(load_blade("sample"), PlanParameters(dr=4.0, h_safe=2.25, k_max=0.140625, feed=feed,
                                                           a_max=a_max), workers=2)
    period = plan_.params.dd / (feed / 60000)
    assert abs(period * 1e6 - round(period * 1e6)) > 1e-3  # the case: a period off the grid
    res = plan_on(plan_, axes=True)
    tl = res.timeline
    np.testing.assert_array_equal(tl.t, np.round(np.arange(len(tl.t)) * period, 6))
    assert (np.diff(tl.t) > 0).all()
    out = tmp_path / "out"
    write_result(res, out)
    rep = verify(out)
    assert rep.findings == [], rep.findings[:5]


@pytest.mark.parametrize("case", ["sample", "sample-axes", "bladex", "bladex-short"])
def test_speed_is_continuous_across_every_hand_over(case, plan):
    """Where a symmetrical stretch hands over to a speed stage (E_vl / E_ss of step 5-6) or a stage
    to a symmetrical stretch (step 6 -> 4), the cutter's speed is the same on both sides of the
    instant: the stage starts or ends at the slope of the symmetrical stretch's own sync map at that
    end, times the master's speed there (it used the ratio of one interval, and jumped by up to 0.7 %
    where tilt-limited axes change the step lengths abruptly: 1148 mm/s^2 in the rows of the default
    --axes plan). Checked on the laws of every pair of consecutive moves: on the sample with and
    without the machine's tilt limit, and on BladeX, whose symmetrical stretches stop at tight corners
    and, at the "short" parameters, hand over below the feed where a stretch from rest is too short."""
    from core.machine.model import load_machine
    from core.machine.reach import machine_plan

    feed, a_max = 1000.0, 500.0
    if case.startswith("bladex"):
        if not (BLADEX / "upper.stl").is_file():
            pytest.skip("BladeX data not present")
        blade = load_blade(f"{BLADEX / 'upper.stl'},{BLADEX / 'lower.stl'}", axis="x")
        if case == "bladex":
            feed, a_max = 500.0, 2000.0
            params = PlanParameters(dr=3.0, h_safe=1.5, k_max=0.2, feed=feed, a_max=a_max)
        else:
            feed, a_max = 787.7102074360873, 488.9088900246051
            params = PlanParameters(tool_radius=1.0, dr=2.0, h_safe=1.406314097192766, k_max=0.15581471507747988,
                                    feed=feed, a_max=a_max)
        plan_ = plan_paths(blade, params, workers=2)
    else:
        plan_ = plan  # (the sample's paths at dR 2 mm, planned once per session)
    if case == "sample-axes":
        plan_, _ = machine_plan(plan_, load_machine(None))
    sch = build_schedule(plan_, "collaborative", feed, a_max)
    checked = moving = 0
    for moves in (sch.left, sch.right):
        for a, b in zip(moves[:-1], moves[1:], strict=True):
            if not (a.cutting and b.cutting) or a.law.duration <= 0 or b.law.duration <= 0:
                continue
            if abs(a.t1 - b.t0) > 1e-9 or a.path != b.path:
                continue
            va, vb = float(a.law.speed(a.law.duration)), float(b.law.speed(0.0))
            assert abs(va - vb) <= 1e-9 * max(va, vb) + 1e-15, (a.step, b.step, a.path, va * 60000, vb * 60000)
            checked += 1
            moving += vb > 0 and (type(a.law).__name__ == "MappedLaw" or type(b.law).__name__ == "MappedLaw")
    assert checked > (50 if case.startswith("sample") else 5)
    assert moving >= 2  # hand-overs at speed between a symmetrical stretch and a stage


MESH = ("--blade", f"{BLADEX / 'upper.stl'},{BLADEX / 'lower.stl'}", "--axis", "x")


def _plan_and_verify(capsys, out, *options: str) -> Ran:
    """``bladecam plan OPTIONS --out OUT`` (it must succeed), then ``bladecam verify OUT``, in-process:
    returns the verify run. With MESH among the options the BladeX data must be present (else the test
    skips)."""
    if options[:1] == ("--blade",) and options[1] == MESH[1] and not (BLADEX / "upper.stl").is_file():
        pytest.skip("BladeX data not present")
    res = cli(capsys, "plan", *options, "--out", out)
    assert res.returncode == 0, res.stderr
    return cli(capsys, "verify", out)


def _assert_clean(res: Ran) -> None:
    assert res.returncode == 0 and "ok: 0 findings" in res.stdout, res.stdout[-2000:]


@pytest.mark.slow
def test_bladex_default_plan_verifies_clean(tmp_path, capsys):
    """The real BladeX mesh at the default parameters (every path single-sided): bladecam verify
    finds nothing: no ball cuts a facet (chords across convex facet edges refined, 24 candidate
    facets per ball), no chord of the CL tables reads as an acceleration above a_max (the cutter
    stops at the contact path's tight corners where the ball rolls over a facet edge), and no part
    of the tool touches the blade (the contacts past the pair's seam round the tip and the hub go to
    the cutter they face: core.paths.single_sided.facing_sides)."""
    _assert_clean(_plan_and_verify(capsys, tmp_path / "bx", *MESH))


@pytest.mark.parametrize("mode", [
    # (make test: symmetric, every path's stretch symmetrical; the collaborative plan at these inputs in
    # make test-all: BladeX's collaborative plans at dR 3 verify clean in make test below, step 3's)
    pytest.param("collaborative", marks=pytest.mark.slow), "symmetric"])
def test_bladex_symmetrical_stretches_keep_speed_and_acceleration(tmp_path, mode, capsys):
    """The faceted BladeX mesh at a coarse dR has symmetrical stretches whose two contact paths step
    irregularly (micrometres to 0.2 mm, the two sides' ratio jumping by 5x): the cutters keep to the
    feed and a_max there (an interpolant through every pair overshot the feed by 13 % and read as
    64,000 mm/s^2), as bladecam verify finds from the written CL files."""
    res = _plan_and_verify(capsys, tmp_path / "bx", *MESH, "--dr", "3", "--feed", "500", "--a-max", "2000",
                           "--h-safe", "1.5", "--k-max", "0.2", "--mode", mode, "--force")
    speed = [ln for ln in res.stdout.splitlines() if "> feed" in ln or "accelerates" in ln]
    assert speed == [], speed[:5]
    peaks = dict(re.findall(r"(\w+_peak_\w+) ([\d.]+)", res.stdout))
    for side in ("left", "right"):
        assert float(peaks[f"{side}_peak_speed_mm_min"]) <= 500 * 1.0001
        assert float(peaks[f"{side}_peak_accel_mm_s2"]) <= 2000 * 1.001
    if mode == "collaborative":
        _assert_clean(res)


def test_leading_comes_down_only_once_the_subsequent_stands_at_s_vl(collaborative):
    """Step 3 starts with the leading cutter coming down onto S_vl of the first collaborative path;
    the subsequent cutter stands still at its S_vl the whole time (it used to be still cutting the
    edge stretch before S_vl, where the pair spacing is below h_safe)."""
    sch, tl = collaborative
    down = next(m for m in sch.left if m.step == 3 and not m.cutting)
    t = np.linspace(down.t0, down.t1, 200)
    left, right = (s.tips for s in sch.sample(t))
    assert np.abs(right - right[0]).max() == 0.0
    assert np.linalg.norm(left - right, axis=1).min() >= 1.875 - 1e-9  # h_safe, the default 1.25 r


def test_bladex_step_3_meeting_keeps_h_safe(tmp_path, capsys):
    """The parameters where the leading's descent at step 3 came within h_safe of the subsequent still
    cutting its edge stretch (BladeX, dR 3 mm; found by a random search): now planned and clean."""
    _assert_clean(_plan_and_verify(capsys, tmp_path / "bx", *MESH, "--dr", "3", "--h-safe", "1.703588703397576",
                                   "--k-max", "0.18796511733349222", "--a-max", "409.16454343072473",
                                   "--feed", "1518.7722995320473"))


def test_bladex_edge_stretches_stop_at_tight_corners(tmp_path, capsys):
    """The edge stretches after a stage (steps 5-7) stop at the contact path's tight corners like the
    single-sided paths do: at these parameters (found by a random search over tool radius, dd and
    the planning parameters) the leading cutter passed a facet-edge zig-zag at speed in step 7 and
    read as 36,800 mm/s^2 at a_max 305."""
    _assert_clean(_plan_and_verify(capsys, tmp_path / "bx", *MESH, "--tool-radius", "1.173699090130524", "--dd", "0.5",
                                   "--dr", "3.129864240348064", "--h-safe", "1.2182118486467488",
                                   "--k-max", "0.1392733637933634", "--a-max", "304.82917846623366",
                                   "--feed", "1192.4319152012456"))


def test_parked_leading_keeps_h_safe_from_the_subsequent_route(tmp_path, capsys):
    """In step 2 the leading backs off above S_vl of the first collaborative path while the subsequent
    comes down onto that path's start and cuts its edge stretch: with a thick tool and a coarse dd
    (found by a random search) the fixed 2 mm back-off left the tips 2.33 mm apart at h_safe 2.53 and
    the plan was refused; the back-off now grows until the route keeps 1.05 h_safe."""
    _assert_clean(_plan_and_verify(capsys, tmp_path / "p", "--tool-radius", "2.183037043963415", "--dd", "0.5",
                                   "--dr", "7.276790146545", "--h-safe", "2.52656735834171",
                                   "--k-max", "0.13722209592134166", "--a-max", "753.4745631241517",
                                   "--feed", "712.8109316059762"))


@pytest.mark.slow
def test_last_path_synchronisation_moves_inside_too(tmp_path, capsys):
    """The end-of-job stage of the last path is staggered like the others, so the self-check may move
    its synchronisation inside the path as well: at these parameters (found by hypothesis) the tips
    came to 0.994 mm at h_safe 1.0 in step 7 and the plan was refused after eight rounds. (A fine dd
    of 0.1 mm: make test-all.)"""
    _assert_clean(_plan_and_verify(capsys, tmp_path / "p", "--tool-radius", "1", "--dr", "2", "--dd", "0.1",
                                   "--h-safe", "1", "--k-max", "0.125", "--a-max", "300", "--feed", "500"))


def test_short_symmetrical_stretch_from_rest_hands_over_at_the_speed_it_reaches(tmp_path, capsys):
    """A symmetrical stretch from rest (step 3) too short to reach the feed before its stage hands over
    at the highest speed it reaches, instead of refusing the plan (BladeX, r 1 mm, feed 788 at
    a_max 489: 'a move of 0.1033 mm cannot change speed', found by hypothesis)."""
    res = _plan_and_verify(capsys, tmp_path / "bx", *MESH, "--tool-radius", "1", "--dr", "2",
                           "--h-safe", "1.406314097192766", "--k-max", "0.15581471507747988",
                           "--a-max", "488.9088900246051", "--feed", "787.7102074360873")
    peaks = dict(re.findall(r"(\w+_peak_\w+) ([\d.]+)", res.stdout))
    for side in ("left", "right"):
        assert float(peaks[f"{side}_peak_speed_mm_min"]) <= 787.7102074360873 * 1.0001
