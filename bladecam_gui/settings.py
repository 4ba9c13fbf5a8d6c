"""Remembered things (QSettings, INI format): recent blades and projects, window layout."""

from __future__ import annotations

from PySide6.QtCore import QSettings

MAX_RECENT = 8


def settings() -> QSettings:
    """The workbench's settings (tests redirect them with QSettings.setPath)."""
    return QSettings(QSettings.Format.IniFormat, QSettings.Scope.UserScope, "bladecam", "workbench")


def recent(key: str) -> list[str]:
    value = settings().value(f"recent/{key}", [])
    if isinstance(value, str):
        value = [value]
    return [str(v) for v in (value or [])]


def add_recent(key: str, entry: str) -> list[str]:
    items = [entry] + [e for e in recent(key) if e != entry]
    items = items[:MAX_RECENT]
    s = settings()
    s.setValue(f"recent/{key}", items)
    s.sync()
    return items


def save_layout(window) -> None:
    s = settings()
    s.setValue("window/geometry", window.saveGeometry())
    s.setValue("window/state", window.saveState())
    s.sync()


def restore_layout(window) -> bool:
    s = settings()
    geometry, state = s.value("window/geometry"), s.value("window/state")
    ok = False
    if geometry is not None:
        ok = bool(window.restoreGeometry(geometry))
    if state is not None:
        ok = bool(window.restoreState(state)) and ok
    return ok
