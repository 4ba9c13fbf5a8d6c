"""Turning the tool axis clear of the blade on single-sided paths.

A ball-end cutter cuts the same surface whatever its axis while the ball centre stays and the contact
stays on the ball (core.machine.tool_axes): so where a part of the assembly above the ball (neck,
shank, holder, spindle nose, head) would come within CLEAR_MARGIN of the blade on a single-sided path,
the axis is turned about the ball centre. At each such pair point the candidates are the axis turned
by TURN_ANGLES_DEG towards AZIMUTHS directions round it, within the head's tilt limit and within
CONTACT_LIMIT_DEG of the surface normal; the smallest turn that clears every part by CLEAR_MARGIN is
taken (none clearing: the one that clears most). Along the path the turn fades in and out over
BLEND_MM of ball-centre travel either side (a raised cosine), so that the axes stay smooth for the
machines; the turned path is checked again, up to ROUNDS times. What still collides is left for the
plan's collision check (core.machine.collisions), which refuses it.
"""

from __future__ import annotations

import numpy as np

from core.machine.clearance import REFINE, blade_distance, interpolated, motion, part_blade, sweep
from core.machine.tool_axes import CONTACT_LIMIT_DEG

#: mm: what a turned axis leaves between every part and the blade
CLEAR_MARGIN = 2 * REFINE
TURN_ANGLES_DEG = (3.0, 6.0, 10.0, 15.0, 20.0, 30.0, 40.0)
AZIMUTHS = 12
#: mm of ball-centre travel over which a turn fades in and out
BLEND_MM = 4.0
ROUNDS = 3


def path_clearance(parts, index, centres: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(n,) mm: the least clearance of any part from the blade at consecutive poses of one path (the
    sweep: a lower bound, exact below REFINE)."""
    n = len(centres)
    out = np.full(n, np.inf)
    for part in parts:
        moves = motion(centres, axes, max(abs(part.s0), abs(part.s1)))
        v, hidden = sweep(lambda rows, frac, part=part: part_blade(part, index, centres[rows], axes[rows])
                          if not frac.any() else _between(part, index, centres, axes, rows, frac), moves, n)
        np.minimum(out, v, out=out)
        for row, _, value in hidden:
            out[row] = min(out[row], value)
    return out


def _between(part, index, centres, axes, rows, frac):
    return part_blade(part, index, *interpolated(centres, axes, rows, frac))


def _rotate(w: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors w (n, 3) turned by rotation vectors phi (n, 3) (Rodrigues)."""
    angle = np.linalg.norm(phi, axis=1, keepdims=True)
    k = phi / np.where(angle > 0, angle, 1.0)
    c, s = np.cos(angle), np.sin(angle)
    return w * c + np.cross(k, w) * s + k * np.einsum("ij,ij->i", k, w)[:, None] * (1 - c)


def _best_turns(parts, index, centres, axes, normals, spindle, max_tilt_deg) -> np.ndarray:
    """(m, 3) rotation vectors: per pose the smallest turn of its axis that clears every part by
    CLEAR_MARGIN within the limits (the best clearing one where none does; zero where no candidate is
    within the limits)."""
    m = len(centres)
    helper = np.where(np.abs(axes[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(axes, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(axes, e1)
    cands = []
    for angle in np.radians(TURN_ANGLES_DEG):
        for az in np.linspace(0, 2 * np.pi, AZIMUTHS, endpoint=False):
            direction = np.cos(az) * e1 + np.sin(az) * e2     # the way the axis leans
            cands.append(np.cross(axes, direction) * angle)   # rotation vector taking w towards it
    phis = np.stack(cands, axis=1)                            # (m, c, 3)
    c = phis.shape[1]
    w = _rotate(np.repeat(axes, c, axis=0), phis.reshape(-1, 3))
    ok = ((w @ spindle) >= np.cos(np.radians(max_tilt_deg)))
    ok &= np.einsum("ij,ij->i", w, np.repeat(normals, c, axis=0)) >= np.cos(np.radians(CONTACT_LIMIT_DEG))
    cen = np.repeat(centres, c, axis=0)
    worst = np.full(len(w), -np.inf)
    idx = np.flatnonzero(ok)
    if idx.size:
        least = np.full(idx.size, np.inf)
        for part in parts:
            np.minimum(least, part_blade(part, index, cen[idx], w[idx], refine=CLEAR_MARGIN + REFINE), out=least)
        worst[idx] = least
    worst = worst.reshape(m, c)
    clears = worst >= CLEAR_MARGIN
    first = np.where(clears.any(axis=1), np.argmax(clears, axis=1), np.argmax(worst, axis=1))
    out = phis[np.arange(m), first]
    out[~np.isfinite(worst[np.arange(m), first])] = 0.0
    return out


def turn_clear(parts, index, centres: np.ndarray, axes: np.ndarray, normals: np.ndarray, spindle: np.ndarray,
               max_tilt_deg: float) -> tuple[np.ndarray, int]:
    """One single-sided path's axes (n, 3) turned clear of the blade where a part comes within
    CLEAR_MARGIN of it (module docstring): (the axes, the number of poses turned). ``centres`` the
    ball centres (n, 3) mm, ``normals`` the surface normals at the contacts (n, 3), W."""
    index = blade_distance(index)
    axes = np.array(axes, float)
    if len(centres) == 0:
        return axes, 0
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(centres, axis=0), axis=1))])
    turned = np.zeros(len(axes), bool)
    for _ in range(ROUNDS):
        bad = np.flatnonzero(path_clearance(parts, index, centres, axes) < CLEAR_MARGIN)
        if not bad.size:
            break
        phi = _best_turns(parts, index, centres[bad], axes[bad], normals[bad], spindle, max_tilt_deg)
        keep = np.linalg.norm(phi, axis=1) > 0
        bad, phi = bad[keep], phi[keep]
        if not bad.size:
            break
        # the turns spread along the path: per pose the largest of the faded turns round it
        weight = np.clip(1.0 - np.abs(arc[:, None] - arc[bad][None, :]) / BLEND_MM, 0.0, 1.0)
        weight = 0.5 - 0.5 * np.cos(np.pi * weight)
        strength = weight * np.linalg.norm(phi, axis=1)[None, :]
        pick = np.argmax(strength, axis=1)
        spread = weight[np.arange(len(axes)), pick][:, None] * phi[pick]
        moved = np.linalg.norm(spread, axis=1) > 0
        new = _rotate(axes[moved], spread[moved])
        fits = (new @ spindle) >= np.cos(np.radians(max_tilt_deg))
        rows = np.flatnonzero(moved)[fits]
        axes[rows] = new[fits]
        turned[rows] = True
    return axes, int(turned.sum())
