"""Executed axes of the single-sided paths (core.machine.tool_axes) and their use in the machine plan."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from core.machine.tool_axes import CONTACT_LIMIT_DEG, single_sided_axes, within
from tests.core.output.test_generated_tables import BLADES, table_text

Z = np.array([0.0, 0.0, 1.0])
R = 1.5  # ball radius, mm
TILT = 39.5


def _wrapping_path(wrap_deg: float = 110.0, edge: float = 0.05, back_wrap_deg: float | None = None):
    """Ball centres over a thin plate's face (30 mm along x), round its rounded edge at x = 0 (radius
    ``edge``) onto the other side by ``wrap_deg`` of normal, and the surface normals at the contacts:
    round the edge the normal turns by wrap_deg within a few millimetres of centre travel, as round a
    blade's leading edge in the tip region. With ``back_wrap_deg`` the path first comes round another
    edge at x = -30 (a section thinner than the ball wrapped at both ends)."""
    x_face = np.linspace(-30.0, 0.0, 151)
    n_face = np.tile(Z, (len(x_face), 1))
    ang = np.radians(np.linspace(0.0, wrap_deg, 111))[1:]
    n_edge = np.column_stack([np.sin(ang), np.zeros_like(ang), np.cos(ang)])
    c_face = np.column_stack([x_face, np.zeros_like(x_face), np.full_like(x_face, R + edge)])
    c_edge = (R + edge) * n_edge
    c, n = np.vstack([c_face, c_edge]), np.vstack([n_face, n_edge])
    if back_wrap_deg is not None:
        ang = np.radians(np.linspace(back_wrap_deg, 0.0, 111))[:-1]
        n_back = np.column_stack([-np.sin(ang), np.zeros_like(ang), np.cos(ang)])
        c_back = np.array([-30.0, 0.0, 0.0]) + (R + edge) * n_back
        c, n = np.vstack([c_back, c]), np.vstack([n_back, n])
    return c, n


def _angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Degrees between unit rows of a and b (b may be one vector)."""
    return np.degrees(np.arccos(np.clip((a * np.broadcast_to(b, a.shape)).sum(1), -1.0, 1.0)))


def _turn_per_mm(c: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Radians the axis turns per mm of ball-centre travel, per segment."""
    return np.radians(_angles(w[1:], w[:-1])) / np.linalg.norm(np.diff(c, axis=0), axis=1)


def test_within_projects_onto_caps_of_given_radii():
    """A row beyond its cap's radius lands on the cap's rim, in the plane of the row and the cap's
    centre; one inside stays; the radii may differ per row."""
    rng = np.random.default_rng(4)
    w = rng.normal(size=(300, 3))
    w /= np.linalg.norm(w, axis=1)[:, None]
    limit = rng.uniform(0.1, 1.4, 300)
    out = within(w, Z, limit)
    before, after = np.radians(_angles(w, Z)), np.radians(_angles(out, Z))
    over = before > limit
    np.testing.assert_allclose(after[over], limit[over], atol=1e-9)
    np.testing.assert_array_equal(out[~over], w[~over])
    # in the plane of w and Z: the azimuth about Z is kept
    np.testing.assert_allclose(np.arctan2(out[over, 1], out[over, 0]), np.arctan2(w[over, 1], w[over, 0]),
                               atol=1e-9)


def test_one_axis_serves_a_path_round_an_edge():
    """Round a sharp edge the normals turn by 110 degrees in a few millimetres, the head's limit
    turned normals by 39.5 degrees within a millimetre of tip. One axis keeps every contact within
    CONTACT_LIMIT_DEG and the tilt within reach: the axis is the same at every point, so the head does
    not swing while the cutter cuts; it tilts towards the edge just enough for the last contact."""
    c, n = _wrapping_path()
    got = single_sided_axes([c], [n], Z, TILT)
    (w,) = got.axes
    assert got.within_limits.all() and got.clear.all() and got.pieces.tolist() == [1]
    np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-12)
    assert _angles(w, Z).max() <= TILT + 1e-7
    contact = _angles(w, n)
    assert contact.max() <= CONTACT_LIMIT_DEG + 1e-7
    # the mean normal turned just far enough: the last contact is on the limit, the tilt is 110 - 80
    assert contact.max() == pytest.approx(CONTACT_LIMIT_DEG, abs=1e-6)
    assert _angles(w[:1], Z)[0] == pytest.approx(110.0 - CONTACT_LIMIT_DEG, abs=1e-6)
    assert w[0, 0] > 0  # towards the edge


def test_a_path_no_one_axis_serves_spreads_its_swing():
    """A section thinner than the ball wrapped at both ends (normals 200 degrees apart): no one axis
    keeps both ends' contacts on the hemisphere. The path is cut into pieces with an axis each and the
    axis swings between them along the path, within both limits everywhere; the swing is spread over
    the path, not made at the edges as the normals turn (the head's limit turned normals turn up to
    1 / (r + edge) radians per mm of centre there)."""
    c, n = _wrapping_path(wrap_deg=100.0, back_wrap_deg=100.0)
    got = single_sided_axes([c], [n], Z, TILT)
    (w,) = got.axes
    assert got.within_limits.all() and got.pieces[0] > 1
    assert _angles(w, Z).max() <= TILT + 1e-7 and _angles(w, n).max() <= CONTACT_LIMIT_DEG + 1e-7
    rate = _turn_per_mm(c, w)
    following = _turn_per_mm(c, within(n, Z, np.radians(TILT)))
    assert rate.max() < following.max() / 10
    # the least swing any axes can make: from 100 - 80 degrees one way to as much the other
    needed = np.radians(2 * (100.0 - CONTACT_LIMIT_DEG))
    assert np.radians(_angles(w[-1:], w[:1])[0]) >= needed - 1e-6
    assert rate.max() < 4 * needed / 30.0  # (30 mm of face between the edges)


def test_unreachable_contact_keeps_the_axis_at_the_head_limit():
    """A normal more than tilt + CONTACT_LIMIT_DEG from the spindle cannot keep both limits: that
    point keeps the normal turned to the head's limit, flagged; the others keep both limits."""
    c = np.column_stack([np.linspace(0, 10, 11), np.zeros(11), np.zeros(11)])
    n = np.tile(Z, (11, 1))
    far = np.radians(TILT + CONTACT_LIMIT_DEG + 5.0)
    n[5] = [np.sin(far), 0.0, np.cos(far)]
    got = single_sided_axes([c], [n], Z, TILT)
    (w,) = got.axes
    assert not got.within_limits[5] and got.within_limits[np.arange(11) != 5].all()
    np.testing.assert_allclose(w[5], within(n[5:6], Z, np.radians(TILT))[0], atol=1e-12)
    others = np.arange(11) != 5
    assert _angles(w[others], n[others]).max() <= CONTACT_LIMIT_DEG + 1e-7


def test_paths_are_chosen_independently():
    """Each path's axes depend on that path alone (the planner keeps them by path): two paths chosen
    together get the axes each gets alone."""
    c1, n1 = _wrapping_path(wrap_deg=110.0)
    c2, n2 = _wrapping_path(wrap_deg=100.0, back_wrap_deg=100.0)
    c2 = c2 + [0.0, 0.4, 0.0]
    both = single_sided_axes([c1, c2], [n1, n2], Z, TILT)
    for k, (c, n) in enumerate(((c1, n1), (c2, n2))):
        alone = single_sided_axes([c], [n], Z, TILT)
        np.testing.assert_allclose(both.axes[k], alone.axes[0], atol=1e-12)


def _neck_clearance(neck_radius: float, neck_from: float, neck_to: float, contacts, normals):
    """A geometric clearance: the neck (a cylinder of ``neck_radius`` from ``neck_from`` to ``neck_to``
    mm along the axis from the ball centre) against the blade's tangent plane at each contact: the
    signed distance of the cylinder from the plane, the least over its two end circles (a cylinder's
    distance to a plane is least on an end circle: n.(c + h w) - R |w x n| is linear in h)."""

    def clearance(centres: np.ndarray, axes: np.ndarray) -> np.ndarray:
        cos = (axes * normals).sum(1)
        sin = np.sqrt(np.maximum(1.0 - cos**2, 0.0))
        base = ((centres - contacts) * normals).sum(1)
        return np.minimum(base + neck_from * cos, base + neck_to * cos) - neck_radius * sin

    return clearance


def test_a_colliding_neck_turns_the_axis_towards_the_normal():
    """A neck thicker than the ball (1.7 mm from 0.3 mm above the centre) reaches below the tangent
    plane of a contact about 70 degrees or more off the axis. Round an edge wrapped by 95 degrees the
    path's one axis has the last contacts 80 degrees off it: the clearance check finds the neck
    there in the blade, and the axis is turned further towards the edge's normals until every contact
    clears, still one axis for the path, within both limits."""
    c, n = _wrapping_path(wrap_deg=95.0)
    contacts = c - R * n
    check = _neck_clearance(1.7, 0.3, 12.0, contacts, n)
    plain = single_sided_axes([c], [n], Z, TILT)
    assert (check(c, plain.axes[0]) < 0).any()  # (the test's collision is real without the check)
    got = single_sided_axes([c], [n], Z, TILT, clearance=check)
    (w,) = got.axes
    assert got.clear.all() and got.within_limits.all() and got.pieces.tolist() == [1]
    assert (check(c, w) >= 0).all()
    assert _angles(w, Z).max() <= TILT + 1e-7 and _angles(w, n).max() <= CONTACT_LIMIT_DEG + 1e-7
    np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-12)


def test_a_collision_no_turn_clears_is_flagged():
    """A neck that collides whatever the axis within reach (a neck far thicker than the ball) is
    flagged where it collides; the axes still keep both limits."""
    c, n = _wrapping_path(wrap_deg=95.0)
    check = _neck_clearance(3.0, 0.3, 12.0, c - R * n, n)
    got = single_sided_axes([c], [n], Z, TILT, clearance=check)
    assert not got.clear.all()
    np.testing.assert_array_equal(got.clear, check(c, got.axes[0]) >= 0)
    assert got.within_limits.all()


def test_machine_plan_moves_tips_not_ball_centres(sample_paths):
    """In a real plan the single-sided pairs' executed axes change, the ball centres do not (the cut
    surface is the same), both limits hold, each single-sided path has one axis, and the other pairs
    only turn where beyond the head's reach."""
    from core.machine.model import load_machine
    from core.machine.reach import TILT_MARGIN_DEG, machine_plan, spindle_direction

    plan = sample_paths(dr=4.0, h_safe=1.5)
    machine = load_machine(None)
    out, changed = machine_plan(plan, machine)
    r = plan.params.tool_radius
    limit = np.radians(machine.max_tilt_deg - TILT_MARGIN_DEG)
    assert changed["left"] > 0 and changed["right"] > 0
    assert any(a.kind == "single" for a in plan.pairs)
    for a, b in zip(plan.pairs, out.pairs, strict=True):
        for side in ("left", "right"):
            old_c = getattr(a, f"{side}_tip") + r * getattr(a, f"{side}_axis")
            new_c = getattr(b, f"{side}_tip") + r * getattr(b, f"{side}_axis")
            np.testing.assert_allclose(new_c, old_c, atol=1e-12)
            w = getattr(b, f"{side}_axis")
            assert (w @ spindle_direction(machine, side) >= np.cos(limit + 1e-9)).all()
            if a.kind == "single":  # the paper's axes there are the contact normals
                contact = (w * getattr(a, f"{side}_axis")).sum(1)
                assert (contact >= np.cos(np.radians(CONTACT_LIMIT_DEG) + 1e-9)).all()
                np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-12)


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(blade=st.fixed_dictionaries(BLADES))
def test_generated_blades_single_sided_axes(tmp_path_factory, blade):
    """Over plausible generated blades (the generated geometry tables' generator), every single-sided
    path's executed axes keep the ball centres and the head's reach, and every contact the machine can
    reach on the cutting hemisphere's margin (its normal within max_tilt + CONTACT_LIMIT_DEG of the
    spindle) is within CONTACT_LIMIT_DEG of the axis; a contact beyond has the least angle the head
    allows (its normal turned to the head's limit). On every path with no such contact the head's
    swing stays within what the machine does at the feed: through the inverse kinematics, no axis
    moves faster than its limit with the tip at the feed."""
    from core.blade.source import load_blade
    from core.machine.kinematics import inverse_kinematics
    from core.machine.model import AXES, load_machine
    from core.machine.reach import TILT_MARGIN_DEG, machine_plan, spindle_direction
    from core.paths.planning import plan_paths
    from core.records import PlanParameters

    table = tmp_path_factory.mktemp("table") / "blade.csv"
    table.write_text(table_text(**blade))
    plan = plan_paths(load_blade(str(table)), PlanParameters(dr=3.0))
    machine = load_machine(None)
    out, _ = machine_plan(plan, machine)
    r, feed = plan.params.tool_radius, plan.params.feed / 60.0
    v_lim = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES])
    tilt = np.radians(machine.max_tilt_deg - TILT_MARGIN_DEG)
    single = [(a, b) for a, b in zip(plan.pairs, out.pairs, strict=True) if a.kind == "single"]
    assert single
    for a, b in single:
        for side in ("left", "right"):
            n, w, tips = getattr(a, f"{side}_axis"), getattr(b, f"{side}_axis"), getattr(b, f"{side}_tip")
            np.testing.assert_allclose(tips + r * w, getattr(a, f"{side}_tip") + r * n, atol=1e-12)
            spindle = spindle_direction(machine, side)
            assert (w @ spindle >= np.cos(tilt + 1e-9)).all()
            beyond = n @ spindle < np.cos(tilt + np.radians(CONTACT_LIMIT_DEG))
            assert ((w * n).sum(1)[~beyond] >= np.cos(np.radians(CONTACT_LIMIT_DEG) + 1e-9)).all()
            least = np.arccos(np.clip(n[beyond] @ spindle, -1, 1)) - tilt  # (its normal turned to the limit)
            assert (np.arccos(np.clip((w[beyond] * n[beyond]).sum(1), -1, 1)) <= least + 1e-7).all()
            if beyond.any():
                continue
            q = inverse_kinematics(machine, side, tips, w)
            dp = np.linalg.norm(np.diff(tips, axis=0), axis=1)
            moving = dp > 1e-9
            speed = np.abs(np.diff(q, axis=0))[moving] / dp[moving, None] * feed
            assert (speed <= v_lim).all(), (a.index, side, speed.max(axis=0))


def test_within_reach_turns_the_sample_axes_clear_of_a_colliding_neck(sample_paths):
    """The planner's step passes a clearance per side: on the sample, a neck thicker than the ball
    (1.7 mm from 0.3 mm above the centre) reaches into the tangent plane of about a hundred contacts a
    side on the plain axes; with the check, none, within both limits, the ball centres where they were
    (a path whose narrowed caps no one axis serves gets pieces)."""
    from core.machine.model import load_machine
    from core.machine.reach import TILT_MARGIN_DEG, spindle_direction, within_reach

    plan = sample_paths(dr=4.0, h_safe=1.5)
    machine = load_machine(None)
    r = plan.params.tool_radius
    single = [p for p in plan.pairs if p.kind == "single"]

    def contacts(side):
        return (np.concatenate([getattr(p, f"{side}_tip") for p in single]),
                np.concatenate([getattr(p, f"{side}_axis") for p in single]))

    def check(side):
        return _neck_clearance(1.7, 0.3, 12.0, *contacts(side))

    plain, _, _ = within_reach(plan, machine)
    turned, _, _ = within_reach(plan, machine, clearance=check)
    tilt = np.radians(machine.max_tilt_deg - TILT_MARGIN_DEG)
    for side in ("left", "right"):
        cc, n = contacts(side)
        centres = cc + r * n

        def axes(p, side=side):
            return np.concatenate([getattr(a, f"{side}_axis") for a in p.pairs if a.kind == "single"])

        assert (check(side)(centres, axes(plain)) < 0).sum() > 20
        w = axes(turned)
        assert (check(side)(centres, w) >= 0).all()
        assert (w @ spindle_direction(machine, side) >= np.cos(tilt + 1e-9)).all()
        assert _angles(w, n).max() <= CONTACT_LIMIT_DEG + 1e-7
        for a, b in zip(plan.pairs, turned.pairs, strict=True):
            if a.kind == "single":
                wb = getattr(b, f"{side}_axis")
                np.testing.assert_allclose(getattr(b, f"{side}_tip") + r * wb,
                                           getattr(a, f"{side}_tip") + r * getattr(a, f"{side}_axis"), atol=1e-12)


def _stroke_case(x_min_above: float):
    """The 95-degree wrap round an edge on the right machine (spindle +Z_W), 100 mm along X_W from its
    home, and the default machine with the x stroke's low end ``x_min_above`` mm above the lowest x
    the path's axes take without the strokes (the path's one axis tilted 15 degrees towards the edge,
    +X_W: more tilt moves x up): the path, the machine, the strokes' caps (no back-offs) and the axes
    without the strokes."""
    from dataclasses import replace

    from core.machine.kinematics import inverse_kinematics
    from core.machine.model import load_machine
    from core.machine.reach import TILT_MARGIN_DEG, spindle_direction, stroke_caps

    c, n = _wrapping_path(wrap_deg=95.0)
    c = c + [137.5 + 100.0, 0.0, 0.0]
    base = load_machine(None)
    spindle = spindle_direction(base, "right")
    tilt = base.max_tilt_deg - TILT_MARGIN_DEG
    plain = single_sided_axes([c], [n], spindle, tilt).axes[0]
    x_min = inverse_kinematics(base, "right", c - R * plain, plain)[:, 0].min() + x_min_above
    machine = replace(base, limits=replace(base.limits, x=replace(base.limits.x, min_mm=float(x_min))))
    none = (np.zeros(0, int), np.zeros((0, 3)), np.zeros(0))
    return c, n, machine, spindle, tilt, stroke_caps(machine, "right", c, R, none), plain


def test_the_axes_keep_the_strokes_where_an_axis_does():
    """Where the path's one axis without the strokes takes the stage's x below its stroke (by 20 mm),
    the axis is chosen within the strokes too: through the inverse kinematics (not the caps), every
    point's six axis values are within the machine's strokes; the path keeps one axis, within the
    head's reach and the contact limit, tilted further towards the edge."""
    from core.machine.kinematics import inverse_kinematics
    from core.machine.model import AXES

    c, n, machine, spindle, tilt, caps, plain = _stroke_case(20.0)
    q_plain = inverse_kinematics(machine, "right", c - R * plain, plain)
    assert q_plain[:, 0].min() < machine.limits.x.min_mm - 19.0  # (the case: out of the stroke without it)
    got = single_sided_axes([c], [n], spindle, tilt, strokes=caps)
    (w,) = got.axes
    assert got.within_strokes.all() and got.within_limits.all() and got.pieces.tolist() == [1]
    q = inverse_kinematics(machine, "right", c - R * w, w)
    for j, name in enumerate(AXES):
        lim = machine.limits.axis(name)
        assert lim.min_mm <= q[:, j].min() and q[:, j].max() <= lim.max_mm, (name, q[:, j].min(), q[:, j].max())
    np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-12)
    assert _angles(w, spindle).max() <= tilt + 1e-7 and _angles(w, n).max() <= CONTACT_LIMIT_DEG + 1e-7
    assert _angles(w[:1], spindle)[0] > _angles(plain[:1], spindle)[0] + 3.0


def test_a_stroke_no_axis_keeps_is_flagged():
    """Where no axis within the head's reach keeps a point within the stroke (x's low end 120 mm above
    the path's axes without it: the points on the face would need the head tilted beyond its 39.5
    degrees), those points are flagged out of the strokes, exactly where the inverse kinematics finds
    them out, and the path's one axis is chosen for the others (within both limits); the plan's own
    limit check then refuses the plan."""
    from core.machine.kinematics import inverse_kinematics

    c, n, machine, spindle, tilt, caps, plain = _stroke_case(120.0)
    got = single_sided_axes([c], [n], spindle, tilt, strokes=caps)
    (w,) = got.axes
    q = inverse_kinematics(machine, "right", c - R * w, w)
    np.testing.assert_array_equal(got.within_strokes, q[:, 0] >= machine.limits.x.min_mm)
    assert 0 < got.within_strokes.sum() < len(c) and got.within_limits.all() and got.pieces.tolist() == [1]
    np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-12)
    assert _angles(w, spindle).max() <= tilt + 1e-7 and _angles(w, n).max() <= CONTACT_LIMIT_DEG + 1e-7
