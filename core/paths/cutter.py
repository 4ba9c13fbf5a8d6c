"""Cutter location for a ball nose end mill (SPEC.md section 2, paper Eq. 1-2).

For a contact point CC with outward unit normal n: ball centre c = CC + r n; tool axis w (unit, tip ->
spindle); tool tip p = c - r w; tail point p' = p + d_T w. Single-sided machining (the tip region)
puts the axis on the normal, so p = CC. Symmetrical machining of a pair puts both axes on the line
through the two ball centres: w_L = unit(c_L - c_R), w_R = -w_L. Then p_L - p_R = (|c_L - c_R| - 2r) w_L:
the tips lie on the axis line, and their signed separation |c_L - c_R| - 2r is the tip spacing compared
with h_safe (negative where the two balls overlap, near a sharp edge, so the tips have crossed). Where
the two centres coincide (a smooth edge both sides share, with the same point and normal there) the
pair takes the axis of the nearest pair whose centres differ.
"""

from __future__ import annotations

import numpy as np

from core.errors import PlanningError


def symmetric_tools(c_left: np.ndarray, c_right: np.ndarray, tool_radius: float):
    """Tips and axes of symmetrical pairs from their ball centres.

    c_left, c_right : (n, 3) float, mm. Returns (p_left, w_left, p_right, w_right, signed_spacing):
    tips (n, 3) mm, unit axes (n, 3), signed tip spacing (n,) mm = |c_L - c_R| - 2 r.
    """
    d = c_left - c_right
    dist = np.linalg.norm(d, axis=1)
    same = dist <= 1e-12
    if same.all():
        raise PlanningError("the two ball centres coincide at every pair: no symmetrical axis anywhere")
    w = d / np.where(same, 1.0, dist)[:, None]
    if same.any():  # a smooth edge shared by both sides (the same point and normal): the nearest pair's axis
        ok, bad = np.flatnonzero(~same), np.flatnonzero(same)
        j = np.searchsorted(ok, bad)
        after, before = ok[np.minimum(j, len(ok) - 1)], ok[np.maximum(j - 1, 0)]
        w[same] = w[np.where(np.abs(after - bad) <= np.abs(bad - before), after, before)]
    return c_left - tool_radius * w, w, c_right + tool_radius * w, -w, dist - 2.0 * tool_radius


def tail_points(tips: np.ndarray, axes: np.ndarray, tool_length: float) -> np.ndarray:
    """Eq. 1-2: p' = p + d_T w. (n, 3) mm, (n, 3) unit -> (n, 3) mm."""
    return tips + tool_length * axes
