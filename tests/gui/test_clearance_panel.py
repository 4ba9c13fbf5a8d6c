"""The Clearance panel's read-out: each part's figure as the plan's collision check holds it (exact
below REFINE, 'at least' above, red for a collision), and the jumps to the closest approaches."""

from __future__ import annotations

import numpy as np

from bladecam_gui.widgets.clearance_panel import ClearancePanel, clearance_text, rows_at
from core.machine.clearance import Clamp
from core.machine.collisions import check_rows
from core.machine.model import load_machine
from core.machine.tool import assembly, load_tool
from core.paths.tessellation import SurfaceMesh, TriangleIndex


def _profile():
    v = np.array([[-500.0, -500.0, 0.0], [500.0, -500.0, 0.0], [500.0, 500.0, 0.0], [-500.0, 500.0, 0.0]])
    index = TriangleIndex(SurfaceMesh(v, np.array([[0, 1, 2], [0, 2, 3]])), k=8)
    n = 20
    cl = np.column_stack([np.linspace(0, 10, n), np.zeros(n), np.full(n, 1.5)])
    tilt = np.radians(np.where(np.arange(n) == 7, 89.0, 0.0))
    wl = np.column_stack([np.sin(tilt), np.zeros(n), np.cos(tilt)])
    up = np.tile([0.0, 0.0, 1.0], (n, 1))
    return check_rows(assembly(load_tool(), load_machine()), index, Clamp(-1e3, 1.0),
                      {"left": (cl, wl), "right": (cl + [0.0, 400.0, 0.0], up)})


def test_read_out_and_jumps(qtbot):
    from bladecam_gui.state import WorkbenchState

    prof = _profile()
    assert clearance_text(0.0123) == "0.012" and clearance_text(3.2).startswith("≥ 3.20")
    assert "color" in clearance_text(-0.5)
    lines = rows_at(prof, 0)
    flute = dict((w, (a, b)) for w, a, b in lines)["flute"]
    # upright over the plane at the ball's height: the flutes' capsule from 0.75 mm up clears by 0.75
    assert flute[0] == "≥ 0.75" or flute[0].startswith("≥ 0.7")
    state = WorkbenchState()
    panel = ClearancePanel(state)
    qtbot.addWidget(panel)
    panel.profile = prof
    asked = []
    state.set_cursor = asked.append  # (no plan shown: the state would keep its cursor at 0)
    panel.jump("holder")
    row, value, which = prof.closest("holder")
    assert asked == [row] and row == 7 and value < 0 and "left holder" in which
