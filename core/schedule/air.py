"""The moves of a cutter in the air, kept clear of the blade: backing off the blade along its normal,
the turning paths from one path's end to the next one's start (lifted higher, or taken over the top,
where the straight legs would come near the blade), the approach from the zero position and the way
home (``AirMoves``, a part of core.schedule.builder.MoveBuilder). Units: mm, ms, mm/ms, mm/ms^2."""

from __future__ import annotations

import numpy as np

from core.paths.contours import TURN_LIFT, turning_path
from core.paths.plan import PathPlan
from core.paths.tessellation import FACET_CANDIDATES, TriangleIndex, surface_mesh
from core.schedule.motion import MoveTag, ramp_law

#: mm beyond the tool radius within which a contact point counts as the ball's (AirMoves.backoff)
BACKOFF_REACH = 0.5
#: contacts looked at around a ball (both sides' ends where the contours meet at an edge's nose)
BACKOFF_SHARED = 4
HOME_CLEARANCE = 40.0    # mm beyond the blade's extent along Z_W
#: the least distance (mm) a ball moving in the air between its lift and its descent keeps from the
#: blade; a turn whose move across comes nearer is lifted higher (x2, up to MAX_TURN_LIFT mm), else
#: taken over the top (AirMoves.turn_path)
AIR_CLEARANCE = 0.5
MAX_TURN_LIFT = 16.0


class AirMoves:
    """MoveBuilder's moves in the air. Uses the builder's plan, memo, cutters (``cut``), zero
    positions (``home``), rapid speed and acceleration."""

    plan: PathPlan
    memo: dict
    #: the blade index (core.paths.tessellation.TriangleIndex), None until ``blade_index`` finds it
    index: TriangleIndex | None
    cut: dict
    home: dict
    rapid: float
    a: float
    #: mm, the blade's tip along X_W (the farthest contact point from the axis)
    tip_x: float

    def blade_index(self) -> TriangleIndex:
        """The blade index moves in the air are measured against: the one the planner keeps for the
        blade (``index``, given to the builder), else a mesh blade's facets or the check's
        tessellation (core.paths.tessellation), built here once per plan."""
        if self.index is None:
            guard = self.plan.guard
            if guard is not None and guard.index is not None:
                self.index = guard.index
            else:
                blade = self.plan.blade
                self.index = TriangleIndex(surface_mesh(blade, self.plan.frame),
                                           k=FACET_CANDIDATES if hasattr(blade, "facets") else 8)
        return self.index

    def clear_in_air(self, a: np.ndarray, b: np.ndarray, wa: np.ndarray, wb: np.ndarray,
                     leaving: bool = False) -> bool:
        """Whether a ball moving straight from tip a (axis wa) to tip b (axis wb) keeps AIR_CLEARANCE
        from the blade: the exact distance of its centre's straight move from the blade's triangles
        (the blade index's compiled search); ``leaving``: a rests on the blade and the move backs off
        from it, checked from 2 AIR_CLEARANCE of travel on."""
        r = self.plan.params.tool_radius
        ca, cb = a + r * wa, b + r * wb
        length = float(np.linalg.norm(cb - ca))
        start = min(2.0 * AIR_CLEARANCE / length, 1.0) if leaving and length > 0 else 0.0
        need = r + AIR_CLEARANCE
        dist = self.blade_index().grid.distance((ca + start * (cb - ca))[None], cb[None], need, need)
        return bool(dist[0] >= need)

    def _clear_turn(self, pts: np.ndarray, axes: np.ndarray) -> bool:
        """Every leg of a turning path (4 waypoints) clear of the blade (``clear_in_air``): its lift and
        its descent from where they leave the end they rest on (a path's end, or the zero position)."""
        return (self.clear_in_air(pts[0], pts[1], axes[0], axes[1], leaving=True)
                and self.clear_in_air(pts[1], pts[2], axes[1], axes[2])
                and self.clear_in_air(pts[3], pts[2], axes[3], axes[2], leaving=True))

    def turn_path(self, side, end_tip, end_axis, start_tip, start_axis, lift: float = TURN_LIFT):
        """The move in the air from a path's end to the next one's start (waypoints and their axes,
        straight legs between them): core.paths.contours.turning_path, backing off and coming down
        along the blade's normals (``backoff``) by ``lift``. Where its move across would come within
        AIR_CLEARANCE of the blade (round a skewed edge between distant paths) the lift is doubled,
        up to MAX_TURN_LIFT; where that is not enough, the cutter goes from its lifted end along Z_W to
        the height of its zero position (its side of the blade, HOME_CLEARANCE beyond it), across there,
        and back along Z_W to above the start. Found once per plan (the memo)."""
        key = ("turn", side, end_tip.tobytes(), end_axis.tobytes(), start_tip.tobytes(), start_axis.tobytes(),
               lift)
        if key not in self.memo:
            off = self.backoff(end_tip, end_axis), self.backoff(start_tip, start_axis)
            base = pts, axes = turning_path(end_tip, end_axis, start_tip, start_axis, lift, *off)
            high = lift
            while not self._clear_turn(pts, axes):
                high *= 2.0
                if high > MAX_TURN_LIFT:
                    pts, axes = self._over_the_top(side, *base)
                    break
                pts, axes = turning_path(end_tip, end_axis, start_tip, start_axis, high, *off)
            self.memo[key] = (pts, axes)
        return self.memo[key]

    def _over_the_top(self, side, pts: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """turn_path's way round a turning path's waypoints (4, 3): from the end backed off along its
        normal, along Z_W to the zero position's height (its side of the blade), across there, along Z_W
        down to the start backed off along its normal, and down onto it; each back-off the shortest of
        TURN_LIFT, twice that, ... up to HOME_CLEARANCE mm whose legs keep AIR_CLEARANCE (``_riser``:
        round the blade's tip where the way along Z_W would cross the blade). The given path where
        none does (the plan's own check then refuses it)."""
        safe = self.home[side][0][2]
        lift = float(np.linalg.norm(pts[1] - pts[0]))
        off = [(pts[1] - pts[0]) / lift, (pts[2] - pts[3]) / lift] if lift > 0 else [axes[0], axes[3]]
        rise0, rise1 = (self._riser(tip, d, w, safe)
                        for tip, d, w in ((pts[0], off[0], axes[0]), (pts[3], off[1], axes[3])))
        if rise0 is None or rise1 is None:
            return pts, axes
        route = np.array([pts[0], *rise0, *rise1[::-1], pts[3]])
        w = np.array([axes[0]] * (len(rise0) + 1) + [axes[3]] * (len(rise1) + 1))
        k = len(rise0)  # (the move across at the zero position's height: from route[k] to route[k + 1])
        if not self.clear_in_air(route[k], route[k + 1], w[k], w[k + 1]):
            return pts, axes
        return route, w

    def _riser(self, tip, direction, axis, safe: float) -> list[np.ndarray] | None:
        """The way from a point ``tip`` on the blade to the height ``safe`` along Z_W: backed off along
        ``direction`` by the shortest of TURN_LIFT, twice that, ... up to HOME_CLEARANCE mm, then along
        Z_W; or, where that crosses the blade (a contact round the blade's tip whose normal points to
        the other side), out along X_W beyond the blade's tip first. Every leg keeps AIR_CLEARANCE;
        None if no way does."""
        lengths = [TURN_LIFT * 2.0 ** k for k in range(8) if TURN_LIFT * 2.0 ** k < HOME_CLEARANCE]
        r = self.plan.params.tool_radius
        beyond = self.tip_x + r + 2.0 * AIR_CLEARANCE + TURN_LIFT
        ups = [up for up in (tip + h * direction for h in [*lengths, HOME_CLEARANCE])
               if self.clear_in_air(tip, up, axis, axis, leaving=True)]
        for up in ups:
            level = np.array([up[0], up[1], safe])
            if self.clear_in_air(up, level, axis, axis):
                return [up, level]
        for up in ups:
            out = np.array([max(beyond, up[0]), up[1], up[2]])
            level = np.array([out[0], out[1], safe])
            if self.clear_in_air(up, out, axis, axis) and self.clear_in_air(out, level, axis, axis):
                return [up, out, level]
        return None

    def travel(self, side, to_tip, to_axis, step, path, region, lift=TURN_LIFT) -> None:
        """Back off, move across, come down: three legs, each from rest to rest."""
        c = self.cut[side]
        pts, axes = self.turn_path(side, c.tip, c.axis, to_tip, to_axis, lift)
        for k in range(len(pts) - 1):
            a, b = pts[k], pts[k + 1]
            length = float(np.linalg.norm(b - a))
            if length <= 1e-12 and np.allclose(axes[k], axes[k + 1]):
                continue
            law = ramp_law(max(length, 1e-9), self.rapid, self.a)
            self.cut[side].add(law, pts[k:k + 2], axes[k:k + 2], MoveTag(step, path, False, region))

    def backoff(self, tip: np.ndarray, axis: np.ndarray) -> np.ndarray:
        """(3,) unit: the direction in which a ball resting on the blade at ``tip`` (axis ``axis``) backs
        off: the outward normal at the nearest blade contact the ball rests on (its centre lies outward
        along that normal; the other side's contacts, as near at a thin edge, are passed over; the
        contours' contact points and normals, both sides, sample the blade); where the two sides'
        contours meet at a sharp nose, the mean of their normals there; else its axis (no contact
        within BACKOFF_REACH of the ball, or no normal leading away). Not the axis on the blade: at an
        edge the axes lie on the line through the two ball centres, up to 90 deg from the normal where
        the balls meet round the nose at a path's end, and a ball backed off along its axis there
        slides into the blade."""
        key = ("backoff", tip.tobytes(), axis.tobytes())
        if key not in self.memo:
            if "contacts" not in self.memo:
                from scipy.spatial import cKDTree

                paths = self.plan.paths
                points = np.concatenate([c for p in paths for c in (p.left_cc, p.right_cc)])
                normals = np.concatenate([n for p in paths for n in (p.left_normals, p.right_normals)])
                self.memo["contacts"] = (cKDTree(points), points, normals)
            tree, points, normals = self.memo["contacts"]
            r = self.plan.params.tool_radius
            centre = tip + r * axis
            dist, k = tree.query(centre, k=BACKOFF_SHARED)
            # a contact the ball can rest on: the centre lies outward of it, along its normal (within
            # 60 deg); the contacts of the blade's other side, as near at a thin edge, point away. Where
            # none faces the ball (it rests on the nose where both sides' contours meet), the mean of
            # the nearest contacts' normals, if it leads away from them
            out = centre - points[k]
            near = dist <= r + BACKOFF_REACH
            facing = near & (np.einsum("ij,ij->i", normals[k], out) > 0.5 * np.maximum(dist, 1e-12))
            pick = facing if facing.any() else near
            n = normals[k[pick & (dist <= dist[pick].min(initial=np.inf) + 1e-3)]].sum(axis=0)
            size = float(np.linalg.norm(n))
            away = size > 1e-9 and float(n @ out[np.argmax(pick)]) > 0.0
            self.memo[key] = n / size if away else axis
        return self.memo[key]

    def go_home(self, side, step) -> None:
        """Back off HOME_CLEARANCE along the blade's normal, then to the zero position: straight where
        that keeps AIR_CLEARANCE from the blade, else first along Z_W to the zero position's height (its
        side of the blade, HOME_CLEARANCE beyond it) and across there."""
        tip, axis = self.home[side]
        c = self.cut[side]
        up = c.tip + HOME_CLEARANCE * self.backoff(c.tip, c.axis)
        pts, axs = np.array([c.tip, up, tip]), np.array([c.axis, c.axis, axis])
        if not self.clear_in_air(up, tip, c.axis, axis):
            level = np.array([up[0], up[1], tip[2]])
            pts, axs = np.array([c.tip, up, level, tip]), np.array([c.axis, c.axis, c.axis, axis])
        for k in range(len(pts) - 1):
            law = ramp_law(max(float(np.linalg.norm(pts[k + 1] - pts[k])), 1e-9), self.rapid, self.a)
            c.add(law, pts[k:k + 2], axs[k:k + 2], MoveTag(step, -1, False, "idle"))
