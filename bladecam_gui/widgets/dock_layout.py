"""The window's layout rules, so that the 3D view gets the space: the side docks give way when the
window shrinks (down to their own minimum widths), the 3D view keeps a minimum size, and one action
hides or shows every side panel at once (the docks' own toggles stay in the View menu)."""

from __future__ import annotations

import logging

from PySide6.QtCore import QEvent, QObject, Qt, QTimer
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QDockWidget, QMainWindow, QWidget

log = logging.getLogger(__name__)

#: the 3D view's minimum size (px), and the share of the window's width it gets back when the
#: window shrinks
CENTRAL_MIN = (300, 240)
CENTRAL_SHARE = 0.5


def side_docks(window: QMainWindow, area: Qt.DockWidgetArea) -> list[QDockWidget]:
    """The docks shown in ``area`` (docked, visible: one per tab group; a tab behind another is
    'visible' to Qt, placed off the window, and has nothing on screen)."""
    return [d for d in window.findChildren(QDockWidget)
            if window.dockWidgetArea(d) == area and d.isVisible() and not d.isFloating()
            and not d.visibleRegion().isEmpty()]


class DockBalancer(QObject):
    """Watches the window's resizes: when the 3D view (the central widget) is narrower than
    CENTRAL_SHARE of the window, the left and right docks shrink (each by its share of the room it
    has above its minimum width). A dock the operator widens later keeps its width until the window
    shrinks again."""

    def __init__(self, window: QMainWindow):
        super().__init__(window)
        self.window = window
        window.centralWidget().setMinimumSize(*CENTRAL_MIN)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(0)
        self._timer.timeout.connect(self.balance)
        window.installEventFilter(self)
        self.central = window.centralWidget()
        self.central.installEventFilter(self)  # (resized once the layout has placed the docks)

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt name)
        if event.type() in (QEvent.Type.Resize, QEvent.Type.Show) and (obj is self.window
                                                                       or obj is self.central):
            self._timer.start()  # after the layout has placed the docks
        return False

    def balance(self) -> None:
        try:
            w = self.window
            central = w.centralWidget()
            want = max(int(CENTRAL_SHARE * w.width()), central.minimumWidth())
            short = want - central.width()
            if short <= 0:
                return
            docks = (side_docks(w, Qt.DockWidgetArea.LeftDockWidgetArea)
                     + side_docks(w, Qt.DockWidgetArea.RightDockWidgetArea))
            # one per column: tabified and stacked docks share their width
            columns: dict[tuple[int, int], QDockWidget] = {}
            for d in docks:
                columns.setdefault((d.x(), d.width()), d)
            docks = list(columns.values())
            room = [max(d.width() - d.minimumSizeHint().width(), 0) for d in docks]
            total = sum(room)
            if total <= 0:
                return
            take = min(short, total)
            widths = [d.width() - int(round(take * r / total)) for d, r in zip(docks, room, strict=True)]
            w.resizeDocks(docks, widths, Qt.Orientation.Horizontal)
        except Exception:  # slots never raise
            log.exception("balancing the docks failed")


class PanelsToggle(QAction):
    """Hide every side panel (the 3D view takes the window) or show again the ones that were."""

    def __init__(self, window: QMainWindow, docks: list[QDockWidget], shortcut: str = "Ctrl+Shift+H"):
        super().__init__("Hide the side panels", window)
        self.window, self.docks = window, docks
        self.hidden: list[QDockWidget] = []
        self.setCheckable(True)
        self.setShortcut(QKeySequence(shortcut))
        self.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
        self.setStatusTip("the 3D view takes the whole window; again to bring the panels back")
        self.toggled.connect(self._on_toggled)

    def _on_toggled(self, hide: bool) -> None:
        try:
            if hide:
                self.hidden = [d for d in self.docks if d.isVisible()]
                for d in self.hidden:
                    d.hide()
            else:
                for d in self.hidden:
                    d.show()
                self.hidden = []
        except Exception:  # slots never raise
            log.exception("hiding the panels failed")


def minimum_width(widget: QWidget, extra: int = 0) -> int:
    return widget.minimumSizeHint().width() + extra
