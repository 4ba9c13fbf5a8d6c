"""GUI fixtures (after napari's and pyvistaqt's conftest): real windows under Xvfb (pytest-xvfb)."""

import os

import pytest

os.environ.setdefault("QT_API", "pyside6")
os.environ.pop("QT_QPA_PLATFORM", None)  # a real (virtual) X server, never 'offscreen'

pytestmark = pytest.mark.gui


@pytest.fixture
def main_window(qtbot):
    from bladecam_gui.main_window import MainWindow

    window = MainWindow()
    qtbot.addWidget(window)
    window.show()
    qtbot.waitExposed(window)
    yield window
    window.close()
