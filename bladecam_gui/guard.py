"""Slots never raise: ``guarded`` catches, logs and shows a message box; ``show_error`` is the one
place the workbench tells the operator what went wrong (tests patch QMessageBox.warning)."""

from __future__ import annotations

import functools
import inspect
import logging

from PySide6.QtWidgets import QMessageBox, QWidget

from core.errors import BladecamError

log = logging.getLogger("bladecam_gui")

ADVICE = {
    "BladeInputError": "Check the file (or choose another blade); the previous blade and plan stay shown.",
    "PlanningError": "Change the parameter named above (Edit > Undo goes back); the previous plan stays "
                     "shown.",
    "OutputError": "Choose another folder or file, or free it, and try again.",
    "ProjectError": "Fix the key named above in the project file, or open another project.",
    "MachineError": "Check machine.toml, or the pose named above.",
}


def message_for(exc: BaseException) -> str:
    """The operator's message: core's own text plus what to do; other errors with their type."""
    if isinstance(exc, BladecamError):
        advice = ADVICE.get(type(exc).__name__, "The previous plan stays shown.")
        return f"{exc}\n\n{advice}"
    return (f"Unexpected error ({type(exc).__name__}): {exc}\n\nThe window stays usable; the details are "
            "in the log. Please report this with the blade and parameters used.")


def show_error(parent: QWidget | None, title: str, exc_or_text) -> None:
    text = exc_or_text if isinstance(exc_or_text, str) else message_for(exc_or_text)
    QMessageBox.warning(parent, title, text)


def guarded(title: str):
    """Decorator for slots and menu actions: any exception becomes a message box (never propagates)."""
    def wrap(fn):
        sig = inspect.signature(fn)
        varargs = any(p.kind is p.VAR_POSITIONAL for p in sig.parameters.values())
        positional = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
        n_pos = sum(p.kind in positional for p in sig.parameters.values()) - 1

        @functools.wraps(fn)
        def inner(self, *args, **kwargs):
            if not varargs:
                args = args[:n_pos]  # Qt passes extra signal arguments (e.g. triggered's 'checked')
            try:
                return fn(self, *args, **kwargs)
            except Exception as exc:  # slots never raise
                if not isinstance(exc, BladecamError):
                    log.exception("%s failed", title)
                parent = self if isinstance(self, QWidget) else getattr(self, "parent_widget", None)
                show_error(parent if isinstance(parent, QWidget) else None, title, exc)
                return None
        return inner
    return wrap
