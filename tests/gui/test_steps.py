"""The seven steps on the timeline: seven bands (a lane each) drawn where each step runs, the job's
step the earlier of the two cutters' (the second cutter's tip pass is step 2 on a plan with no
collaborative path, as on BladeX at the defaults), and the lanes' labels count the contours."""

import numpy as np
import pytest
from PySide6.QtGui import QColor

from bladecam_gui.style import STEPS

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def close(c: QColor, colour: str) -> bool:
    want = QColor(colour)
    return all(abs(a - b) <= 6 for a, b in zip(c.getRgb()[:3], want.getRgb()[:3], strict=True))


def test_seven_step_bands(planned, qtbot):
    w = planned
    data = w.state.plan
    bar = w.timeline.bar
    bar.fit()
    img = bar.grab().toImage()
    rects = [bar.lane_rect(k) for k in STEPS]
    # seven lanes, one above the other, inside the bar
    assert len(rects) == 7 and all(r.height() >= 6 for r in rects)
    assert all(a.bottom() < b.top() for a, b in zip(rects, rects[1:], strict=False))
    t = data.timeline.t
    for k, (_, _, colour) in STEPS.items():
        lane = bar.lane_rect(k)
        y = lane.center().y()
        # in its lane, step k's colour where (and only where) the job is in step k; sampled at the
        # middle of every run of the step wider than 3 px, and between them
        runs = data.bands[data.bands[:, 2] == k]
        assert len(runs), k
        wide = runs[(runs[:, 1] - runs[:, 0]) > 3 * bar.span / bar.width()]
        assert len(wide), k
        for t0, t1, _ in wide[:20]:
            x = int(bar.x_of(0.5 * (t0 + t1)))
            assert close(img.pixelColor(x, y), colour), (k, t0, t1)
        other = np.flatnonzero(data.step != k)
        # a sample of another step, away from any run of step k by more than 3 px
        near = 3 * bar.span / bar.width()
        quiet = [i for i in other[:: max(len(other) // 200, 1)]
                 if not ((runs[:, 0] - near <= t[i]) & (t[i] <= runs[:, 1] + near)).any()]
        assert quiet, k
        for i in quiet[:20]:
            assert not close(img.pixelColor(int(bar.x_of(t[i])), y), colour), (k, i)
    # the labels count the contours either cutter cuts in the step
    tl = data.timeline
    during = data.step == 4
    n4 = len(np.union1d(tl.left.path[during & tl.left.cutting], tl.right.path[during & tl.right.cutting]))
    assert bar.lane_texts[4] == f"4 symmetric · {n4} contours" and n4 > 1


def test_the_second_cutters_tip_pass_is_step_2(planned, qtbot):
    """K_max so low that no contour is collaborative (as on BladeX at the defaults): the left cutter
    machines the tip region and returns (its step 7) while the right cutter machines its own: the job
    is in step 2 then, not in step 7."""
    w = planned
    data = wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.02))
    tl = data.timeline
    assert not any(not r.is_tip for r in data.result.plan.regions)
    right_tip = tl.right.cutting & (tl.right.step == 2)
    assert right_tip.any() and (tl.left.step[right_tip] == 7).all()  # (the cutters' own steps)
    assert (data.step[right_tip] == 2).all()
    # step 7 is the job's finish: once both cutters are in it
    assert (data.step == 7).sum() == ((tl.left.step == 7) & (tl.right.step == 7)).sum()
    i = int(np.flatnonzero(right_tip)[len(np.flatnonzero(right_tip)) // 2])
    w.state.set_cursor(i)
    qtbot.waitUntil(lambda: f"sample {i} " in w.timeline.readout.text())
    assert f"step 2: {STEPS[2][0]}" in w.timeline.readout.text()
    assert set(w.timeline.bar.bands[:, 2].astype(int)) == {1, 2, 7}
