"""The workbench state: the current blade (and later plan and parameters), emitting signals.

Widgets receive this object in ``__init__`` and react to its signals; they never compute geometry.
"""

from __future__ import annotations

from PySide6.QtCore import QObject, Signal

from core.blade import Blade


class WorkbenchState(QObject):
    """Holds the loaded blade; ``blade_changed`` fires with the new blade."""

    blade_changed = Signal(object)

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._blade: Blade | None = None
        self.blade_source: str = "sample"
        self.axis: str = "z"

    @property
    def blade(self) -> Blade | None:
        return self._blade

    def set_blade(self, blade: Blade, source: str, axis: str = "z") -> None:
        self._blade = blade
        self.blade_source = source
        self.axis = axis
        self.blade_changed.emit(blade)
