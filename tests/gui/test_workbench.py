"""The window opens on the sample blade with a plan: 3D view, status figures, screenshot colours."""

import numpy as np
import pytest

from bladecam_gui.style import LEFT_COLOUR, REGIONS, RIGHT_COLOUR

from .conftest import hue_mask, side_view_instant

pytestmark = pytest.mark.gui


def test_sample_plan_shown(fresh_planned, qtbot):
    w = fresh_planned
    data = w.state.plan
    assert data.has_schedule and data.result.source == "sample"
    # blade, paths (every region of the sample blade), both cutters, frame axes
    assert set(w.viewport.blade.actors) == {"face", "back"}
    counts = w.viewport.paths.counts()
    assert all(counts[name] > 0 for name in REGIONS), counts
    assert set(w.viewport.cutters.actors) == {"left", "right"}
    assert w.viewport.frame_axes.actors
    # the status bar states the plan's figures
    fig = data.result.figures
    text = w.figures.text()
    regions = data.result.plan.region_counts()
    assert f"{regions['paths']} paths: {regions['tip_paths']} tip" in text
    assert f"total {fig['total_time_s'] / 60:.1f} min" in text
    assert f"min spacing {fig['min_tip_spacing_mm']:.3f} mm" in text and "safe" in text
    # the timeline covers the job; the plots carry the time column
    assert w.timeline.isEnabled() and w.timeline.bar.duration == pytest.approx(data.timeline.t[-1])
    steps = set(data.bands[:, 2].astype(int))
    assert steps == set(range(1, 8)), steps
    x, y = w.spacing_plot.spacing_curve.getOriginalDataset()
    assert len(x) == len(data.timeline.t) and np.allclose(y, data.spacing)
    # the feed plot: both cutters' speeds while cutting, in a window that follows the cursor
    _, v = w.feed_plot.left_curve.getOriginalDataset()
    cutting = data.timeline.left.cutting
    assert np.isnan(v[~cutting]).all() and np.allclose(v[cutting], data.speed_left[cutting])
    assert v[cutting].max() <= data.result.plan.params.feed * 1.001
    # its strip: where the machine clock runs below 0.99 of the schedule's speed, by what slows it
    from core.machine.tables import SLOWED_BELOW, SLOWED_FOR

    scale = data.result.warp.scale
    shown = np.zeros(len(scale), bool)
    for code, curve in w.feed_plot.slowed.items():
        x, y = curve.getOriginalDataset()
        assert len(x) == len(scale) and SLOWED_FOR[code] in curve.name()
        marked = np.isfinite(y)
        assert np.array_equal(marked, data.result.warp.slowed_for == code)
        shown |= marked
    assert shown.any() and np.array_equal(shown, scale < SLOWED_BELOW)
    w.state.set_cursor(len(data.timeline.t) // 2)
    from bladecam_gui.widgets.plots import MS

    def window_follows():
        lo, hi = w.feed_plot.view_box.viewRange()[0]
        width = pytest.approx(w.feed_plot.WINDOW_MIN, rel=0.05)
        return lo < w.state.cursor_time / MS < hi and hi - lo == width

    qtbot.waitUntil(window_follows)


def test_screenshot_shows_blade_and_both_cutters(planned, qtbot):
    w = planned
    data = w.state.plan
    tl = data.timeline
    w.state.set_cursor(side_view_instant(data))  # both cutting, seen from the side (the chord axis)
    i = w.state.cursor
    centre = 0.5 * (tl.left.tips[i] + tl.right.tips[i])
    p = w.viewport.plotter
    w.viewport.view("side")
    p.camera.focal_point = centre
    p.camera.position = centre + np.array([0.0, -250.0, 0.0])
    p.camera.up = (1.0, 0.0, 0.0)
    img = w.viewport.screenshot()
    assert img.ndim == 3 and img.shape[0] > 200
    flat = img.reshape(-1, 3)
    assert len(np.unique(flat, axis=0)) > 100, "one flat colour: nothing drawn"
    left = hue_mask(img, LEFT_COLOUR).sum()
    right = hue_mask(img, RIGHT_COLOUR).sum()
    # the blade: light, low-saturation pixels like its face colour
    light = ((flat.min(axis=1) > 110) & (flat.max(axis=1) - flat.min(axis=1) < 60)).sum()
    assert left > 200 and right > 200, (left, right)
    assert light > 2000, light
    # hide the cutters: their colours go (the pixels were theirs, not something else's)
    w.viewport.cutters.set_visible(False)
    img2 = w.viewport.screenshot()
    assert hue_mask(img2, LEFT_COLOUR).sum() < 0.05 * left
    assert hue_mask(img2, RIGHT_COLOUR).sum() < 0.05 * right


def test_views_and_about(planned, dialogs):
    w = planned
    cam = w.viewport.plotter.camera
    w.viewport.view("front")
    front = np.array(cam.direction)
    w.viewport.view("side")
    side = np.array(cam.direction)
    w.viewport.view("iso")
    iso = np.array(cam.direction)
    assert abs(abs(front[2]) - 1) < 1e-6 and abs(abs(side[1]) - 1) < 1e-6
    assert np.all(np.abs(iso) > 0.3)
    about = [a for a in w.menuBar().actions() if a.text() == "&Help"][0].menu().actions()[0]
    about.trigger()
    title, text = dialogs["about"][0]
    assert "bladecam" in title and "PySide6" in text and "VTK" in text and "pyvista" in text
    assert f"<td>3D view</td><td>{w.viewport.kind}</td>" in text and "OpenGL: " in text
