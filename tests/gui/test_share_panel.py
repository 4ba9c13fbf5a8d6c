"""How collaborative the plan is, up front (bladecam_gui.widgets.share_panel): the panel's figures
against plan.json's and a brute-force count of the regions, the staggered-ratio plot's points and
hover text, the warning; the paths in one colour in the modes that do not use the regions; the 3D
view's legend at a fixed pixel size."""

import json
import re
from collections import Counter

import numpy as np
import pytest

from bladecam_gui.style import LEGEND_FONT_PX, MODE_PATHS, REGIONS, hex_rgb
from bladecam_gui.widgets.share_panel import COLUMNS, ROWS
from bladecam_gui.widgets.status import collaboration_warning

from .conftest import hue_mask, wait_plan

pytestmark = pytest.mark.gui


def _numbers(text: str) -> list[float]:
    return [float(v.replace(" ", "")) for v in re.findall(r"\d[\d ]*(?:\.\d+)?", text)]


def test_panel_figures_equal_plan_json_and_the_regions(planned, tmp_path):
    from core.output.writer import write_result

    w = planned
    data = w.state.plan
    folder = write_result(data.result, tmp_path / "plan")
    fig = json.loads((folder / "plan.json").read_text())["schedule"]["collaboration"]
    panel = w.share_panel
    cells = {key: panel.cells[key].text() for key in panel.cells}
    # paths: the share, then 'n of total', against a brute-force count of the regions
    regions = data.result.plan.regions
    n_tip = sum(1 for r in regions if r.is_tip)
    share, n_coll, n_total = _numbers(cells[("paths", "collaborative")])
    assert (n_coll, n_total) == (len(regions) - n_tip, len(regions)) == (fig["paths"]["collaborative"],
                                                                         fig["paths"]["total"])
    assert share == pytest.approx(100 * fig["paths"]["collaborative_share"], abs=0.051)
    share, n_single, _ = _numbers(cells[("paths", "single_sided")])
    assert n_single == n_tip == fig["paths"]["single_sided"]
    assert 0 < n_tip < len(regions)  # (the coarse sample: both kinds, so that a swap would show)
    # cutting length (m) and job time (min) with their shares, per column
    for key, _ in COLUMNS:
        share, metres = _numbers(cells[("cutting_length", key)])
        assert metres * 1000.0 == pytest.approx(fig["cutting_length_mm"][key], abs=5.1)
        assert share == pytest.approx(100 * fig["cutting_length_share"][key], abs=0.051)
        share, minutes = _numbers(cells[("job_time", key)])
        assert minutes == pytest.approx(fig["job_time_s"][key] / 60.0, abs=0.0051)
        assert share == pytest.approx(100 * fig["job_time_share"][key], abs=0.051)
    assert len(cells) == len(ROWS) * len(COLUMNS)
    # the tip paths' reasons, counted from the regions
    reasons = Counter(r.reason for r in regions if r.is_tip)
    assert reasons == Counter(fig["tip_reasons"])
    for reason, count in reasons.items():
        assert f"{count} path{'s' if count > 1 else ''}: {reason}" in panel.reasons.text()
    assert w.share_dock.windowTitle() == f"Collab. {100 * fig['paths']['collaborative_share']:.0f} % ⚠"


def test_ratio_plot_points_are_the_regions(planned):
    w = planned
    plan = w.state.plan.result.plan
    r, ratio, tip = w.share_panel.plot.points()
    expect = sorted((p.r, g.staggered_ratio, g.is_tip) for p, g in zip(plan.pairs, plan.regions, strict=True))
    got = sorted(zip(r.tolist(), ratio.tolist(), tip.tolist(), strict=True))
    assert len(got) == len(expect) == len(plan.pairs)
    np.testing.assert_allclose([g[:2] for g in got], [e[:2] for e in expect])
    assert [g[2] for g in got] == [e[2] for e in expect]
    assert w.share_panel.plot.k_line.value() == pytest.approx(plan.params.k_max)


def test_hovering_a_tip_path_names_its_reason(planned, qtbot):
    w = planned
    w.share_dock.show()
    w.share_dock.raise_()
    plot = w.share_panel.plot
    qtbot.waitUntil(lambda: plot.isVisible() and plot.width() > 100)
    plan = w.state.plan.result.plan
    # a tip path whose reason is not the most common one, if there is one (a wrong lookup shows)
    tips = [(p, g) for p, g in zip(plan.pairs, plan.regions, strict=True) if g.is_tip]
    rare = min(Counter(g.reason for _, g in tips).items(), key=lambda kv: kv[1])[0]
    pair, region = next((p, g) for p, g in tips if g.reason == rare)
    hover(plot, pair.r, region.staggered_ratio)
    qtbot.waitUntil(lambda: f"contour {pair.index}:" in plot.view_box.toolTip())
    assert region.reason in plot.view_box.toolTip()
    # a collaborative one says so, with no reason
    pair, region = next((p, g) for p, g in zip(plan.pairs, plan.regions, strict=True) if not g.is_tip)
    qtbot.wait(50)  # (pyqtgraph drops moves closer than its rate limit)
    hover(plot, pair.r, region.staggered_ratio)
    qtbot.waitUntil(lambda: f"contour {pair.index}:" in plot.view_box.toolTip())
    assert "collaborative" in plot.view_box.toolTip() and rare not in plot.view_box.toolTip()


def hover(plot, x: float, y: float) -> None:
    """The mouse moved onto the plot's point (x, y) (a move event to the view: qtbot.mouseMove only
    moves the X pointer, which Xvfb does not turn into an event for the plot)."""
    from PySide6.QtCore import QEvent, QPointF, Qt
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication

    pos = QPointF(plot.mapFromScene(plot.view_box.mapViewToScene(QPointF(x, y))))
    no = Qt.MouseButton.NoButton
    event = QMouseEvent(QEvent.Type.MouseMove, pos, plot.viewport().mapToGlobal(pos), no, no,
                        Qt.KeyboardModifier.NoModifier)
    QApplication.sendEvent(plot.viewport(), event)


def test_the_panel_warns_as_the_status_does_and_names_the_parameter(planned, qtbot):
    w = planned
    panel = w.share_panel
    warning = collaboration_warning(w.state.plan)
    assert warning and "K_max" in warning  # the coarse sample at the defaults: 41 % collaborative
    assert panel.warning.isVisibleTo(panel) and panel.warning.text() == warning
    assert warning in w.figures.text()
    data = wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.9))
    assert not collaboration_warning(data)
    assert not panel.warning.isVisibleTo(panel)
    assert "⚠" not in w.share_dock.windowTitle()


def _rgb_set(paths) -> set[tuple[int, int, int]]:
    return {tuple(int(c) for c in row) for row in np.asarray(paths.mesh.cell_data["rgb"])}


@pytest.mark.parametrize("mode", ["symmetric", "single"])
def test_paths_in_one_colour_when_the_mode_does_not_use_the_regions(planned, qtbot, mode):
    w = planned
    paths = w.viewport.paths
    assert len(_rgb_set(paths)) > 1  # collaborative: by region
    assert any("region" in label for label, _ in paths.legend.entries)
    wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText(mode))
    label, colour = MODE_PATHS[mode]
    assert _rgb_set(paths) == {hex_rgb(colour)}
    assert paths.legend.entries == [(f"{mode} mode: {label}", colour)]
    # on screen: the mode's colour, and no region's
    img = w.viewport.screenshot()
    assert hue_mask(img, colour).sum() > 200
    for name in ("edge", "variable"):
        assert hue_mask(img, REGIONS[name][1]).sum() < 20
    wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("collaborative"))
    assert len(_rgb_set(paths)) > 1


def _swatch_height(img: np.ndarray) -> int:
    """Rows of the legend's first swatch (the tip region's blue) in the view's top right corner."""
    corner = img[:60, -40:]
    rows = np.nonzero(hue_mask(corner, REGIONS["tip"][1]).sum(axis=1) >= 8)[0]
    return int(rows.max() - rows.min() + 1) if len(rows) else 0


def test_legend_text_keeps_its_pixel_size(planned, qtbot):
    w = planned
    legend = w.viewport.paths.legend
    assert legend.entries[0][0] == "tip region"
    seen = []
    for size in ((1280, 800), (1920, 1080)):
        w.resize(*size)
        qtbot.waitUntil(lambda s=size: (w.width(), w.height()) == s)
        qtbot.wait(50)
        img = w.viewport.screenshot()
        seen.append((img.shape[1], _swatch_height(img), legend.text_size(0)[1],
                     legend.labels[0].GetTextProperty().GetFontSize()))
    (w0, swatch0, text0, font0), (w1, swatch1, text1, font1) = seen
    assert w1 > w0 + 200  # the view did grow
    assert font0 == font1 == LEGEND_FONT_PX
    assert swatch0 == swatch1 and swatch0 >= LEGEND_FONT_PX
    assert text0 == text1 >= LEGEND_FONT_PX
