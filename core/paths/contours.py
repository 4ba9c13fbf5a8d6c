"""Contour tool paths (paper section 2, SPEC.md section 4).

Concentric circles of radius r_i about the propeller axis, projected along the axis onto the blade,
are the blade's cylindrical sections. Radii run from the tip toward the root,
r_i = tip_radius - (i + 1/2) dR for i = 0, 1, ... while r_i >= hub_radius (half a step in from the
closed tip, so that the outermost path has a real section). Each section is split at LE and TE into
its two sides: the machining-tool-paths of one symmetrical pair, the left cutter on the side facing
-Z_W, the right cutter on the side facing +Z_W. Consecutive paths alternate direction (reciprocating):
path 0 runs LE -> TE, path 1 TE -> LE, and so on. The points here are the contact points (CC) with
their outward normals in the workpiece frame; cutter locations come from core.paths.cutter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.blade.frame import WorkpieceFrame
from core.blade.model import Blade
from core.errors import PlanningError


@dataclass(frozen=True)
class ContourPath:
    """One symmetrical pair of machining-tool-paths, in machining order.

    index : int, 0 = outermost; r : float, mm; direction : +1 LE -> TE, -1 TE -> LE
    left_cc, right_cc : (n, 3), (m, 3) float, mm, workpiece frame, contact points in machining order
    left_normals, right_normals : same shapes, unit outward normals
    """

    index: int
    r: float
    direction: int
    left_cc: np.ndarray
    left_normals: np.ndarray
    right_cc: np.ndarray
    right_normals: np.ndarray


def path_radii(blade: Blade, dr: float) -> np.ndarray:
    """(n,) float, mm: the radii of the contour paths, tip first."""
    if not np.isfinite(dr) or dr <= 0:
        raise PlanningError(f"dR must be a positive number of mm, got {dr}")
    span = blade.tip_radius - blade.hub_radius
    n = int(np.floor(span / dr + 0.5))
    if n < 1:
        raise PlanningError(f"dR = {dr} mm is larger than the blade's span ({span:.3f} mm)")
    return blade.tip_radius - (np.arange(n) + 0.5) * dr


def side_assignment(blade: Blade, frame: WorkpieceFrame) -> bool:
    """True when the back faces -Z_W (so the left cutter machines the back), from the mid-span section."""
    s = blade.section(0.5 * (blade.hub_radius + blade.tip_radius))
    return float(frame.vectors(s.back_normals)[:, 2].mean()) < float(frame.vectors(s.face_normals)[:, 2].mean())


def contour_path(blade: Blade, frame: WorkpieceFrame, r: float, index: int, left_is_back: bool,
                 stations: np.ndarray | None = None) -> ContourPath:
    """The contour path at radius r (mm), number ``index`` counted from the tip (its parity sets the
    direction), on the section's chordwise ``stations`` (core.paths.stations; None: the blade's own).
    Raises BladeInputError when the blade has no section there."""
    s = blade.section(float(r)) if stations is None else blade.section(float(r), stations)
    face, back = frame.points(s.face), frame.points(s.back)
    nf, nb = frame.vectors(s.face_normals), frame.vectors(s.back_normals)
    left, nl, right, nr = (back, nb, face, nf) if left_is_back else (face, nf, back, nb)
    direction = 1 if index % 2 == 0 else -1
    if direction < 0:
        left, nl, right, nr = left[::-1], nl[::-1], right[::-1], nr[::-1]
    return ContourPath(index=index, r=float(r), direction=direction,
                       left_cc=left, left_normals=nl, right_cc=right, right_normals=nr)


#: how far a cutter backs off along its axis before it moves to the next path (mm)
TURN_LIFT = 2.0


def turning_path(end_tip: np.ndarray, end_axis: np.ndarray, start_tip: np.ndarray, start_axis: np.ndarray,
                 lift: float = TURN_LIFT, end_off: np.ndarray | None = None,
                 start_off: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The turning-tool-path that joins the end of one machining path to the start of the next on the
    same side: back off by ``lift``, move across, come down by ``lift``; the back-off and the descent
    go along ``end_off`` and ``start_off`` (unit: the directions in which the balls leave the blade,
    core.schedule.builder.MoveBuilder.backoff), the tool axes by default.

    end_tip, start_tip : (3,) float, mm; end_axis, start_axis : (3,) unit. Returns waypoints (4, 3) mm
    and their tool axes (4, 3); the tool moves in straight lines between waypoints.
    """
    end_off = end_axis if end_off is None else end_off
    start_off = start_axis if start_off is None else start_off
    pts = np.array([end_tip, end_tip + lift * end_off, start_tip + lift * start_off, start_tip])
    axes = np.array([end_axis, end_axis, start_axis, start_axis])
    return pts, axes
