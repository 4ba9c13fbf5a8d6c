"""machine.toml: the shipped default, write-back round trip, and every malformed case named by key."""

import copy
import math
import tomllib

import numpy as np
import pytest

from core.errors import MachineError
from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, default_machine_path, load_machine, machine_to_toml, parse_machine

RX180 = np.diag([1.0, -1.0, -1.0])


@pytest.fixture(scope="module")
def machine():
    return load_machine()


@pytest.fixture()
def raw():
    return tomllib.loads(default_machine_path().read_text())


def test_default_machine_loads(machine):
    assert machine.base_radius > machine.platform_radius > 0
    assert machine.gauge_length > machine.home_height > 0
    assert machine.max_tilt_deg == 40.0
    assert math.isclose(machine.home_leg_length,
                        math.hypot(machine.base_radius - machine.platform_radius, machine.home_height))
    for side in ("left", "right"):
        r = machine.side(side).rotation
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-15)
        assert np.linalg.det(r) == pytest.approx(1.0)
    # the left tool axis at zero tilt (+z_M) points to -Z_W, the right one to +Z_W
    np.testing.assert_allclose(machine.left.rotation @ [0, 0, 1], [0, 0, -1])
    np.testing.assert_allclose(machine.right.rotation @ [0, 0, 1], [0, 0, 1])
    assert machine.limits.d1.max_speed_mm_s < machine.limits.x.max_speed_mm_s
    assert machine.limits.x.max_speed_mm_s * 60 > 1000  # above a 1000 mm/min feed


def test_default_right_is_left_turned_180_about_x(machine):
    # the premise of the left/right symmetry tests in test_kinematics
    np.testing.assert_array_equal(machine.right.rotation, RX180 @ machine.left.rotation)
    np.testing.assert_array_equal(machine.right.origin, RX180 @ machine.left.origin)
    assert machine.left.origin[1] == 0.0  # so the mirror through Z_W = 0 is a y_M mirror in both frames


def test_arrays_are_read_only(machine):
    with pytest.raises(ValueError):
        machine.left.origin[0] = 1.0


def test_default_machine_reaches_the_blade_box_at_full_tilt(machine):
    # corners and edges of the W box (X 40..235, Y -90..90, Z -60..60) at max tilt, all azimuths, plus random
    g = np.array(np.meshgrid([40, 137.5, 235], [-90, 0, 90], [-60, 0, 60], indexing="ij")).reshape(3, -1).T
    phi = np.radians(np.arange(0, 360, 5.0))
    rng = np.random.default_rng(1)
    n = 20000
    for side, sgn in (("left", -1.0), ("right", 1.0)):
        for tilt in (0.0, machine.max_tilt_deg):
            t = np.radians(tilt)
            tips = np.repeat(g, len(phi), axis=0)
            f = np.tile(phi, len(g))
            axes = np.column_stack([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f),
                                    np.full_like(f, sgn * np.cos(t))])
            _assert_within_strokes(machine, inverse_kinematics(machine, side, tips, axes))
        tips = np.column_stack([rng.uniform(40, 235, n), rng.uniform(-90, 90, n), rng.uniform(-60, 60, n)])
        t = np.radians(machine.max_tilt_deg) * np.sqrt(rng.uniform(0, 1, n))
        f = rng.uniform(-np.pi, np.pi, n)
        axes = np.column_stack([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), sgn * np.cos(t)])
        _assert_within_strokes(machine, inverse_kinematics(machine, side, tips, axes))


def _assert_within_strokes(machine, values):
    for k, axis in enumerate(AXES):
        lim = machine.limits.axis(axis)
        assert lim.min_mm + 5 <= values[:, k].min(), axis
        assert values[:, k].max() <= lim.max_mm - 5, axis


def test_toml_round_trip(machine, tmp_path):
    text = machine_to_toml(machine)
    path = tmp_path / "machine.toml"
    path.write_text(text)
    again = load_machine(path)
    assert machine_to_toml(again) == text
    for name in ("base_radius", "platform_radius", "home_height", "gauge_length", "max_tilt_deg"):
        assert getattr(again, name) == getattr(machine, name)
    for side in ("left", "right"):
        np.testing.assert_array_equal(again.side(side).origin, machine.side(side).origin)
        np.testing.assert_array_equal(again.side(side).rotation, machine.side(side).rotation)
    assert again.limits == machine.limits


def test_round_trip_of_awkward_values(raw):
    raw["head"]["gauge_length_mm"] = 0.1 + 0.2
    a = np.radians(17.3)
    raw["left"]["rotation"] = [[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                               [0.0, 0.0, 1.0]]
    raw["left"]["origin_mm"] = [1e-300, -0.0, 12345.678901234567]
    m = parse_machine(raw)
    m2 = parse_machine(tomllib.loads(machine_to_toml(m)))
    assert m2.gauge_length == 0.1 + 0.2
    np.testing.assert_array_equal(m2.left.rotation, m.left.rotation)
    np.testing.assert_array_equal(m2.left.origin, m.left.origin)


def test_rounded_rotation_is_accepted_and_snapped(raw):
    s = 0.70710678  # 8 digits: orthonormal to ~1e-8
    raw["right"]["rotation"] = [[s, -s, 0], [s, s, 0], [0, 0, 1]]
    r = parse_machine(raw).right.rotation
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(r, [[s, -s, 0], [s, s, 0], [0, 0, 1]], atol=1e-8)


def _drop(d, *path):
    for key in path[:-1]:
        d = d[key]
    del d[path[-1]]


def _set(d, value, *path):
    for key in path[:-1]:
        d = d[key]
    d[path[-1]] = value


BAD = [
    # (edit, words the message must contain)
    (lambda d: _drop(d, "head", "base_radius_mm"), ["missing", "[head]", "base_radius_mm"]),
    (lambda d: _drop(d, "head", "max_tilt_deg"), ["missing", "max_tilt_deg"]),
    (lambda d: _drop(d, "head"), ["missing", "[head]"]),
    (lambda d: _drop(d, "right"), ["missing", "[right]"]),
    (lambda d: _drop(d, "left", "origin_mm"), ["missing", "[left]", "origin_mm"]),
    (lambda d: _drop(d, "right", "rotation"), ["missing", "[right]", "rotation"]),
    (lambda d: _drop(d, "limits", "d2"), ["missing", "[limits.d2]"]),
    (lambda d: _drop(d, "limits"), ["missing", "[limits]"]),
    (lambda d: _drop(d, "limits", "y", "max_accel_mm_s2"), ["missing", "[limits.y]", "max_accel_mm_s2"]),
    (lambda d: _set(d, "100", "head", "base_radius_mm"), ["[head]", "base_radius_mm", "number"]),
    (lambda d: _set(d, True, "head", "max_tilt_deg"), ["[head]", "max_tilt_deg", "number"]),
    (lambda d: _set(d, float("nan"), "head", "gauge_length_mm"), ["gauge_length_mm", "finite"]),
    (lambda d: _set(d, 5.0, "head"), ["[head]", "table"]),
    (lambda d: _set(d, [1.0, 2.0], "left", "origin_mm"), ["[left]", "origin_mm", "3 numbers"]),
    (lambda d: _set(d, "0,0,0", "left", "origin_mm"), ["[left]", "origin_mm"]),
    (lambda d: _set(d, [[1, 0, 0], [0, 1, 0]], "right", "rotation"), ["[right]", "rotation", "3 rows"]),
    (lambda d: _set(d, [[1, 0, 0], [0, 1, 0], [0, 0, "1"]], "right", "rotation"), ["[right]", "rotation"]),
    (lambda d: _set(d, "fast", "limits", "x", "max_speed_mm_s"), ["[limits.x]", "max_speed_mm_s", "number"]),
    (lambda d: _set(d, 0.0, "head", "platform_radius_mm"), ["[head]", "platform_radius_mm", "positive"]),
    (lambda d: _set(d, -5.0, "head", "home_height_mm"), ["[head]", "home_height_mm", "positive"]),
    (lambda d: _set(d, -1, "head", "gauge_length_mm"), ["[head]", "gauge_length_mm", "positive"]),
    (lambda d: _set(d, 0, "head", "base_radius_mm"), ["[head]", "base_radius_mm", "positive"]),
    (lambda d: _set(d, 95.0, "head", "max_tilt_deg"), ["[head]", "max_tilt_deg", "below 90"]),
    (lambda d: _set(d, [[1, 0, 0], [0, 1, 0], [0, 0, 2]], "left", "rotation"),
     ["[left]", "rotation", "orthonormal"]),
    (lambda d: _set(d, [[1, 0, 0], [0, 0.9, 0.1], [0, 0, 1]], "right", "rotation"),
     ["[right]", "rotation", "orthonormal"]),
    (lambda d: _set(d, [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "right", "rotation"),
     ["[right]", "rotation", "determinant"]),
    (lambda d: _set(d, 200.0, "limits", "z", "min_mm"), ["[limits.z]", "min_mm", "max_mm"]),
    (lambda d: _set(d, 55.0, "limits", "d3", "min_mm"), ["[limits.d3]", "min_mm"]),
    (lambda d: _set(d, 0.0, "limits", "d1", "max_speed_mm_s"),
     ["[limits.d1]", "max_speed_mm_s", "positive"]),
    (lambda d: _set(d, -1.0, "limits", "y", "max_accel_mm_s2"),
     ["[limits.y]", "max_accel_mm_s2", "positive"]),
]


@pytest.mark.parametrize("edit,words", BAD, ids=[" ".join(w) for _, w in BAD])
def test_bad_machine_raises_naming_the_key(raw, edit, words):
    data = copy.deepcopy(raw)
    edit(data)
    with pytest.raises(MachineError) as exc:
        parse_machine(data, source="bad.toml")
    msg = str(exc.value)
    assert "bad.toml" in msg
    for word in words:
        assert word in msg, msg


def test_bad_files(tmp_path, machine):
    with pytest.raises(MachineError, match="cannot read"):
        load_machine(tmp_path / "absent.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[head\nbase_radius_mm = 1\n")
    with pytest.raises(MachineError, match="not valid TOML"):
        load_machine(broken)
    # a file edited by hand: one key removed, the message names file and key
    text = machine_to_toml(machine).replace("home_height_mm = 180.0\n", "")
    edited = tmp_path / "edited.toml"
    edited.write_text(text)
    with pytest.raises(MachineError, match=r"edited\.toml: missing key \[head\] home_height_mm"):
        load_machine(edited)


def test_extra_keys_are_accepted(raw):
    raw["head"]["spindle"] = "ER11"
    raw["vendor"] = {"name": "bench"}
    assert parse_machine(raw).base_radius == raw["head"]["base_radius_mm"]


def test_unknown_side_and_axis(machine):
    with pytest.raises(MachineError, match="side"):
        machine.side("top")
    with pytest.raises(MachineError, match="axis"):
        machine.limits.axis("a")
