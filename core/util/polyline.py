"""The geometry of polylines and ball-nose cutters that every stage shares, written once: unit rows,
cumulative length, the turn at a polyline's vertices, the sagitta of an interval (how far a curve
that turns by theta over a chord c strays from it: c theta / 8), and the ball centre of a cutter
(tip + r axis, SPEC.md section 2). Row norms are core.util.rowwise.row_norm (bitwise numpy's)."""

from __future__ import annotations

import math

import numpy as np

from core.util.rowwise import row_norm


def unit_rows(v: np.ndarray) -> np.ndarray:
    """(n, k) vectors (or one (k,) vector) -> unit vectors; zero vectors stay zero."""
    v = np.asarray(v, float)
    n = row_norm(v)[:, None] if v.ndim == 2 else np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def cumulative_length(points: np.ndarray) -> np.ndarray:
    """(m, 3) polyline -> (m,) cumulative length from its first point, mm."""
    if len(points) == 2:  # waits and straight moves: thousands of them per schedule (same sums as below)
        dx, dy, dz = (points[1] - points[0]).tolist()
        return np.array([0.0, math.sqrt(dx * dx + dy * dy + dz * dz)])
    return np.concatenate([[0.0], np.cumsum(row_norm(np.diff(points, axis=0)))])


def turn_angles(u: np.ndarray) -> np.ndarray:
    """(m, 3) unit directions of consecutive segments -> (m - 1,) the angle (rad) between each two."""
    return np.arccos(np.clip(np.einsum("ij,ij->i", u[:-1], u[1:]), -1.0, 1.0))


def interval_turns(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For a polyline (n, 3): the chord of each interval (n - 1,) mm, and the larger turn (rad) at its
    two ends (n - 1,)."""
    d = np.diff(points, axis=0)
    c = row_norm(d)
    turn = turn_angles(d / np.where(c > 0, c, 1.0)[:, None])
    theta = np.zeros(len(c))
    theta[:-1] = turn
    theta[1:] = np.maximum(theta[1:], turn)
    return c, theta


def sagitta(chord: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """How far an arc that turns by theta (rad) over a chord (mm) strays from it (small angles), mm."""
    return chord * theta / 8.0


def ball_centres(tips: np.ndarray, axes: np.ndarray, tool_radius: float) -> np.ndarray:
    """Ball centres tip + r axis (n, 3) mm of a ball-nose cutter's tips (n, 3) mm and unit axes (n, 3);
    also a contact point plus r times its unit outward normal (SPEC.md section 2)."""
    return tips + tool_radius * axes
