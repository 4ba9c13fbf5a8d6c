"""Coalescing of fast updates: while the cursor is dragged or played, the secondary views (plots,
read-out) follow at most every ``interval`` ms, always ending on the latest value; the 3D view and
the step bar follow every frame."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QObject, QTimer


class Throttle(QObject):
    """``request(value)`` applies at once when idle, else keeps the latest value for the next tick.
    ``phase_ms`` > 0 delays the first application of a burst by that much instead, so that several
    throttles fed by one signal (the plots beside the read-out) take their turns in different frames
    rather than all in the same one."""

    def __init__(self, apply: Callable[[object], None], interval_ms: int = 150,
                 parent: QObject | None = None, phase_ms: int = 0):
        super().__init__(parent)
        self._apply = apply
        self._pending = False
        self._value = None
        self._interval = interval_ms
        self._phase = phase_ms
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(interval_ms)
        self._timer.timeout.connect(self._on_timeout)

    def request(self, value) -> None:
        if self._timer.isActive():
            self._value, self._pending = value, True
            return
        if self._phase > 0:
            self._value, self._pending = value, True
            self._timer.start(self._phase)
            return
        self._apply(value)
        self._timer.start(self._interval)

    def flush(self) -> None:
        """Apply a pending value now."""
        if self._pending:
            self._timer.stop()
            self._on_timeout()

    def _on_timeout(self) -> None:
        if self._pending:
            self._pending = False
            self._apply(self._value)
            self._timer.start(self._interval)
