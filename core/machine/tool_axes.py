"""Executed tool axes of the single-sided (tip region) paths: smoothed along the path.

In the tip region the paper puts the tool axis on the surface normal. Round the small sections near
the tip the normal turns by up to 180 degrees within a few millimetres of path, and the 3-RPS head
can only follow by swinging the spindle, which the XYZ stage must compensate over the gauge length
(280 mm): at the feed that asks the stage for 3-10 times its speed limit, and the machine clock
(core.machine.timing) then slows most of the tip region down.

A ball-end cutter cuts the same surface whatever its axis, as long as the contact stays on the ball
(the axis within 90 degrees of the surface normal at the contact) and the ball centre stays where it
is. So here each path's axes are smoothed along the path (the ball centres fixed, the tips moved
with the axes) within two limits at every point:

- the head's reach: the axis within ``max_tilt`` of the spindle axis (as core.machine.reach.limit_tilt);
- the contact on the ball with a margin: the axis within CONTACT_LIMIT_DEG of the surface normal
  (the contact then never nears the ball's equator, where the shank begins; a tilted axis also keeps
  the contact away from the ball's tip, where the cutting speed falls to zero).

The smoothing alternates a low-pass filter along the arc length of the ball centres (three passes of
a moving average of half-width SMOOTH_HALF_WIDTH_MM, close to a Gaussian) on the axes' tilt vectors
(tilt angle times the direction of the tilt, in the spindle's frame) with the projections onto both
limits (alternating projections onto convex sets), SMOOTH_ROUNDS times, then projects until both
limits hold. A point where they cannot both hold (the normal more than max_tilt + CONTACT_LIMIT_DEG
from the spindle axis) keeps the axis turned to the head's limit, as before.
"""

from __future__ import annotations

import numpy as np

from core.util.polyline import cumulative_length

#: the largest angle between the executed axis and the surface normal at the contact (degrees)
CONTACT_LIMIT_DEG = 80.0
#: half-width of the moving average along the path (mm of ball-centre travel)
SMOOTH_HALF_WIDTH_MM = 6.0
SMOOTH_ROUNDS = 30
FINAL_PROJECTIONS = 50
#: the limits hold to this (radians) after the final projections
ANGLE_TOLERANCE = 1e-9


def _frame(spindle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the spindle direction to a right-handed orthonormal frame."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(spindle[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(spindle, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(spindle, e1)


def to_tilt(w: np.ndarray, spindle: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """Unit axes (n, 3) -> tilt vectors (n, 2), radians: tilt angle times the tilt's direction (along
    e1 where the axis is the spindle's or its opposite)."""
    return _tilt_rows(w, np.column_stack([e1, e2, spindle])).T


def _tilt_rows(w: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """to_tilt as two contiguous rows (2, n) (the smoothing's layout: each component's moving
    average reads and writes whole rows); ``frame`` the columns e1, e2, spindle."""
    xyz = w @ frame
    rho = np.hypot(xyz[:, 0], xyz[:, 1])
    theta = np.arctan2(rho, xyz[:, 2])
    f = theta / np.where(rho > 0, rho, 1.0)
    out = np.empty((2, len(w)))
    np.multiply(f, xyz[:, 0], out=out[0])
    np.multiply(f, xyz[:, 1], out=out[1])
    flat = np.flatnonzero(rho == 0)
    out[0, flat] = theta[flat]
    return out


def from_tilt(u: np.ndarray, spindle: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """Tilt vectors (n, 2) -> unit axes (n, 3): cos(theta) spindle + sin(theta)/theta (u1 e1 + u2 e2)."""
    return _from_rows(u.T, np.vstack([spindle, e1, e2]))


def _from_rows(u: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """from_tilt of tilt vectors given as two rows (2, n); ``basis`` the rows spindle, e1, e2."""
    theta = np.hypot(u[0], u[1])
    k = np.sinc(theta / np.pi)  # sin(theta) / theta, 1 at 0
    return np.column_stack([np.cos(theta), k * u[0], k * u[1]]) @ basis


def within(w: np.ndarray, centre: np.ndarray, limit: float) -> np.ndarray:
    """Unit axes w (n, 3) turned towards the unit vectors ``centre`` ((3,) or (n, 3)), in the plane of
    the two, where they are more than ``limit`` radians from them (projection onto a cone)."""
    centre = np.broadcast_to(centre, w.shape)
    cos = np.einsum("ij,ij->i", w, centre)
    over = cos < np.cos(limit)
    if not over.any():
        return w
    perp = w[over] - cos[over, None] * centre[over]
    norm = np.linalg.norm(perp, axis=1)
    out = w.copy()
    ok = norm > 1e-12  # w opposite the centre has no plane: left for the caller's check
    sel = np.flatnonzero(over)[ok]
    out[sel] = np.cos(limit) * centre[sel] + np.sin(limit) * perp[ok] / norm[ok, None]
    return out


class _Window:
    """The moving average of piecewise-linear values u(s) over [s - half, s + half] cut to each
    point's own path [lo, hi] (paths laid end to end in s with gaps between them): the difference of
    the running integral at the two ends, over the width. The running integral is exact: trapezoids
    up to the point before an end, then the part of the next segment (quadratic in the end's place).
    Where the ends fall between the points is found once; each average is then a few gathers."""

    def __init__(self, s: np.ndarray, lo: np.ndarray, hi: np.ndarray, half: float):
        self.half_ds = 0.5 * np.diff(s)
        a, b = np.maximum(s - half, lo), np.minimum(s + half, hi)
        width = b - a
        self.ok = np.flatnonzero(width > 1e-12)  # (a point alone on its path keeps its value)
        self.width = width[self.ok]
        self.ends = [self._locate(s, a[self.ok]), self._locate(s, b[self.ok])]

    @staticmethod
    def _locate(s: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Segment k of each x (s[k] <= x <= s[k + 1]), the distance x - s[k], and half the fraction
        of the segment it covers."""
        k = np.clip(np.searchsorted(s, x, side="right") - 1, 0, len(s) - 2)
        into = x - s[k]
        return k, into, 0.5 * into / np.maximum(s[k + 1] - s[k], 1e-300)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """(m, n) values at the points, one row per quantity -> (m, n) their averages."""
        every = len(self.ok) == u.shape[1]
        out = np.empty_like(u) if every else u.copy()
        area = np.empty(u.shape[1])
        area[0] = 0.0
        (ka, ia, ha), (kb, ib, hb) = self.ends
        for j in range(u.shape[0]):
            c = np.ascontiguousarray(u[j])
            step = np.diff(c)
            np.cumsum((c[1:] + c[:-1]) * self.half_ds, out=area[1:])
            # the integral up to x in segment k: area[k] + (x - s[k]) (u[k] + f (u[k + 1] - u[k]) / 2)
            at_a = area.take(ka) + ia * (c.take(ka) + ha * step.take(ka))
            at_b = area.take(kb) + ib * (c.take(kb) + hb * step.take(kb))
            if every:
                np.divide(at_b - at_a, self.width, out=out[j])
            else:
                out[j, self.ok] = (at_b - at_a) / self.width
        return out


def smooth_axes(centres: list[np.ndarray], normals: list[np.ndarray], spindle: np.ndarray, max_tilt_deg: float
                ) -> tuple[list[np.ndarray], np.ndarray]:
    """Smoothed executed axes for paths of ball centres (each (m, 3) mm) with the surface normals at
    their contacts ((m, 3) unit): see the module docstring. Returns the axes per path and a bool
    array over all points (concatenated) telling where both limits hold."""
    if not centres:
        return [], np.zeros(0, bool)
    spindle = np.asarray(spindle, float) / np.linalg.norm(spindle)
    e1, e2 = _frame(spindle)
    tilt, contact = np.radians(max_tilt_deg), np.radians(CONTACT_LIMIT_DEG)
    n = np.concatenate(normals)
    # each path's arc length, the paths laid end to end with gaps wider than the filter
    offset, s_parts, lo, hi = 0.0, [], [], []
    for c in centres:
        cum = cumulative_length(c)
        s_parts.append(offset + cum)
        lo.append(np.full(len(c), offset))
        hi.append(np.full(len(c), offset + cum[-1]))
        offset += cum[-1] + 10.0 * SMOOTH_HALF_WIDTH_MM + 1.0
    s, lo, hi = np.concatenate(s_parts), np.concatenate(lo), np.concatenate(hi)
    w = within(n, spindle, tilt)  # the normals within reach: the start
    average = _Window(s, lo, hi, SMOOTH_HALF_WIDTH_MM)
    frame, basis = np.column_stack([e1, e2, spindle]), np.vstack([spindle, e1, e2])
    for _ in range(SMOOTH_ROUNDS):
        u = _tilt_rows(w, frame)  # (2, n): the tilt's two components as rows
        for _ in range(3):
            u = average(u)
        w = within(within(_from_rows(u, basis), n, contact), spindle, tilt)
    w = w.copy()
    active = np.arange(len(w))  # the points still moving (the projections act point by point: one
    for _ in range(FINAL_PROJECTIONS):  # that a round leaves where it is stays there)
        part = w[active]
        new = within(within(part, n[active], contact), spindle, tilt)
        moved = np.flatnonzero((new != part).any(axis=1))
        if moved.size == 0:
            break
        w[active[moved]] = new[moved]
        active = active[moved]
    ok = ((np.einsum("ij,ij->i", w, n) >= np.cos(contact + ANGLE_TOLERANCE))
          & (w @ spindle >= np.cos(tilt + ANGLE_TOLERANCE)))
    w = np.where(ok[:, None], w, within(n, spindle, tilt))
    return np.split(w, np.cumsum([len(c) for c in centres])[:-1]), ok
