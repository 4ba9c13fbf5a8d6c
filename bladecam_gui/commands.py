"""Undo and redo of input edits: every parameter, profile or period change is a QUndoCommand.

Quick successive edits of one input (spin box arrows, a held key) merge into one command.
"""

from __future__ import annotations

import time
from dataclasses import fields

from PySide6.QtCore import QObject
from PySide6.QtGui import QUndoCommand, QUndoStack

from core.records import PlanParameters

from .state import WorkbenchState

PARAM_NAMES = tuple(f.name for f in fields(PlanParameters))
SCHEDULE_NAMES = ("profile", "period")
NAMES = PARAM_NAMES + SCHEDULE_NAMES
MERGE_SECONDS = 1.0


class SetInput(QUndoCommand):
    """Set one input from ``old`` to ``new``."""

    def __init__(self, editor: InputEditor, name: str, old, new):
        super().__init__(f"{name} {old} -> {new}")
        self.editor, self.name, self.old, self.new = editor, name, old, new
        self.stamp = time.monotonic()

    def id(self) -> int:  # noqa: A003 (Qt name)
        return NAMES.index(self.name)

    def mergeWith(self, other: QUndoCommand) -> bool:  # noqa: N802 (Qt name)
        if not isinstance(other, SetInput) or other.name != self.name:
            return False
        if other.stamp - self.stamp > MERGE_SECONDS:
            return False
        self.new, self.stamp = other.new, other.stamp
        self.setText(f"{self.name} {self.old} -> {self.new}")
        return True

    def redo(self) -> None:
        self.editor.apply(self.name, self.new)

    def undo(self) -> None:
        self.editor.apply(self.name, self.old)


class InputEditor(QObject):
    """The one way widgets change inputs: ``edit(name, value)`` pushes an undoable command."""

    def __init__(self, state: WorkbenchState, parent: QObject | None = None):
        super().__init__(parent)
        self.state = state
        self.stack = QUndoStack(self)

    def current(self, name: str):
        if name in PARAM_NAMES:
            return getattr(self.state.params, name)
        return getattr(self.state, name)

    def edit(self, name: str, value) -> None:
        if name not in NAMES:
            raise KeyError(name)
        old = self.current(name)
        if old == value:
            return
        self.stack.push(SetInput(self, name, old, value))

    def apply(self, name: str, value) -> None:
        if name in PARAM_NAMES:
            self.state.set_param(name, value)
        else:
            self.state.set_schedule_option(name, value)
