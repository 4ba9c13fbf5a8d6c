"""GUI fixtures (after napari's and pyvistaqt's conftest): real windows under Xvfb (pytest-xvfb).

Every window is closed at teardown and must leave no pyvista plotter behind. Settings go to a
temporary folder. Plans use coarse parameters (dR 4 mm, dd 0.5 mm: about a second each).
"""

import os

import numpy as np
import pytest

os.environ.setdefault("QT_API", "pyside6")
os.environ.pop("QT_QPA_PLATFORM", None)  # a real (virtual) X server, never 'offscreen'

pytestmark = pytest.mark.gui

from ..conftest import COARSE  # noqa: E402

PLAN_TIMEOUT = 60_000  # ms: a coarse plan takes 1-3 s; generous for a loaded 2-core machine


@pytest.fixture(autouse=True)
def isolated_settings(tmp_path_factory):
    from PySide6.QtCore import QSettings

    folder = tmp_path_factory.mktemp("settings")
    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, str(folder))
    return folder


@pytest.fixture
def window(qtbot):
    from pyvista.plotting import plotter as pv_plotter

    from bladecam_gui.main_window import MainWindow
    from core.records import PlanParameters

    before = set(pv_plotter._ALL_PLOTTERS)
    w = MainWindow(params=PlanParameters(**COARSE), debounce_ms=50, restore=False)
    qtbot.addWidget(w)
    w.resize(1400, 900)
    with qtbot.waitExposed(w):
        w.show()
    yield w
    w.close()
    assert w.viewport.plotter._closed
    leaked = set(pv_plotter._ALL_PLOTTERS) - before
    assert not leaked, f"interactors left open: {leaked}"


def wait_plan(qtbot, window, action):
    """Run ``action`` and wait until the controller has shown the resulting plan; returns it."""
    with qtbot.waitSignal(window.controller.finished, timeout=PLAN_TIMEOUT):
        action()
    qtbot.waitUntil(lambda: not window.controller.running, timeout=PLAN_TIMEOUT)
    return window.state.plan


@pytest.fixture
def fresh_planned(window, qtbot):
    """The window with the sample blade planned through the worker (collaborative, coarse)."""
    data = wait_plan(qtbot, window, lambda: window.open_blade_source("sample"))
    _CACHE.setdefault("sample", data)
    return window


_CACHE: dict = {}


@pytest.fixture
def planned(window, qtbot):
    """The window showing the sample blade's coarse collaborative plan: planned through the worker once
    per session, then shown again from that (immutable) result to keep the GUI tests quick."""
    if "sample" not in _CACHE:
        _CACHE["sample"] = wait_plan(qtbot, window, lambda: window.open_blade_source("sample"))
        return window
    data = _CACHE["sample"]
    assert data.job == window.state.job()  # same inputs as a fresh plan would have
    window.state.set_plan(data)
    qtbot.waitUntil(lambda: window.state.plan is data and not window.state.stale)
    return window


@pytest.fixture
def dialogs(monkeypatch):
    """Patch QMessageBox so that tests see the messages instead of blocking on them."""
    from PySide6.QtWidgets import QMessageBox

    shown = {"warning": [], "question": [], "about": []}
    answers = {"question": QMessageBox.StandardButton.No}
    def warn(parent, title, text, *args, **kwargs):
        shown["warning"].append((title, text))
        return QMessageBox.StandardButton.Ok

    def ask(parent, title, text, *args, **kwargs):
        shown["question"].append((title, text))
        return answers["question"]

    monkeypatch.setattr(QMessageBox, "warning", warn)
    monkeypatch.setattr(QMessageBox, "critical", warn)
    monkeypatch.setattr(QMessageBox, "question", ask)
    monkeypatch.setattr(QMessageBox, "about", lambda parent, title, text: shown["about"].append(
        (title, text)))
    shown["answers"] = answers
    return shown


def hue_mask(img: np.ndarray, colour: str, hue_tol: float = 12.0, min_sat: float = 0.35,
             min_val: float = 0.15) -> np.ndarray:
    """Pixels (h, w) whose hue is within hue_tol degrees of ``colour`` and clearly saturated (shading
    scales a colour's value, not its hue)."""
    from PySide6.QtGui import QColor

    target = QColor(colour).hsvHueF() * 360.0
    rgb = img[..., :3].astype(float) / 255.0
    mx, mn = rgb.max(axis=-1), rgb.min(axis=-1)
    delta = mx - mn
    sat = np.where(mx > 0, delta / np.where(mx > 0, mx, 1), 0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    d = np.where(delta > 0, delta, 1)
    hue = np.where(mx == r, ((g - b) / d) % 6, np.where(mx == g, (b - r) / d + 2, (r - g) / d + 4)) * 60.0
    diff = np.abs((hue - target + 180.0) % 360.0 - 180.0)
    return (diff <= hue_tol) & (sat >= min_sat) & (mx >= min_val) & (delta > 0)


def side_view_instant(data) -> int:
    """A time sample where both tools show clear of the blade when seen along the chord (from -Y_W,
    the tests' side view): symmetrical machining (both cutting, step 4, no danger) in the middle of
    the span, the tool axes nearest to the thickness axis Z_W (a tilted tool can hide behind the
    blade's leading part, whichever sample lies at the middle of the job)."""
    tl = data.timeline
    both = np.nonzero(tl.left.cutting & tl.right.cutting & ~data.danger & (tl.left.step == 4))[0]
    both = both[len(both) // 3: 2 * len(both) // 3]
    upright = np.abs(tl.left.axes[both, 2]) + np.abs(tl.right.axes[both, 2])
    return int(both[np.argmax(upright)])
