"""The planner (core.planner.Planner, used by the CLI and the workbench), the writer
(core.output.writer: PlanWriter as the planner's listener, write_result) and the region re-plan that
reuses the paths."""

from __future__ import annotations

import numpy as np
import pytest

from core.blade.source import load_blade
from core.errors import Cancelled, OutputError, PlanningError
from core.output.writer import EarlyPairs, EarlyTables, PlanWriter, write_result
from core.paths.planning import plan_paths, replan_regions
from core.planner import Planner
from core.records import PlanJob, PlanParameters

from ..conftest import plan_on


@pytest.fixture(scope="module")
def blade():
    return load_blade("sample")


@pytest.fixture(scope="module")
def coarse(sample_paths):
    return sample_paths(dr=4.0, h_safe=1.5)


def test_replan_regions_equals_a_fresh_plan(blade, coarse):
    new = PlanParameters(dr=4.0, h_safe=1.9, k_max=0.11)
    again = replan_regions(coarse, new)
    fresh = plan_paths(blade, new)
    assert [r.is_tip for r in again.regions] == [r.is_tip for r in fresh.regions]
    assert sum(r.is_tip for r in again.regions) != sum(r.is_tip for r in coarse.regions)
    for a, b, ra, rb in zip(again.pairs, fresh.pairs, again.regions, fresh.regions, strict=True):
        np.testing.assert_array_equal(ra.labels, rb.labels)
        np.testing.assert_allclose(a.left_tip, b.left_tip, atol=1e-12)
        np.testing.assert_allclose(a.right_axis, b.right_axis, atol=1e-12)
        assert ra.boundaries == rb.boundaries


def test_replan_regions_refuses_a_geometry_change(coarse):
    with pytest.raises(PlanningError, match="dd"):
        replan_regions(coarse, PlanParameters(dr=4.0, dd=0.3))


def test_a_plan_cancels():
    with pytest.raises(Cancelled):
        Planner(workers=1).plan(PlanJob("sample", "z", PlanParameters(dr=4.0), axes=False),
                                progress=lambda f, m: f < 0.3)


def test_write_result_refuses_an_unsafe_collaborative_plan(coarse, tmp_path):
    res = plan_on(coarse, params=PlanParameters(dr=4.0, h_safe=1.5))
    assert res.safe and res.figures["spacing_violations"] == 0
    unsafe = type(res)(**{**res.__dict__, "figures": {**res.figures, "spacing_violations": 3}})
    out = tmp_path / "plan"
    with pytest.raises(PlanningError, match="nothing was written"):
        write_result(unsafe, out)
    assert not out.exists()
    write_result(unsafe, out, force=True)
    assert {p.name for p in out.iterdir()} == {"pairs.csv", "plan.json", "left_cl.csv", "right_cl.csv", "tool.toml",
                                              "blade.stl"}


def test_sample_speeds_match_differences_of_positions(coarse):
    from core.schedule.movetable import MoveTable

    sch = plan_on(coarse, params=PlanParameters(dr=4.0, h_safe=1.5)).schedule
    t = np.linspace(0.0, sch.duration, 100001)
    for moves in (sch.left, sch.right):
        table = MoveTable(moves)
        v = table.speeds(t)
        tips = table.sample(t).tips
        diff = np.linalg.norm(np.diff(tips, axis=0), axis=1) / np.diff(t)
        mid = 0.5 * (v[1:] + v[:-1])
        assert np.percentile(np.abs(diff - mid), 99) < 5e-5  # mm/ms; the rest is at vertices
        assert v.max() <= sch.feed / 60000.0 * 3.0 + 1e-9 and v.min() >= -1e-12


def test_a_plan_cancels_inside_the_schedule(coarse):
    """A cancel while the schedule or the machine timing run stops them there."""
    seen = []

    def progress(f, msg):
        seen.append(msg)
        return not msg.startswith("schedule:")

    with pytest.raises(Cancelled):
        plan_on(coarse, params=PlanParameters(dr=4.0, h_safe=1.5), progress=progress)
    assert seen[-1] == "schedule: safety rounds"
    seen.clear()
    with pytest.raises(Cancelled):
        plan_on(coarse, params=PlanParameters(dr=4.0, h_safe=1.5), axes=True,
                progress=lambda f, m: (seen.append(m), m != "machine timing")[1])
    assert seen[-1] == "machine timing"


def test_tables_written_beside_are_the_same(coarse, tmp_path):
    """The tables written beside the plan folder in threads are the same bytes as those formatted
    into it when there is no folder to write beside; a forked helper's failure is an error naming
    the file, with nothing written."""
    from core.errors import OutputError
    from core.output.csvio import beside
    from core.output.files import cl_csv

    res = plan_on(coarse, params=PlanParameters(dr=4.0, h_safe=1.5), axes=True)
    one, two = tmp_path / "one", tmp_path / "new" / "two"  # (two: no folder to write beside)
    write_result(res, one, workers=1)
    write_result(res, two, workers=2)
    for name in ("left_cl.csv", "right_cl.csv", "pairs.csv", "left_axes.csv", "right_axes.csv"):
        assert (one / name).read_bytes() == (two / name).read_bytes()
    assert (one / "right_cl.csv").read_bytes() == cl_csv(res.timeline.t, res.timeline.right)

    def broken(*args):
        raise ValueError("no room")

    with beside([("right_cl.csv", broken, ())], 2) as others, pytest.raises(OutputError, match="right_cl.csv"):
        others()


def test_forked_paths_are_reusable_report_progress_and_cancel(blade, coarse):
    """With workers the paths come back from forked processes: the same pairs as in one process, with
    their fitted curves when asked (the workbench re-plans regions from them), progress per finished
    chunk, and a cancel that stops the pool."""
    seen = []
    two = plan_paths(blade, coarse.params, workers=2, reusable=True,
                     progress=lambda f, m: seen.append(f) is None)
    assert two.reuse is not None and len(seen) >= 8 and seen == sorted(seen)
    for a, b in zip(two.pairs, coarse.pairs, strict=True):
        np.testing.assert_array_equal(a.left_tip, b.left_tip)
    new = PlanParameters(dr=4.0, h_safe=1.9, k_max=0.11)
    again, fresh = replan_regions(two, new), replan_regions(coarse, new)
    assert [r.boundaries for r in again.regions] == [r.boundaries for r in fresh.regions]
    assert plan_paths(blade, coarse.params, workers=2).reuse is None  # not asked: curves stay behind
    with pytest.raises(Cancelled):
        plan_paths(blade, coarse.params, workers=2, progress=lambda f, m: f < 0.2)


def test_a_helper_that_dies_is_an_error():
    import os

    from core.errors import OutputError
    from core.output.csvio import beside

    def die(*args):
        os._exit(3)

    with beside([("right_cl.csv", die, ())], 2) as others, pytest.raises(OutputError, match="exit code 3"):
        others()


def _started(writer: PlanWriter) -> tuple[list, list]:
    """(the table writers, the early pairs.csv writers) a PlanWriter has started and not yet closed."""
    tables = [writer._tables] if writer._tables is not None else []
    pairs = [writer._pairs] if writer._pairs is not None else []
    assert all(isinstance(h, EarlyTables) for h in tables) and all(isinstance(h, EarlyPairs) for h in pairs)
    return tables, pairs


def test_early_tables_are_the_same_and_a_refusal_ends_the_writers(coarse, tmp_path):
    """A PlanWriter (workers > 1) as the planner's listener starts writing both sides' tables beside
    its folder, one thread per side, while the planner computes the figures, and writes pairs.csv in a
    thread while it plans the schedule, when the folder's parent exists (else they are written with the
    rest): write moves the same bytes in and leaves nothing beside it; when it refuses the plan
    instead, the threads are stopped, their scratch folders removed and nothing is written."""
    params = PlanParameters(dr=4.0, h_safe=1.5)
    plain = plan_on(coarse, params=params)
    write_result(plain, tmp_path / "plain", workers=1)
    written = {"plain"}
    for out_dir, spooled in ((tmp_path / "new" / "early", False), (tmp_path / "early", True)):
        writer = PlanWriter(out_dir, workers=2)
        early = plan_on(coarse, params=params, workers=2, listener=writer)
        tables, pairs = _started(writer)
        assert len(tables) == spooled and len(pairs) == spooled
        writer.write(early)
        assert _started(writer) == ([], [])
        assert all(not h.spool.exists() for h in (*tables, *pairs))
        for name in ("left_cl.csv", "right_cl.csv", "pairs.csv"):
            assert (tmp_path / "plain" / name).read_bytes() == (out_dir / name).read_bytes()
        written.add(out_dir.relative_to(tmp_path).parts[0])
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(written)
        assert [p.name for p in out_dir.parent.iterdir() if p.name.startswith(".")] == []  # no scratch left

    writer = PlanWriter(tmp_path / "refused", workers=2)
    again = plan_on(coarse, params=params, workers=2, listener=writer)
    tables, pairs = _started(writer)
    assert len(tables) == 1 and len(pairs) == 1
    unsafe = type(again)(**{**again.__dict__, "figures": {**again.figures, "spacing_violations": 1}})
    with pytest.raises(PlanningError, match="nothing was written"):
        writer.write(unsafe)
    # no folder, no scratch left, no thread running
    assert sorted(p.name for p in tmp_path.iterdir()) == ["early", "new", "plain"]
    assert not any(t.is_alive() for h in (*tables, *pairs) for t in h.threads)
    for h in (*tables, *pairs):
        h.close()  # closing twice is harmless
    writer.close()


def test_early_pairs_cleared_on_cancel_and_on_a_failed_write(coarse, tmp_path, monkeypatch):
    """pairs.csv written early (EarlyPairs, by a PlanWriter as the planner's listener): a run cancelled
    after the paths leaves no scratch folder once the writer is closed (as the command line's `with`
    does); a write that fails is reported by PlanWriter.write as any failed write of the plan folder
    is (an OutputError naming the folder: the command line's clear error), and nothing is written."""
    import core.output.writer

    params = PlanParameters(dr=4.0, h_safe=1.5)

    def cancel_at_schedule(fraction, message):
        return message != "schedule"

    with PlanWriter(tmp_path / "cancelled", workers=2) as writer:
        with pytest.raises(Cancelled):
            plan_on(coarse, params=params, workers=2, listener=writer, progress=cancel_at_schedule)
        assert len(_started(writer)[1]) == 1  # pairs.csv was started beside the folder before the cancel
    assert list(tmp_path.iterdir()) == []

    def broken(plan):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(core.output.writer, "pairs_csv", broken)
    writer = PlanWriter(tmp_path / "full", workers=2)
    res = plan_on(coarse, params=params, workers=2, listener=writer)
    with pytest.raises(OutputError, match="cannot write the plan to .*full: No space left"):
        writer.write(res)
    assert list(tmp_path.iterdir()) == []
