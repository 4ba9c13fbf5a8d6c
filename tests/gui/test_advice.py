"""The advice says how far to go: the K_max values it names really make the number of contours it
states collaborative (re-planned and counted), and a value outside the paper's range says so."""

import re

import pytest

from bladecam_gui.advice import PAPER_K_MAX, k_max_options

from .conftest import wait_plan
from .test_parameters import type_value

pytestmark = pytest.mark.gui

OPTION = re.compile(r"to (\d+(?:\.\d+)?) \(([^)]*)\): (\d+)( of \d+ paths collaborative)?(, outside the paper's)?")


def named_options(text: str) -> list[tuple[float, int, bool]]:
    """(K_max, paths, said to be outside the paper's range) of each value the advice names."""
    return [(float(v), int(n), bool(out)) for v, _why, n, _of, out in OPTION.findall(text)]


def collaborative(data) -> int:
    return sum(not r.is_tip for r in data.result.plan.regions)


@pytest.mark.parametrize("h_safe", [None, 2.25])
def test_the_advised_k_max_gives_the_stated_count(planned, qtbot, h_safe):
    w = planned
    if h_safe is not None:  # longer edge stretches: half the contours needs a K_max above the paper's
        wait_plan(qtbot, w, lambda: type_value(qtbot, w.params_panel.spins["h_safe"], f"{h_safe}"))
    data = w.state.plan
    n = len(data.result.plan.regions)
    qtbot.waitUntil(lambda: w.share_panel.warning.isVisible())
    text = w.share_panel.warning.text()
    assert text in w.figures.text()  # the status bar says the same
    options = named_options(text)
    assert options, text
    assert [o.value for o in k_max_options(data.result.plan)] == [v for v, _, _ in options]
    assert f"{options[0][1]} of {n} paths collaborative" in text
    for value, paths, outside in options:
        assert outside == (not PAPER_K_MAX[0] <= value <= PAPER_K_MAX[1])
        if outside:
            assert "outside the method" in text
        # the operator types the advised value: the new plan has that many collaborative paths
        again = wait_plan(qtbot, w, lambda v=value: type_value(qtbot, w.params_panel.spins["k_max"], f"{v}"))
        assert again.result.plan.params.k_max == value
        assert collaborative(again) == paths, (value, paths, collaborative(again))
    if h_safe is not None:
        assert any(out for _, _, out in options), text
