"""The 3D view's inspection tools, driven through the View options panel as an operator would: the
blade coloured by the scallop height (against the plan's per-path figures, cell by cell), the section
at the cursor's contour (following the cursor) and the measuring tool (two clicks on the blade)."""

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from vtkmodules.vtkRenderingCore import vtkCoordinate

from bladecam_gui.render.blade_view import SCALLOP_BAR, SCALLOP_NONE, SCALLOP_UNCUT, cell_scallops, scallop_bands

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def _radius(vp, points):
    f = vp.blade.blade.frame
    b = (np.asarray(points) - f.translation) @ f.rotation
    return np.hypot(b[:, 0], b[:, 1])


def test_the_scallop_map_colours_each_cell_by_the_strips_it_crosses(window, qtbot):
    """dR 2 mm: below the ball's diameter (3 mm), the strips between the paths are cut."""
    w = window
    w.state.set_param("dr", 2.0)
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    vp = w.viewport
    fig = data.result.figures["scallop"]
    per_path = fig["per_path_max_mm"]
    w.view_options.inspect["scallop"].setChecked(True)
    assert vp.blade.scallop is not None
    bar = vp.plotter.scalar_bars[SCALLOP_BAR]
    assert bar.GetVisibility()
    # the strips: between each path and the next towards the hub, the outer path's figure
    by_r = sorted(data.result.plan.paths, key=lambda p: p.r)
    strips = [(b.r, a.r, per_path[str(a.index)]) for b, a in zip(by_r, by_r[1:], strict=False)
              if str(a.index) in per_path]
    values = [h for *_, h in strips if h is not None]
    assert values and data.result.plan.params.dr == 2.0
    for key, actor in vp.blade.actors.items():
        mesh = actor.mapper.dataset
        shown = np.asarray(mesh.cell_data["scallop"])
        assert actor.mapper.scalar_range == pytest.approx((0.0, max(values)))
        # every tenth cell against its own corners' radii (an independent walk over the strips)
        for c in range(0, mesh.n_cells, 10):
            r = _radius(vp, mesh.get_cell(c).points)
            lo, hi = r.min(), r.max()
            crossed = [h for r0, r1, h in strips if r0 < hi and r1 > lo]
            if not crossed:
                assert np.isnan(shown[c])
            elif None in crossed:
                assert shown[c] == np.inf
            else:
                assert shown[c] == pytest.approx(max(crossed))
    # the strips cover the blade between the paths: the map's largest is the plan's largest
    assert max(np.nanmax(vp.blade.scallop[k][np.isfinite(vp.blade.scallop[k])]) for k in ("face", "back")) \
        == pytest.approx(max(values))
    assert max(values) == pytest.approx(fig["max_mm"])
    # off again: the plain blade, no bar
    w.view_options.inspect["scallop"].setChecked(False)
    assert vp.blade.scallop is None and SCALLOP_BAR not in vp.plotter.scalar_bars
    assert all(a.mapper.scalar_visibility is False for a in vp.blade.actors.values())


def test_scallop_strips_uncut_and_outside():
    """cell_scallops on a made-up grid: a cell over an uncut strip is inf, one outside every strip NaN,
    one across two strips the larger."""
    class P:
        def __init__(self, index, r):
            self.index, self.r = index, r

    paths = [P(0, 30.0), P(1, 20.0), P(2, 10.0)]
    bands = scallop_bands(paths, {"0": 0.02, "1": None})
    assert bands.tolist() == [[10.0, 20.0, np.inf], [20.0, 30.0, 0.02]]
    radius = np.array([[5.0, 5.0], [8.0, 8.0], [25.0, 25.0], [28.0, 28.0], [40.0, 40.0]])
    h = cell_scallops(radius, bands)
    assert np.isnan(h[0]) and h[1] == np.inf and h[2] == pytest.approx(0.02) and h[3] == pytest.approx(0.02)
    assert SCALLOP_UNCUT != SCALLOP_NONE


def test_the_section_follows_the_cursors_contour(planned, qtbot):
    w = planned
    vp, data = w.viewport, w.state.plan
    tl, pairs = data.timeline, data.result.plan.pairs
    w.view_options.inspect["section"].setChecked(True)
    cutting = np.nonzero(tl.left.cutting & (tl.left.path >= 0))[0]
    seen = set()
    for i in (cutting[len(cutting) // 5], cutting[4 * len(cutting) // 5]):
        w.state.set_cursor(int(i))
        r = pairs[int(tl.left.path[i])].r
        seen.add(round(r, 6))
        assert vp.blade.section_r == pytest.approx(r)
        for actor in vp.blade.actors.values():  # the tip side removed
            assert _radius(vp, actor.mapper.dataset.points).max() <= r + 1e-6
        outline = np.asarray(vp.blade.outline.mapper.dataset.points)
        assert len(outline) and np.allclose(_radius(vp, outline), r, atol=1e-6)
    assert len(seen) == 2  # two contours
    w.view_options.inspect["section"].setChecked(False)
    assert vp.blade.section_r is None and vp.blade.outline is None
    assert sum(a.mapper.dataset.n_points for a in vp.blade.actors.values()) == \
        sum(m.n_points for m in vp.blade.meshes.values())


def _widget_pixel(vp, point) -> QPoint:
    """The widget's pixel showing the point (3,) in W."""
    c = vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, point))
    x, y = c.GetComputedDoubleDisplayValue(vp.plotter.renderer)
    w, h = vp.plotter.ren_win.GetSize()
    return QPoint(round(x * vp.widget.width() / w), round((h - 1 - y) * vp.widget.height() / h))


def test_measuring_two_points_on_the_blade(planned, qtbot):
    w = planned
    vp = w.viewport
    w.view_options.boxes["paths"].setChecked(False)  # (the paths lie over the face)
    w.view_options.boxes["left"].setChecked(False)
    w.view_options.boxes["right"].setChecked(False)
    vp.view("front")
    w.view_options.inspect["measure"].setChecked(True)
    face = vp.blade.blade.face
    targets = [face[len(face) // 2, 20], face[len(face) // 2, 60]]
    for target in targets:
        qtbot.mouseClick(vp.widget, Qt.MouseButton.LeftButton, pos=_widget_pixel(vp, target))
    qtbot.waitUntil(lambda: len(vp.measure.points) == 2)
    size = float(np.max(np.ptp(face.reshape(-1, 3), axis=0)))
    pixel = size / min(vp.widget.width(), vp.widget.height())  # (the fitted view: at most this per pixel)
    for got, want in zip(vp.measure.points, targets, strict=True):
        # the face's surface under the target's pixel (the back lies millimetres behind it)
        assert np.linalg.norm(got - want) < 3 * pixel
    d = vp.measure.distance
    assert d == pytest.approx(float(np.linalg.norm(vp.measure.points[1] - vp.measure.points[0])))
    assert d == pytest.approx(float(np.linalg.norm(targets[1] - targets[0])), abs=6 * pixel)
    assert vp.measure.text == f"{d:.3f} mm" and len(vp.measure.actors) == 3  # points, line, label
    # a third click starts again; off removes the measurement
    qtbot.mouseClick(vp.widget, Qt.MouseButton.LeftButton, pos=_widget_pixel(vp, targets[0]))
    qtbot.waitUntil(lambda: len(vp.measure.points) == 1)
    w.view_options.inspect["measure"].setChecked(False)
    assert vp.measure.points == [] and vp.measure.actors == []
    # not measuring: a click picks nothing
    qtbot.mouseClick(vp.widget, Qt.MouseButton.LeftButton, pos=_widget_pixel(vp, targets[0]))
    assert vp.measure.points == []
