"""The timeline's keyboard: actions with window-wide shortcuts (Space plays and pauses wherever the
focus is; a text field keeps the keys it types), gathered in a Go menu, and the Help menu's list of
every shortcut of the window, read from its actions (so that it cannot drift from them)."""

from __future__ import annotations

import html

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QDialog, QDialogButtonBox, QLabel, QMenu, QScrollArea, QVBoxLayout, QWidget

from ..style import STEPS
from .timeline import ZOOM_STEP, TimelinePanel

#: (text, shortcuts, what it does (a TimelinePanel method name and its arguments))
GO_ACTIONS = (
    ("Play / pause", ("Space",), ("toggle_play",)),
    ("Back a little", ("Left",), ("nudge", -1)),
    ("Forward a little", ("Right",), ("nudge", +1)),
    ("Back one time sample", ("Shift+Left",), ("nudge", -1, True)),
    ("Forward one time sample", ("Shift+Right",), ("nudge", +1, True)),
    ("Previous step start", ("PgUp", "Ctrl+Left"), ("jump_step", -1)),
    ("Next step start", ("PgDown", "Ctrl+Right"), ("jump_step", +1)),
    ("Start of the job", ("Home",), ("go_end", False)),
    ("End of the job", ("End",), ("go_end", True)),
    ("Previous violation", ("Shift+V",), ("jump_violation", -1)),
    ("Next violation", ("V",), ("jump_violation", +1)),
    ("Minimum tip spacing", ("M",), ("jump_minimum", "spacing")),
    ("Minimum tool clearance", ("Shift+M",), ("jump_minimum", "clearance")),
    (None, (), ()),
    ("Zoom the timeline in", ("+", "="), ("zoom", ZOOM_STEP ** 2)),
    ("Zoom the timeline out", ("-",), ("zoom", ZOOM_STEP ** -2)),
    ("Fit the whole job", ("F",), ("fit",)),
)


def _act(parent: QWidget, text: str, keys, slot) -> QAction:
    action = QAction(text, parent)
    action.setShortcuts([QKeySequence(k) for k in keys])
    action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
    action.triggered.connect(lambda checked=False: slot())
    parent.addAction(action)  # live while the menu is closed
    return action


def build_go_menu(window: QWidget, timeline: TimelinePanel, title: str = "&Go") -> QMenu:
    """A Go menu of the timeline's moves, each action also a shortcut of the whole window."""
    menu = QMenu(title, window)
    menu.setObjectName("menu-go")
    actions = {}
    for text, keys, (name, *args) in ((t, k, w) for t, k, w in GO_ACTIONS if t is not None):
        actions[text] = _act(window, text, keys, lambda n=name, a=args: getattr(timeline, n)(*a))
    for text, _keys, _ in GO_ACTIONS:
        if text is None:
            menu.addSeparator()
        else:
            menu.addAction(actions[text])
    menu.addSeparator()
    contour = _act(window, "Contour N…", ("Ctrl+G",), lambda: (timeline.contour.setFocus(),
                                                              timeline.contour.selectAll()))
    menu.addAction(contour)
    steps = menu.addMenu("Start of step")
    for k, (short, _, _) in STEPS.items():
        steps.addAction(_act(window, short, (f"Alt+{k}",), lambda k=k: timeline.jump_to_step(k)))
    menu.actions_by_text = actions  # (for the tests)
    return menu


def shortcut_rows(window: QWidget) -> list[tuple[str, str]]:
    """(keys, what) of every action of the window (and its menus) that has a shortcut, in menu order."""
    rows, seen = [], set()

    def visit(actions, prefix: str) -> None:
        for a in actions:
            if a.menu() is not None:
                visit(a.menu().actions(), prefix + a.menu().title().replace("&", "") + " › ")
                continue
            keys = [k.toString(QKeySequence.SequenceFormat.NativeText) for k in a.shortcuts()]
            if keys and id(a) not in seen:
                seen.add(id(a))
                rows.append((", ".join(keys), prefix + a.text().replace("&", "").replace("…", "")))

    visit(window.menuBar().actions(), "")
    visit(window.actions(), "")
    return rows


def show_shortcuts(window: QWidget) -> QDialog:
    """A (non-modal) window listing the shortcuts; returned for the tests."""
    body = "".join(f"<tr><td><b>{html.escape(k)}</b>&nbsp;&nbsp;</td><td>{html.escape(w)}</td></tr>"
                   for k, w in shortcut_rows(window))
    mouse = ("<p><b>Timeline:</b> click or drag to move the cursor; wheel to zoom round the mouse; "
             "shift + wheel, or drag with the right or middle button, to pan.</p>")
    dialog = QDialog(window)
    dialog.setWindowTitle("Keyboard shortcuts")
    label = QLabel(f"<table>{body}</table>{mouse}")
    label.setObjectName("shortcuts-table")
    label.setWordWrap(True)
    scroll = QScrollArea(dialog)
    scroll.setWidget(label)
    scroll.setWidgetResizable(True)
    buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close, dialog)
    buttons.rejected.connect(dialog.close)
    layout = QVBoxLayout(dialog)
    layout.addWidget(scroll)
    layout.addWidget(buttons)
    dialog.resize(460, 560)
    dialog.show()
    return dialog
