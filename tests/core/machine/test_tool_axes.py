"""Smoothed executed axes of the tip region (core.machine.tool_axes) and their use in the machine plan."""

from __future__ import annotations

import numpy as np

from core.machine.tool_axes import CONTACT_LIMIT_DEG, from_tilt, smooth_axes, to_tilt, within

Z = np.array([0.0, 0.0, 1.0])


def _rolling_path(r: float = 1.5, edge: float = 0.05):
    """Ball centres over a thin plate's face, round its rounded edge (radius ``edge``) and a little
    onto the other side, and the surface normals at the contacts: the normal turns by 110 degrees
    within a millimetre of centre travel, as round a blade's leading edge near the tip."""
    x_face = np.linspace(-30.0, 0.0, 151)
    n_face = np.tile(Z, (len(x_face), 1))
    ang = np.radians(np.linspace(0.0, 110.0, 111))[1:]
    n_edge = np.column_stack([np.sin(ang), np.zeros_like(ang), np.cos(ang)])
    c_face = np.column_stack([x_face, np.zeros_like(x_face), np.full_like(x_face, r + edge)])
    c_edge = np.array([0.0, 0.0, 0.0]) + (r + edge) * n_edge
    return np.vstack([c_face, c_edge]), np.vstack([n_face, n_edge])


def _turn_rate(c: np.ndarray, w: np.ndarray) -> np.ndarray:
    ds = np.linalg.norm(np.diff(c, axis=0), axis=1)
    return np.arccos(np.clip((w[1:] * w[:-1]).sum(1), -1.0, 1.0)) / ds


def test_tilt_chart_round_trip():
    rng = np.random.default_rng(2)
    w = rng.normal(size=(500, 3))
    w /= np.linalg.norm(w, axis=1)[:, None]
    w = w[w @ Z > -0.9]
    e1, e2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    np.testing.assert_allclose(from_tilt(to_tilt(w, Z, e1, e2), Z, e1, e2), w, atol=1e-12)


def test_smoothed_axes_keep_both_limits_and_turn_slower():
    """Round a sharp edge the normals turn at 1/(r + edge) per mm of centre travel; the smoothed axes
    stay within the head's tilt and within CONTACT_LIMIT_DEG of every normal. Where the normals turned
    to the head's limit turn (the face -> edge transition, what the machine had to follow before) the
    smoothed axes turn over a hundred times slower, and their turning energy (integral of the squared
    turn rate along the path) falls. Where the contact limit binds (the normal more than 80 degrees
    past the axis, beyond 110 - 80 = 30 degrees of tilt here) the axis has to turn with the normal:
    never faster than the normal itself."""
    c, n = _rolling_path()
    (w,), ok = smooth_axes([c], [n], Z, 39.5)
    assert ok.all()
    assert np.degrees(np.arccos(np.clip(w @ Z, -1, 1))).max() <= 39.5 + 1e-7
    assert np.degrees(np.arccos(np.clip((w * n).sum(1), -1, 1))).max() <= CONTACT_LIMIT_DEG + 1e-7
    clamped = within(n, Z, np.radians(39.5))
    rate_clamped, rate = _turn_rate(c, clamped), _turn_rate(c, w)
    turning = rate_clamped > 1e-6  # where the clamped normals turn: the first 39.5 degrees of the edge
    assert turning.sum() > 10
    assert rate[turning].max() < rate_clamped[turning].max() / 100, (rate[turning].max(), rate_clamped.max())
    ds = np.linalg.norm(np.diff(c, axis=0), axis=1)
    assert (rate**2 * ds).sum() < 0.7 * (rate_clamped**2 * ds).sum()
    assert rate.max() <= rate_clamped.max() * (1 + 1e-9)  # never faster than the normal turns
    # the turn is spread along the face: total turning is no more than the clamped normals'
    assert (np.arccos(np.clip((w[1:] * w[:-1]).sum(1), -1, 1))).sum() <= (
        np.arccos(np.clip((clamped[1:] * clamped[:-1]).sum(1), -1, 1))).sum() + 1e-9


def test_unreachable_contact_keeps_the_axis_at_the_head_limit():
    """A normal more than tilt + CONTACT_LIMIT_DEG from the spindle cannot keep both limits: that
    point keeps the normal turned to the head's limit (as limit_tilt), flagged."""
    c = np.column_stack([np.linspace(0, 10, 11), np.zeros(11), np.zeros(11)])
    n = np.tile(Z, (11, 1))
    far = np.radians(39.5 + CONTACT_LIMIT_DEG + 5.0)
    n[5] = [np.sin(far), 0.0, np.cos(far)]
    (w,), ok = smooth_axes([c], [n], Z, 39.5)
    assert not ok[5] and ok[np.arange(11) != 5].all()
    np.testing.assert_allclose(w[5], within(n[5:6], Z, np.radians(39.5))[0], atol=1e-12)


def test_machine_plan_moves_tips_not_ball_centres(sample_paths):
    """In a real plan the tip region's executed axes change, the ball centres do not (the cut surface
    is the same), both limits hold, and the other pairs only turn where beyond the head's reach."""
    from core.machine.model import load_machine
    from core.machine.reach import TILT_MARGIN_DEG, machine_plan, spindle_direction

    plan = sample_paths(dr=4.0, h_safe=1.5)
    machine = load_machine(None)
    out, changed = machine_plan(plan, machine)
    r = plan.params.tool_radius
    limit = np.radians(machine.max_tilt_deg - TILT_MARGIN_DEG)
    assert changed["left"] > 0 and changed["right"] > 0
    for a, b in zip(plan.pairs, out.pairs, strict=True):
        for side in ("left", "right"):
            old_c = getattr(a, f"{side}_tip") + r * getattr(a, f"{side}_axis")
            new_c = getattr(b, f"{side}_tip") + r * getattr(b, f"{side}_axis")
            np.testing.assert_allclose(new_c, old_c, atol=1e-12)
            w = getattr(b, f"{side}_axis")
            assert (w @ spindle_direction(machine, side) >= np.cos(limit + 1e-9)).all()
            if a.kind == "single":  # the paper's axes there are the contact normals
                assert ((w * getattr(a, f"{side}_axis")).sum(1) >= np.cos(np.radians(CONTACT_LIMIT_DEG) + 1e-9)).all()


def test_window_average_is_the_mean_of_the_piecewise_linear_values():
    """The smoothing's moving average (core.machine.tool_axes._Window) against numerical integration: the
    mean of the piecewise-linear u(s) over [s - half, s + half] cut to the point's own path, on two
    paths of irregular spacing laid end to end with a gap; a path of one point keeps its value."""
    from scipy.integrate import quad

    from core.machine.tool_axes import _Window

    rng = np.random.default_rng(5)
    parts, lo, hi, offset = [], [], [], 0.0
    for n in (40, 1, 25):
        s = offset + np.concatenate([[0.0], np.cumsum(rng.uniform(0.05, 1.0, n - 1))])
        parts.append(s)
        lo.append(np.full(n, s[0]))
        hi.append(np.full(n, s[-1]))
        offset = s[-1] + 20.0
    s, lo, hi = np.concatenate(parts), np.concatenate(lo), np.concatenate(hi)
    u = rng.normal(size=(len(s), 2))
    half = 3.0
    got = _Window(s, lo, hi, half)(u.T).T
    for i in range(len(s)):
        a, b = max(s[i] - half, lo[i]), min(s[i] + half, hi[i])
        for j in range(2):
            if b - a < 1e-12:
                assert got[i, j] == u[i, j]
                continue
            inside = s[(s > a) & (s < b)]
            val, _ = quad(lambda x, j=j: np.interp(x, s, u[:, j]), a, b, points=inside, limit=200)
            assert abs(got[i, j] - val / (b - a)) < 1e-9, (i, j)
