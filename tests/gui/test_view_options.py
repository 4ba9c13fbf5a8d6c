"""The 3D view's options panel (bladecam_gui.widgets.view_options), driven as an operator would: the
blade's opacity and the show/hide boxes change the actors; one face's paths; the current contour
emphasised; the bottom and top views; the camera that follows a cutter keeps it mid-view over a scrub."""

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

pytestmark = pytest.mark.gui


def _visible(actor) -> bool:
    return bool(actor.GetVisibility())


def test_opacity_and_show_hide_change_the_actors(planned, qtbot):
    w = planned
    opts, vp = w.view_options, w.viewport
    assert all(a.prop.opacity == 1.0 for a in vp.blade.actors.values())
    opts.blade_opacity.setValue(35)
    assert all(a.prop.opacity == pytest.approx(0.35) for a in vp.blade.actors.values())
    box = opts.boxes["blade"]  # (on the indicator: the box may be wider than its label)
    qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=QPoint(8, box.height() // 2))
    assert not opts.boxes["blade"].isChecked()
    assert not any(_visible(a) for a in vp.blade.actors.values())
    opts.boxes["paths"].setChecked(False)
    assert not _visible(vp.paths.actor)
    opts.boxes["left"].setChecked(False)
    assert not _visible(vp.cutters.actors["left"]) and _visible(vp.cutters.actors["right"])
    # the choices hold across a new plan (the same plan shown again) and a cursor move
    w.state.set_plan(w.state.plan)
    w.state.set_cursor(w.state.cursor + 5)
    assert not any(_visible(a) for a in vp.blade.actors.values())
    assert all(a.prop.opacity == pytest.approx(0.35) for a in vp.blade.actors.values())
    assert not _visible(vp.paths.actor)
    assert not _visible(vp.cutters.actors["left"]) and _visible(vp.cutters.actors["right"])
    for key in ("blade", "paths", "left"):
        opts.boxes[key].setChecked(True)
    assert all(_visible(a) for a in vp.blade.actors.values()) and _visible(vp.paths.actor)
    assert _visible(vp.cutters.actors["left"])
    # the machines: off by default, on with their box, their opacity from the slider
    assert not any(vp.machines.visible(s) for s in ("left", "right"))
    opts.boxes["machines"].setChecked(True)
    assert vp.machines.actors and any(vp.machines.visible(s) for s in ("left", "right"))
    opts.machine_opacity.setValue(50)
    assert all(a.prop.opacity == pytest.approx(0.5) for a in vp.machines.actors.values())
    opts.boxes["machines"].setChecked(False)
    assert not any(vp.machines.visible(s) for s in ("left", "right"))


def test_one_face_and_the_current_contour(planned, qtbot):
    w = planned
    opts, paths = w.view_options, w.viewport.paths
    lines = w.state.plan.lines
    total = len(lines.region)
    assert paths.mesh.n_cells == total
    counts = {}
    for face in ("left", "right"):
        opts.face.setCurrentIndex(opts.face.findData(face))
        counts[face] = paths.mesh.n_cells
        assert 0 < counts[face] < total
        # every segment shown lies on that side's paths (the tips of the plan's pairs)
        pts = np.asarray(paths.mesh.points)[np.asarray(paths.mesh.lines).reshape(-1, 3)[:, 1]]
        side_pts = np.concatenate([getattr(p, f"{face}_tip") for p in w.state.plan.result.plan.pairs])
        other = np.concatenate([getattr(p, f"{'right' if face == 'left' else 'left'}_tip")
                                for p in w.state.plan.result.plan.pairs])
        probe = pts[:: max(1, len(pts) // 50)]
        near_side = np.min(np.linalg.norm(probe[:, None] - side_pts[None, ::4], axis=2), axis=1)
        near_other = np.min(np.linalg.norm(probe[:, None] - other[None, ::4], axis=2), axis=1)
        assert (near_side <= near_other).all()
    assert counts["left"] + counts["right"] == total
    opts.face.setCurrentIndex(opts.face.findData("both"))
    assert paths.mesh.n_cells == total
    # the current contour and its neighbours, thicker, over the others dimmed
    tl = w.state.plan.timeline
    i = int(np.nonzero(tl.left.path == 10)[0][0])
    w.state.set_cursor(i)
    assert paths.emphasis is None
    opts.emphasis.setChecked(True)
    assert paths.current == 10 and paths.emphasis is not None and paths.actor.prop.opacity < 0.5
    assert paths.emphasis.prop.line_width > paths.actor.prop.line_width
    shown = np.asarray(paths.emphasis.mapper.dataset.points)[
        np.asarray(paths.emphasis.mapper.dataset.lines).reshape(-1, 3)[:, 1]]
    pairs = w.state.plan.result.plan.pairs
    near = [np.concatenate([pairs[k].left_tip, pairs[k].right_tip]) for k in (9, 10, 11)]
    d = np.min(np.linalg.norm(shown[:, None] - np.concatenate(near)[None, ::2], axis=2), axis=1)
    assert d.max() < 1.0  # every emphasised segment lies on contours 9-11
    j = int(np.nonzero(tl.left.path == 20)[0][0])
    w.state.set_cursor(j)
    assert paths.current == 20
    opts.emphasis.setChecked(False)
    assert paths.emphasis is None and paths.actor.prop.opacity == 1.0


def test_bottom_and_top_views(planned, qtbot):
    w = planned
    cam = w.viewport.plotter.camera
    w.view_options.view_actions["bottom"].trigger()
    d = np.asarray(cam.focal_point) - np.asarray(cam.position)
    assert d[2] > 0.99 * np.linalg.norm(d)  # from -Z_W, looking up +Z_W
    w.view_options.view_actions["top"].trigger()
    d = np.asarray(cam.focal_point) - np.asarray(cam.position)
    assert -d[0] > 0.99 * np.linalg.norm(d)  # from the blade tip (+X_W), looking down the span
    assert abs(np.asarray(cam.up)[2]) > 0.99


def _display(renderer, point) -> np.ndarray:
    """(x, y) display pixels of a world point (VTK's own projection)."""
    renderer.SetWorldPoint(*point, 1.0)
    renderer.WorldToDisplay()
    return np.asarray(renderer.GetDisplayPoint()[:2])


@pytest.mark.parametrize("which", ["left", "right", "midpoint"])
def test_follow_camera_keeps_the_cutter_mid_view(planned, qtbot, which):
    w = planned
    vp = w.viewport
    tl = w.state.plan.timeline
    w.view_options.follow.setCurrentIndex(w.view_options.follow.findData(which))
    vp.view("iso")
    ren = vp.plotter.renderer
    width, height = ren.GetSize()
    centre = np.array([width / 2.0, height / 2.0])
    dist = np.linalg.norm(np.asarray(vp.plotter.camera.position) - np.asarray(vp.plotter.camera.focal_point))
    n = len(tl.t)
    for i in np.linspace(0, n - 1, 25).astype(int):  # a scrub over the whole job
        w.state.set_cursor(int(i))
        tips = {"left": tl.left.tips[i], "right": tl.right.tips[i]}
        target = 0.5 * (tips["left"] + tips["right"]) if which == "midpoint" else tips[which]
        off = _display(ren, target) - centre
        assert np.linalg.norm(off) <= 0.02 * min(width, height), (i, off)
        cam = vp.plotter.camera  # the view's direction and distance are kept
        assert np.linalg.norm(np.asarray(cam.position) - np.asarray(cam.focal_point)) == pytest.approx(dist)
    # the cutter is drawn there: its actor's tip projects mid-view too
    side = "left" if which == "midpoint" else which
    if which != "midpoint":
        tip = w.viewport.cutters.matrix(side)[:3, 3]
        assert np.linalg.norm(_display(ren, tip) - centre) <= 0.02 * min(width, height)
    # free again: the camera stays where it is as the cursor moves
    w.view_options.follow.setCurrentIndex(w.view_options.follow.findData("off"))
    before = np.asarray(vp.plotter.camera.focal_point)
    w.state.set_cursor(n // 3)
    np.testing.assert_allclose(vp.plotter.camera.focal_point, before)
