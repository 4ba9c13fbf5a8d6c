"""Undo and redo from anywhere in the window: a spin box's line edit claims Ctrl+Z / Ctrl+Y (and the
platform's undo and redo keys) for its own text, so after typing a value and Enter the window's Undo
never fired. This filter, installed on the window's spin boxes, declines those keys' shortcut
override: the window's Edit > Undo / Redo actions take them (a value typed and not yet entered is
dropped and the field shows the undone value)."""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject
from PySide6.QtGui import QKeyEvent, QKeySequence
from PySide6.QtWidgets import QAbstractSpinBox, QWidget

#: the keys the window's undo and redo actions take from the spin boxes
UNDO_KEYS = (QKeySequence.StandardKey.Undo, QKeySequence.StandardKey.Redo)
REDO_EXTRA = "Ctrl+Y"


def is_undo_key(event: QKeyEvent) -> bool:
    if any(event.matches(k) for k in UNDO_KEYS):
        return True
    return QKeySequence(event.keyCombination()) == QKeySequence(REDO_EXTRA)


class WindowUndoKeys(QObject):
    """Installed on every spin box of ``window`` (and its line edit) by ``install``."""

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt name)
        if event.type() == QEvent.Type.ShortcutOverride and is_undo_key(event):
            event.ignore()  # not the widget's: the window's shortcut fires
            return True
        return False

    def install(self, window: QWidget) -> None:
        for spin in window.findChildren(QAbstractSpinBox):
            spin.installEventFilter(self)
            spin.lineEdit().installEventFilter(self)
