"""core.machine.staggered_axes: the staggered stretches of a collaborative pair hold the axis of the
synchronisation point where it keeps every contact within the limit, and otherwise turn once, smoothly,
to one axis that does, about fixed ball centres."""

from __future__ import annotations

import numpy as np

from core.machine.staggered_axes import staggered_axes, stretches
from core.machine.tool_axes import CONTACT_LIMIT_DEG

R = 1.5
SPINDLE = np.array([0.0, 0.0, 1.0])
TILT = 39.5


def _angle(a, b):
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)))


def _pair(n_nose: int, turn_deg: float):
    """One side of a pair along x: 50 points on a flat face (normal +z), then ``n_nose`` points whose
    normal turns about y by up to ``turn_deg`` (a rounded edge), at both ends; the axes the line
    through the ball centres would give are the normals. Boundaries as core.paths.regions makes them
    (edge = the turning points, variable = as many points next to them)."""
    flat = 50
    n = flat + 2 * n_nose
    x = np.linspace(0.0, 0.2 * (n - 1), n)
    angle = np.zeros(n)
    angle[:n_nose] = np.radians(np.linspace(turn_deg, 0.0, n_nose, endpoint=False))
    angle[n - n_nose:] = -np.radians(np.linspace(0.0, turn_deg, n_nose + 1)[1:])
    normals = np.c_[np.sin(angle), np.zeros(n), np.cos(angle)]
    contacts = np.c_[x, np.zeros(n), np.zeros(n)]
    centres = contacts + R * normals
    axes = normals.copy()
    tips = centres - R * axes
    a, b = n_nose, n - n_nose
    bounds = {"S_vl": a, "E_vl": a + n_nose, "E_ss": a + n_nose, "S_vs": b - n_nose, "S_sl": b - n_nose,
              "E_vs": b}
    return tips, axes, normals, bounds


def test_the_stretches_run_outwards_from_the_synchronisation_points():
    bounds = {"S_vl": 3, "E_vl": 6, "E_ss": 6, "S_vs": 14, "S_sl": 14, "E_vs": 17}
    (start, a0), (end, a1) = stretches(bounds, 20)
    assert a0 == 6 and start.tolist() == [5, 4, 3, 2, 1, 0]
    assert a1 == 14 and end.tolist() == [15, 16, 17, 18, 19]


def test_an_axis_that_keeps_every_contact_is_held_over_the_stretch():
    tips, axes, normals, bounds = _pair(10, 30.0)  # every contact within 30 degrees of the face normal
    (p, w), = staggered_axes([tips], [axes], [normals], [bounds], SPINDLE, TILT, R)
    for idx, anchor in stretches(bounds, len(w)):
        assert np.allclose(w[idx], axes[anchor], atol=1e-12)
    internal = np.arange(bounds["E_vl"], bounds["S_vs"] + 1)
    assert np.array_equal(w[internal], axes[internal]) and np.array_equal(p[internal], tips[internal])
    # the ball centres stay where they are
    assert np.allclose(p + R * w, tips + R * axes, atol=1e-12)


def test_round_a_nose_the_axis_turns_once_smoothly_with_every_contact_within_the_limit():
    tips, axes, normals, bounds = _pair(15, 95.0)  # the edge's normals turn 95 degrees off the face
    axes = np.where((_angle(axes, np.tile(SPINDLE, (len(axes), 1))) > TILT)[:, None],
                    np.array([0.0, 0.0, 1.0]), axes)  # (the line's axes, as the head's reach leaves them)
    tips = tips + R * (normals - axes)
    (p, w), = staggered_axes([tips], [axes], [normals], [bounds], SPINDLE, TILT, R)
    centres = tips + R * axes
    assert np.allclose(p + R * w, centres, atol=1e-12)
    assert _angle(w, normals).max() <= CONTACT_LIMIT_DEG + 1e-6
    assert _angle(w, np.tile(SPINDLE, (len(w), 1))).max() <= TILT + 1e-6
    for idx, anchor in stretches(bounds, len(w)):
        assert np.allclose(w[anchor], axes[anchor])  # the synchronisation point keeps its axis
        held = np.tile(axes[anchor], (len(idx), 1))
        first = int(np.argmax(_angle(held, normals[idx]) > CONTACT_LIMIT_DEG))
        assert first > 0
        # one turn away from the held axis, never back, and no steeper than a smoothstep over the arc
        # length to the first point the held axis cannot serve (15/8 of the mean rate there)
        turned = _angle(w[idx], held)
        assert np.all(np.diff(turned) >= -1e-9) and turned[-1] > 1.0
        path = np.vstack([centres[anchor], centres[idx]])
        ds = np.linalg.norm(np.diff(path, axis=0), axis=1)
        steps = _angle(np.vstack([w[anchor], w[idx]])[1:], np.vstack([w[anchor], w[idx]])[:-1])
        assert np.all(steps <= 15.0 / 8.0 * turned[-1] * ds / ds[:first + 1].sum() + 1e-9)
