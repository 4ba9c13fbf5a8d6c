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

from dataclasses import replace

import numpy as np

from core.machine.clearance import REFINE, blade_distance, interpolated, motion, part_blade, sweep
from core.machine.tool_axes import CONTACT_LIMIT_DEG
from core.util.polyline import ball_centres

#: mm: what a turned axis leaves between every part and the blade (a little, for the straight moves
#: between the machines' rows, which the plan's check then measures)
CLEAR_MARGIN = 0.02
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
    table = worst.reshape(m, c)
    clears = table >= CLEAR_MARGIN
    first = np.where(clears.any(axis=1), np.argmax(clears, axis=1), np.argmax(table, axis=1))
    out = phis[np.arange(m), first]
    out[~np.isfinite(table[np.arange(m), first])] = 0.0
    return out


def _spread(arc: np.ndarray, bad: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(n, 3) rotation vectors: per pose the largest of the turns phi (at poses ``bad``) faded by a
    raised cosine over BLEND_MM of arc length ``arc`` (n,) either side."""
    lo = np.searchsorted(arc, arc[bad] - BLEND_MM, side="left")
    hi = np.searchsorted(arc, arc[bad] + BLEND_MM, side="right")
    count = hi - lo
    k = np.repeat(np.arange(len(bad)), count)
    j = np.repeat(lo, count) + (np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count))
    weight = np.clip(1.0 - np.abs(arc[j] - arc[bad][k]) / BLEND_MM, 0.0, 1.0)
    weight = 0.5 - 0.5 * np.cos(np.pi * weight)
    strength = weight * np.linalg.norm(phi, axis=1)[k]
    order = np.lexsort((strength, j))
    last = np.r_[j[order][1:] != j[order][:-1], True]      # the strongest per pose
    pick = order[last]
    out = np.zeros((len(arc), 3))
    out[j[pick]] = weight[pick, None] * phi[k[pick]]
    return out


def turn_clear(parts, index, centres: np.ndarray, axes: np.ndarray, normals: np.ndarray, spindle: np.ndarray,
               max_tilt_deg: float, starts: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Single-sided paths' axes (n, 3) turned clear of the blade where a part comes within
    CLEAR_MARGIN of it (module docstring): (the axes, the number of poses turned). ``centres`` the
    ball centres (n, 3) mm, ``normals`` the surface normals at the contacts (n, 3), W; the poses of
    several paths one after the other, ``starts`` the index of each path's first pose but the first
    (a turn never fades across paths)."""
    index = blade_distance(index)
    axes = np.array(axes, float)
    if len(centres) == 0:
        return axes, 0
    step = np.linalg.norm(np.diff(centres, axis=0), axis=1)
    if starts is not None and len(starts):
        step[np.asarray(starts) - 1] = 4 * BLEND_MM
    arc = np.concatenate([[0.0], np.cumsum(step)])
    turned = np.zeros(len(axes), bool)
    for _ in range(ROUNDS):
        bad = np.flatnonzero(path_clearance(parts, index, centres, axes) < CLEAR_MARGIN)
        if bad.size:  # (the sweep's figures are lower bounds: the poses below the margin measured closely)
            least = np.full(bad.size, np.inf)
            for part in parts:
                np.minimum(least, part_blade(part, index, centres[bad], axes[bad], refine=CLEAR_MARGIN + REFINE),
                           out=least)
            bad = bad[least < CLEAR_MARGIN]
        if not bad.size:
            break
        phi = _best_turns(parts, index, centres[bad], axes[bad], normals[bad], spindle, max_tilt_deg)
        keep = np.linalg.norm(phi, axis=1) > 0
        bad, phi = bad[keep], phi[keep]
        if not bad.size:
            break
        spread = _spread(arc, bad, phi)
        moved = np.linalg.norm(spread, axis=1) > 0
        new = _rotate(axes[moved], spread[moved])
        fits = (new @ spindle) >= np.cos(np.radians(max_tilt_deg))
        rows = np.flatnonzero(moved)[fits]
        axes[rows] = new[fits]
        turned[rows] = True
    return axes, int(turned.sum())


def avoid_pairs(paths, planned, parts, index, machine, tilt_limit_deg: float, done: dict | None = None):
    """The planned PathPlan (core.machine.reach.within_reach's) with its single-sided pairs' axes
    turned clear of the blade (``turn_clear``, the ball centres kept, the tips following), both sides;
    ``paths`` the plan before it (its single-sided pairs' axes are the surface normals). ``done``: a
    dict the caller keeps for one blade, machine and tool, of the pairs done already (by identity of
    the planned pair: the planner's rounds give back the same pairs for the paths they keep). Returns
    (the plan, poses turned per side)."""
    done = {} if done is None else done
    single = [k for k, pair in enumerate(planned.pairs) if pair.kind == "single"]
    todo = [k for k in single if done.get(id(planned.pairs[k]), (None,))[0] is not planned.pairs[k]]
    r = planned.params.tool_radius
    new: dict[int, dict] = {k: {} for k in todo}
    count = {k: {"left": 0, "right": 0} for k in todo}
    for side in ("left", "right") if todo else ():
        spindle = machine.side(side).vectors_to_workpiece(np.array([[0.0, 0.0, 1.0]]))[0]
        tips = [getattr(planned.pairs[k], f"{side}_tip") for k in todo]
        ax = [getattr(planned.pairs[k], f"{side}_axis") for k in todo]
        nrm = [getattr(paths.pairs[k], f"{side}_axis") for k in todo]
        cuts = np.cumsum([len(t) for t in tips])[:-1]
        centres = ball_centres(np.concatenate(tips), np.concatenate(ax), r)
        got, _ = turn_clear(parts, index, centres, np.concatenate(ax), np.concatenate(nrm), spindle,
                            tilt_limit_deg, starts=cuts)
        for k, c, w, w0 in zip(todo, np.split(centres, cuts), np.split(got, cuts), ax, strict=True):
            changed = np.any(w != w0, axis=1)
            count[k][side] = int(changed.sum())
            if changed.any():
                new[k][f"{side}_tip"], new[k][f"{side}_axis"] = c - r * w, w
    for k in todo:
        pair = planned.pairs[k]
        done[id(pair)] = (pair, replace(pair, **new[k]) if new[k] else pair, count[k])
    turned = {"left": 0, "right": 0}
    pairs = list(planned.pairs)
    for k in single:
        _, pairs[k], c = done[id(planned.pairs[k])]
        for side in turned:
            turned[side] += c[side]
    if not any(turned.values()):
        return planned, turned
    return replace(planned, pairs=pairs, pairs_rows=None), turned
