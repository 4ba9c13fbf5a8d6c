"""The tool axes within the machines' reach, before anything is scheduled (paper section 7; SPEC.md
section 9): the paper's tool axes (surface normals in the tip region, the line through both ball
centres elsewhere) tilt up to ~100 degrees from the spindle axis round the rounded edges, and a 3-RPS
head reaches ``max_tilt_deg`` (40 on the default machine). Where an axis tilts more, it is turned
towards the spindle axis, in the plane of the two, until it tilts by the limit less
``TILT_MARGIN_DEG``, about the ball centre (``limit_tilt``): the ball, and so the surface it cuts,
stays the same; only the tip and the shank move. The single-sided (tip region) paths' axes are chosen
within the XYZ strokes too, STROKE_MARGIN_MM inside, at the cut and at the back-off by HOME_CLEARANCE
the schedule may make from either end of a path with its axis (``stroke_caps``, ``end_backoffs``).
Applied to the plan before scheduling
(``machine_plan``), so the schedule, its safety check, the CL tables and ``bladecam verify`` all see
the executed axes; pairs.csv keeps the paper's orientation.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, Machine
from core.machine.staggered_axes import staggered_axes
from core.machine.tool_axes import Clearance, StrokeCaps, single_sided_axes
from core.schedule.builder import HOME_CLEARANCE, MoveBuilder
from core.util.parallel import per_side
from core.util.polyline import ball_centres
from core.util.rowwise import row_norm

if TYPE_CHECKING:
    from core.paths.plan import PathPlan

TILT_MARGIN_DEG = 0.5
#: the single-sided axes keep this far inside the XYZ strokes (mm): the turns between paths move the
#: axis from one path's to the next's, between the poses the strokes are kept at
STROKE_MARGIN_MM = 1.0


def spindle_direction(machine: Machine, side: str) -> np.ndarray:
    """(3,) unit vector, W: the side's spindle axis at zero tilt (+z_M), tip -> spindle."""
    return machine.side(side).vectors_to_workpiece(np.array([[0.0, 0.0, 1.0]]))[0]


def limit_tilt(tips: np.ndarray, axes: np.ndarray, tool_radius: float, spindle: np.ndarray,
               max_tilt_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tool tips (n, 3) mm and unit axes (n, 3) with every axis within ``max_tilt_deg`` of ``spindle``.

    An axis beyond it is turned towards ``spindle`` in the plane of the two, about the ball centre
    c = tip + r w, to exactly the limit; the tip follows: tip' = c - r w'. Returns the new tips, the new
    axes and a (n,) bool mask of the rows changed. Inputs are not modified.
    """
    tips = np.asarray(tips, float)
    axes = np.asarray(axes, float)
    limit = np.radians(max_tilt_deg)
    cos_t = axes @ spindle
    over = cos_t < np.cos(limit)
    if not over.any():
        return tips.copy(), axes.copy(), over
    w = axes[over]
    perp = w - cos_t[over, None] * spindle
    norm = row_norm(perp)
    # an axis exactly opposite the spindle has no plane: tilt it towards any perpendicular direction
    fallback = np.cross(spindle, [1.0, 0.0, 0.0] if abs(spindle[0]) < 0.9 else [0.0, 1.0, 0.0])
    perp = np.where(norm[:, None] > 1e-12, perp / np.where(norm > 1e-12, norm, 1.0)[:, None],
                    fallback / np.linalg.norm(fallback))
    new_w = np.cos(limit) * spindle + np.sin(limit) * perp
    out_axes = axes.copy()
    out_tips = tips.copy()
    out_axes[over] = new_w
    out_tips[over] = tips[over] + tool_radius * (w - new_w)
    return out_tips, out_axes, over


def stroke_caps(machine: Machine, side: str, centres: np.ndarray, tool_radius: float,
                poses: tuple[np.ndarray, np.ndarray, np.ndarray]) -> StrokeCaps:
    """The side's XYZ strokes, STROKE_MARGIN_MM inside, as caps on the axes w about the ball centres
    (n, 3) (core.machine.tool_axes.StrokeCaps). The stage position at tip c - r w is
    q_j = m_j . (c - r w - origin) + e m_j . w - p_j(w) (core.machine.kinematics; m_j the stage's axis
    j in W, p_j the head's parasitic centre, a few millimetres): affine in w but for p_j, so linearised
    at given axes from the exact inverse kinematics, q_j(w') = q_j(w) + (e - r) m_j . (w' - w), a
    stroke min_j <= q_j is the cap w' . m_j >= w . m_j + (min_j - q_j(w)) / (e - r), and max_j the
    like about -m_j. ``poses`` (owner (k,), offset (k, 3), lift (k,)): the poses each point holds
    its axis at besides the cut, the ball centre moved by offset + lift w (a back-off; lift along the
    axis lengthens the lever to e - r + lift)."""
    t = machine.side(side)
    dirs = np.vstack([t.rotation.T, -t.rotation.T])  # (rows: m_x, m_y, m_z, -m_x, -m_y, -m_z)
    lo = np.array([machine.limits.axis(a).min_mm for a in AXES[:3]]) + STROKE_MARGIN_MM
    hi = np.array([machine.limits.axis(a).max_mm for a in AXES[:3]]) - STROKE_MARGIN_MM
    owner, offset, lift = poses

    def bounds(index: np.ndarray, axes: np.ndarray) -> np.ndarray:
        # each point's cut, then the back-offs of those among ``index`` (ascending)
        at = np.minimum(np.searchsorted(index, owner), max(len(index) - 1, 0))
        mine = (index[at] == owner) if len(index) else np.zeros(len(owner), bool)
        row = np.concatenate([np.arange(len(index)), at[mine]])
        w = axes[row]
        up = np.concatenate([np.zeros(len(index)), lift[mine]])
        tips = np.concatenate([centres[index], centres[owner[mine]] + offset[mine]]) + (up - tool_radius)[:, None] * w
        q = inverse_kinematics(machine, side, tips, w)[:, :3]
        lever = (machine.gauge_length - tool_radius + up)[:, None]
        wm = w @ dirs[:3].T
        need = np.hstack([wm + (lo - q) / lever, (q - hi) / lever - wm])
        out = need[:len(index)]
        np.maximum.at(out, row[len(index):], need[len(index):])
        return out

    longest = machine.gauge_length - tool_radius + max(float(np.max(lift, initial=0.0)), 0.0)
    return StrokeCaps(dirs, bounds, STROKE_MARGIN_MM / longest)


def end_backoffs(plan: PathPlan, single: list[int], side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The poses (stroke_caps) of the single-sided paths ``single`` (plan.pairs indices, their points
    numbered end to end) held with the axis of a path's first and last points: the schedule's
    back-off by HOME_CLEARANCE, from and to home, along the direction the ball leaves the blade
    (core.schedule.builder.MoveBuilder.backoff: it depends on the ball centre alone, or is the axis)."""
    builder = MoveBuilder(plan, plan.params.feed, plan.params.a_max, "sigmoid", {})
    owner, offset, lift = [], [], []
    first = 0
    for k in single:
        normals = getattr(plan.pairs[k], f"{side}_axis")
        tips = getattr(plan.pairs[k], f"{side}_tip")
        for i in sorted({0, len(normals) - 1}):
            axis = normals[i]
            away = builder.backoff(tips[i], axis)
            along = away is axis  # (no contact to leave: backoff returns the axis itself)
            owner.append(first + i)
            offset.append(np.zeros(3) if along else HOME_CLEARANCE * away)
            lift.append(HOME_CLEARANCE if along else 0.0)
        first += len(normals)
    return (np.array(owner, int), np.array(offset, float).reshape(-1, 3), np.array(lift, float))


def _staggered(plan: PathPlan) -> dict[int, dict]:
    """The region boundaries of the pairs whose staggered stretches get their own axes
    (core.machine.staggered_axes): collaborative pairs of a collaborative plan, by pair."""
    if plan.params.mode != "collaborative":
        return {}
    return {k: reg.boundaries for k, (pair, reg) in enumerate(zip(plan.pairs, plan.regions, strict=True))
            if pair.kind == "symmetric" and not reg.is_tip and reg.boundaries
            and pair.left_normal is not None and pair.right_normal is not None}


def pair_key(pair) -> tuple:
    """An explicit key of a pair's geometry (what its axes within reach depend on, besides the machine
    and the tool): its path, its kind and a digest of its tips and axes."""
    h = hashlib.blake2b(digest_size=16)
    for a in (pair.left_tip, pair.left_axis, pair.right_tip, pair.right_axis):
        h.update(np.ascontiguousarray(a).data)
    return (pair.index, pair.kind, h.digest())


def machine_plan(plan: PathPlan, machine: Machine) -> tuple[PathPlan, dict[str, int]]:
    """The PathPlan with every pair's axes within the machine's reach, and the number of points changed
    per side (``within_reach``)."""
    planned, changed, _ = within_reach(plan, machine)
    return planned, changed


def within_reach(plan: PathPlan, machine: Machine, done: Mapping[tuple, tuple] | None = None,
                 clearance: Callable[[str], Clearance | None] | None = None
                 ) -> tuple[PathPlan, dict[str, int], dict[tuple, tuple]]:
    """The PathPlan with every pair's axes within the machine's reach (the limit less
    TILT_MARGIN_DEG): single-sided (tip region) pairs' axes chosen per path so that the head does not
    swing while it cuts, within the XYZ strokes (core.machine.tool_axes.single_sided_axes with
    ``stroke_caps`` and ``end_backoffs``), the others turned to the limit
    where beyond it (``limit_tilt``); the ball centres stay. Also returns the number of points changed
    per side, and each pair within reach with its count per side by ``pair_key``. ``done``: such pairs
    from an earlier call for the same machine and tool (the planner's cache): each path's axes depend
    on that path alone, so an h_safe or K_max change redoes only the pairs that changed.
    ``clearance``: side -> the tool assembly's clearance callable on that side (single_sided_axes), or
    None. Nothing passed in is changed."""
    r = plan.params.tool_radius
    limit = machine.max_tilt_deg - TILT_MARGIN_DEG
    dirs = {s: spindle_direction(machine, s) for s in ("left", "right")}
    done = {} if done is None else done
    staggered = _staggered(plan)
    keys = [pair_key(pair) + ((tuple(sorted(staggered[k].items())),) if k in staggered else ())
            for k, pair in enumerate(plan.pairs)]
    todo = [k for k, key in enumerate(keys) if key not in done]
    single = [k for k in todo if plan.pairs[k].kind == "single"]
    collaborative = [k for k in todo if k in staggered]

    poses = {s: end_backoffs(plan, single, s) for s in dirs} if single else {}

    def single_side(side: str) -> dict:
        normals = [getattr(plan.pairs[k], f"{side}_axis") for k in single]  # the paper's: the normals
        centres = [ball_centres(getattr(plan.pairs[k], f"{side}_tip"), w, r)
                   for k, w in zip(single, normals, strict=True)]
        check = clearance(side) if clearance is not None else None
        strokes = stroke_caps(machine, side, np.concatenate(centres), r, poses[side]) if single else None
        axes = single_sided_axes(centres, normals, dirs[side], limit, check, strokes).axes
        return {k: (c - r * w, w) for k, c, w in zip(single, centres, axes, strict=True)}

    def staggered_side(side: str) -> dict:
        held = [limit_tilt(getattr(plan.pairs[k], f"{side}_tip"), getattr(plan.pairs[k], f"{side}_axis"), r,
                           dirs[side], limit)[:2] for k in collaborative]
        got = staggered_axes([p for p, _ in held], [w for _, w in held],
                             [getattr(plan.pairs[k], f"{side}_normal") for k in collaborative],
                             [staggered[k] for k in collaborative], dirs[side], limit, r)
        return dict(zip(collaborative, got, strict=True))

    def chosen_side(side: str) -> dict:
        return {**single_side(side), **staggered_side(side)}

    chosen = per_side(chosen_side, parallel=len(single) + len(collaborative) > 0)
    reached = {}
    for k in todo:
        pair = plan.pairs[k]
        new, count = {}, {}
        for side in ("left", "right"):
            old_tip, old_axis = getattr(pair, f"{side}_tip"), getattr(pair, f"{side}_axis")
            if k in chosen[side]:
                tips, axes = chosen[side][k]
                mask = np.einsum("ij,ij->i", axes, old_axis) < 1.0 - 1e-12
            else:
                tips, axes, mask = limit_tilt(old_tip, old_axis, r, dirs[side], limit)
            new[f"{side}_tip"], new[f"{side}_axis"] = tips, axes
            count[side] = int(mask.sum())
        reached[keys[k]] = (replace(pair, **new), count)
    pairs, changed = [], {"left": 0, "right": 0}
    for key in keys:
        done_pair, count = reached[key] if key in reached else done[key]
        reached[key] = (done_pair, count)
        pairs.append(done_pair)
        for side in changed:
            changed[side] += count[side]
    return replace(plan, pairs=pairs, pairs_rows=None), changed, reached
