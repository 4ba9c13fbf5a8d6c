"""The Qt binding keeps Python's reference counts (PySide6 6.12.0 on Python 3.11 does not: every
Python override of a Qt virtual drops a reference to None, and a long session, or this test suite,
ends in 'Fatal Python error: none_dealloc'). Pin PySide6-Essentials below 6.12 on Python 3.11."""

import gc
import sys

import pytest

pytestmark = pytest.mark.gui


def test_qt_virtual_overrides_keep_reference_counts(qtbot):
    import PySide6
    from PySide6.QtGui import QPainter
    from PySide6.QtWidgets import QApplication, QWidget

    class Painted(QWidget):
        def paintEvent(self, event):  # noqa: N802 (Qt name)
            QPainter(self).end()

    w = Painted()
    qtbot.addWidget(w)
    w.resize(50, 50)
    with qtbot.waitExposed(w):
        w.show()
    gc.collect()
    before = sys.getrefcount(None)
    for _ in range(300):
        w.repaint()
        QApplication.processEvents()
    gc.collect()
    lost = before - sys.getrefcount(None)
    assert lost < 100, (f"PySide6 {PySide6.__version__} on Python {sys.version.split()[0]} lost {lost} "
                        "references to None in 300 repaints: it will crash the workbench; install "
                        "PySide6-Essentials<6.12 (or Python >= 3.12)")
