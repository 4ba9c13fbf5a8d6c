"""Coalescing of fast updates: while the cursor is dragged or played, the secondary views (plots,
read-out) follow at most every ``interval`` ms, always ending on the latest value; the 3D view and
the step bar follow every frame."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QObject, QTimer


class Throttle(QObject):
    """``request(value)`` applies at once when idle, else keeps the latest value for the next tick."""

    def __init__(self, apply: Callable[[object], None], interval_ms: int = 150,
                 parent: QObject | None = None):
        super().__init__(parent)
        self._apply = apply
        self._pending = False
        self._value = None
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(interval_ms)
        self._timer.timeout.connect(self._on_timeout)

    def request(self, value) -> None:
        if self._timer.isActive():
            self._value, self._pending = value, True
            return
        self._apply(value)
        self._timer.start()

    def flush(self) -> None:
        """Apply a pending value now."""
        if self._pending:
            self._timer.stop()
            self._on_timeout()

    def _on_timeout(self) -> None:
        if self._pending:
            self._pending = False
            self._apply(self._value)
            self._timer.start()
