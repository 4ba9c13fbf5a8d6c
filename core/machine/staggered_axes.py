"""Executed tool axes of the staggered stretches of collaborative paths: the head holds one axis while
its cutter cuts an edge alone, instead of swinging round the edge with the line through both balls.

Between its synchronisation points a collaborative path is machined symmetrically: both cutters at
the two points of a pair, their axes on the line through the two ball centres (the paper's axes).
At each end the cutters are staggered (steps 5 and 6): each cuts the variable and edge stretches of
its side while the other is elsewhere, and the paper holds the axis there at the line of the pair
before the staggering. Round a rounded edge the line through the ball centres of each pair turns by
tens of degrees within a few millimetres of tip, and a head following it swings the spindle, which
the XYZ stage compensates over the gauge length; the caps of the machine clock then slow both
machines to a few per cent of the feed for the whole edge stretch, and the cutter in its speed stage
on the other side crawls with them.

So each staggered stretch (the points of one side before E_vl, or after S_vs) holds the axis of its
synchronisation point (the line through both centres there), as the paper says, wherever that axis
keeps every contact of the stretch within CONTACT_LIMIT_DEG of it. Where it does not (round the
nose), the axis is projected from it onto the caps of the whole stretch (contact and head's reach,
core.machine.tool_axes: the nearest axis that serves every point), and the stretch turns from the
synchronisation point's axis to that one with a quintic smoothstep in the ball centre's arc length,
over the longest span that still gives every point the share of the turn its contact needs: the head
turns once, as gently as the contacts allow, and holds its axis round the nose.

The ball centres do not move (the surface cut is the same); only the tips and the shanks do. A
stretch that no one axis serves, or whose turned axes would put a contact further from its axis than
the line through the ball centres does (and beyond CONTACT_LIMIT_DEG), or outside the head's reach,
keeps the line's axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.machine.tool_axes import ANGLE_TOLERANCE, CONTACT_LIMIT_DEG, _piece_axes
from core.util.polyline import ball_centres, cumulative_length, unit_rows


def stretches(boundaries: dict, n: int) -> list[tuple[np.ndarray, int]]:
    """The staggered stretches of a collaborative pair of n points with these region boundaries
    (core.paths.regions.Regions.boundaries): (points, anchor) each, the points in order from the
    synchronisation point ``anchor`` (E_vl or S_vs) outwards, excluding it."""
    out = []
    if boundaries["E_vl"] > 0:
        out.append((np.arange(boundaries["E_vl"] - 1, -1, -1), boundaries["E_vl"]))
    if boundaries["S_vs"] < n - 1:
        out.append((np.arange(boundaries["S_vs"] + 1, n), boundaries["S_vs"]))
    return out


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (10.0 + x * (-15.0 + 6.0 * x))


def _smooth_inverse(share: np.ndarray) -> np.ndarray:
    """x in [0, 1] with _smoothstep(x) = share (monotonic: by interpolation on a fine table)."""
    x = np.linspace(0.0, 1.0, 2049)
    return np.maximum(np.interp(share, _smoothstep(x), x), 1e-12)


def _least_share(w_from: np.ndarray, w_to: np.ndarray, normals: np.ndarray, cos_contact: float) -> np.ndarray:
    """(n,) the least share sigma of the turn from w_from to w_to (each (n, 3): the axis
    unit((1 - sigma) w_from + sigma w_to)) that keeps each contact normal within the contact limit (w_to
    keeps them all; the cap is convex, so the shares that keep one form an interval up to 1): by
    bisection."""
    lo, hi = np.zeros(len(normals)), np.ones(len(normals))
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        w = unit_rows((1.0 - mid)[:, None] * w_from + mid[:, None] * w_to)
        ok = np.einsum("ij,ij->i", w, normals) >= cos_contact
        hi, lo = np.where(ok, mid, hi), np.where(ok, lo, mid)
    return np.where(np.einsum("ij,ij->i", normals, w_from) >= cos_contact, 0.0, hi)


def staggered_axes(tips: Sequence[np.ndarray], axes: Sequence[np.ndarray], normals: Sequence[np.ndarray],
                   boundaries: Sequence[dict], spindle: np.ndarray, max_tilt_deg: float, tool_radius: float
                   ) -> list[tuple[np.ndarray, np.ndarray]]:
    """One side of collaborative pairs: each pair's tips and axes (n, 3) within the head's reach (the
    line through the ball centres, tilt-limited), the contact normals (n, 3) and the region boundaries
    -> the pair's tips and axes with its staggered stretches' axes chosen (module docstring). Every
    stretch of every pair is solved in one pass: one projection (``_piece_axes``, a piece per
    stretch) and one bisection of the shares."""
    r = tool_radius
    spindle = np.asarray(spindle, float) / np.linalg.norm(spindle)
    tilt = np.radians(max_tilt_deg)
    cos_contact = np.cos(np.radians(CONTACT_LIMIT_DEG) + ANGLE_TOLERANCE)
    cos_tilt = np.cos(tilt + ANGLE_TOLERANCE)
    out = [(np.array(p, float), np.array(w, float)) for p, w in zip(tips, axes, strict=True)]
    found = _stretches_of(out, normals, boundaries, r, cos_contact)
    turned = _turned_axes([f for f in found if not f.held.all()], spindle, tilt, cos_contact)
    for f in found:
        w_new = np.tile(f.w_anchor, (len(f.idx), 1)) if f.held.all() else turned.get(id(f))
        if w_new is None:
            continue
        p, w = out[f.pair]
        contact_old = np.einsum("ij,ij->i", w[f.idx], f.normals)
        keeps = ((np.einsum("ij,ij->i", w_new, f.normals) >= np.minimum(cos_contact, contact_old))
                 & (w_new @ spindle >= cos_tilt))
        if keeps.all():
            w[f.idx] = w_new
            p[f.idx] = f.centres[1:] - r * w_new
    return out


@dataclass
class _Stretch:
    """One staggered stretch of pair ``pair``: its points ``idx`` from the synchronisation point
    outwards, their contact normals, the ball centres from the synchronisation point's on (len(idx) + 1,
    3), the synchronisation point's axis, and which contacts that axis keeps within the limit."""

    pair: int
    idx: np.ndarray
    normals: np.ndarray
    centres: np.ndarray
    w_anchor: np.ndarray
    held: np.ndarray


def _stretches_of(pairs: list, normals: Sequence[np.ndarray], boundaries: Sequence[dict], r: float,
                  cos_contact: float) -> list[_Stretch]:
    """Every staggered stretch of the pairs (tips, axes) in order, pair by pair."""
    found = []
    for k, ((p, w), nrm, bd) in enumerate(zip(pairs, normals, boundaries, strict=True)):
        c = ball_centres(p, w, r)
        for idx, anchor in stretches(bd, len(c)):
            n = nrm[idx]
            found.append(_Stretch(k, idx, n, c[np.append(anchor, idx)], w[anchor].copy(),
                                  n @ w[anchor] >= cos_contact))
    return found


def _turned_axes(turning: list[_Stretch], spindle: np.ndarray, tilt: float, cos_contact: float) -> dict:
    """{id(stretch): its axes (m, 3)} for stretches whose contacts the synchronisation point's axis does
    not all keep: the nearest axis that serves every contact (one piece each), reached from the
    synchronisation point's axis with a quintic smoothstep in the ball centre's arc length over the
    longest span that gives each contact its share of the turn (module docstring). A stretch no one
    axis serves is left out."""
    if not turning:
        return {}
    sizes = np.array([len(f.idx) for f in turning])
    starts = np.cumsum(sizes) - sizes
    n = np.concatenate([f.normals for f in turning])
    anchors = np.array([f.w_anchor for f in turning])
    limit = np.full(len(n), np.radians(CONTACT_LIMIT_DEG))
    one, ok = _piece_axes(n, anchors, starts, limit, spindle, tilt)
    owner = np.repeat(np.arange(len(turning)), sizes)
    need = _least_share(anchors[owner], one[owner], n, cos_contact)
    out = {}
    for j, f in enumerate(turning):
        if not ok[j]:
            continue
        s = cumulative_length(f.centres)[1:]
        share = need[starts[j]:starts[j] + sizes[j]]
        span = min(float(s[-1]), float(np.min(s[~f.held] / _smooth_inverse(share[~f.held]))))
        sigma = _smoothstep(s / span) if span > 0 else np.ones(len(f.idx))
        out[id(f)] = unit_rows((1.0 - sigma)[:, None] * f.w_anchor + sigma[:, None] * one[j])
    return out
