"""Plausible propeller geometry tables drawn at random (chord, thickness, pitch, skew, rake, diameter
varied round the sample's), each planned in full with the machines: the plan keeps the safety rule
(a path the schedule cannot make safe goes single-sided, it is never refused for safety), and a plan
that keeps the machines' limits is written and passes `bladecam verify`; no plan's tool assembly or
heads collide (with the blade, the clamp or each other: core.machine.collisions)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from core.output.writer import write_result
from core.planner import Planner
from core.records import PlanJob, PlanParameters
from core.verify.check import verify

SAMPLE = Path(__file__).resolve().parents[3] / "resources" / "sample_blade.csv"


def _sample_rows() -> np.ndarray:
    lines = [ln for ln in SAMPLE.read_text().splitlines() if ln and not ln.startswith("#")]
    return np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


def table_text(chord: float, thickness: float, pitch: float, skew_deg: float, rake: float,
               diameter: float) -> str:
    """A geometry table: the sample's rows with chord and thickness ratios scaled, P/D shifted, the
    skew and rake laid on as smooth functions of r/R, at another diameter."""
    rows = _sample_rows().copy()
    x = (rows[:, 0] - 0.2) / 0.8
    rows[:, 1] *= chord
    rows[:, 3] = np.minimum(rows[:, 3] * thickness, 0.3)
    rows[:, 2] = np.maximum(rows[:, 2] + pitch, 0.3)
    rows[:, 5] = skew_deg * x**2
    rows[:, 6] = rake * x
    head = ["# name: generated blade", "# blades: 5", f"# diameter_mm: {diameter:.3f}", "# hub_ratio: 0.2",
            "# meanline: NACA a=0.8", "# thickness: NACA 66 mod", "r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D"]
    return "\n".join(head + [",".join(f"{v:.7f}" for v in row) for row in rows]) + "\n"


BLADES = dict(chord=st.floats(0.75, 1.25), thickness=st.floats(0.6, 1.4), pitch=st.floats(-0.3, 0.3),
              skew_deg=st.floats(-10.0, 35.0), rake=st.floats(-0.03, 0.05), diameter=st.floats(300.0, 600.0))


@pytest.mark.slow
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(blade=st.fixed_dictionaries(BLADES), h_ratio=st.floats(1.0, 1.5), k_max=st.floats(0.1, 0.2))
def test_generated_tables_plan_safely_and_verify(tmp_path_factory, blade, h_ratio, k_max):
    _plans_safely_and_verifies(tmp_path_factory, blade, 3.0, h_ratio, k_max)


@settings(max_examples=1, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(blade=st.fixed_dictionaries(BLADES), h_ratio=st.floats(1.0, 1.5), k_max=st.floats(0.1, 0.2))
def test_generated_tables_plan_safely_and_verify_fast(tmp_path_factory, blade, h_ratio, k_max):
    """The property test above on one coarser plan (make test; the full one is marked slow)."""
    _plans_safely_and_verifies(tmp_path_factory, blade, 5.0, h_ratio, k_max)


def _plans_safely_and_verifies(tmp_path_factory, blade: dict, dr: float, h_ratio: float, k_max: float) -> None:
    folder = tmp_path_factory.mktemp("table")
    table = folder / "blade.csv"
    table.write_text(table_text(**blade))
    params = PlanParameters(dr=dr, h_safe=1.5 * h_ratio, k_max=k_max)
    res = Planner(workers=2).plan(PlanJob(str(table), "z", params, axes=True))
    assert res.safe, res.figures["min_tip_spacing_mm"]
    assert res.figures["min_tip_spacing_mm"] >= params.h_safe - 1e-6
    assert not res.collisions, [c.describe(res.timeline.t) for c in res.collisions[:3]]  # (whole tool)
    if res.blocking_findings:  # (refused for the machines' limits: named in the findings)
        return
    out = write_result(res, folder / "plan", workers=2)
    findings = verify(out).findings
    assert not findings, findings[:5]
