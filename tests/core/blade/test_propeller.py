"""One blade of a whole propeller mesh: a 5-blade propeller made of the real BladeX blade (its two sides and
caps, turned about the X axis by 72 degrees a copy) on a hub cylinder, merged into one STL. The blade
picked out of it is checked against the BladeX pair it was made of, and planned."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from core.blade.mesh_tools import farthest_pair
from core.blade.propeller import HUB_MARGIN, TIP_BAND, _sample_points, hub_end, split_propeller
from core.blade.source import SourceOptions, load_blade, make_options, split_options, with_options
from core.errors import BladeInputError

from ...conftest import cli
from .propellers import HUB_RADIUS, N_BLADES, bladex_propeller, turn_x


@pytest.fixture(scope="module")
def bladex_parts(bladex_dir):
    return {k: trimesh.load(bladex_dir / f"{k}.stl") for k in ("upper", "lower", "tip", "root")}


@pytest.fixture(scope="module")
def propeller_stl(bladex_dir, tmp_path_factory):
    return bladex_propeller(bladex_dir, tmp_path_factory.mktemp("prop") / "propeller.stl")


def copy_of(vertices: np.ndarray, upper: trimesh.Trimesh) -> np.ndarray:
    """The rotation that turns ``vertices`` (file frame) back onto the original blade: of the N_BLADES
    copies, the one whose vertices then coincide best with upper.stl's."""
    tree = cKDTree(upper.vertices)
    turns = [turn_x(-360.0 * k / N_BLADES) for k in range(N_BLADES)]
    return min(turns, key=lambda t: np.median(tree.query(vertices @ t.T)[0]))


def test_five_blades_found_evenly_round_the_axis_outside_the_hub(propeller_stl, bladex_parts):
    blade = load_blade(str(propeller_stl), axis="x")
    prop = blade.propeller
    # the original blade's facets outside the cut, and those across it (each clipped into one or two)
    whole = trimesh.util.concatenate(list(bladex_parts.values()))
    fr = np.hypot(whole.vertices[:, 1], whole.vertices[:, 2])[whole.faces]
    outside = int((fr.min(axis=1) >= prop.r_min).sum())
    across = int(((fr.min(axis=1) < prop.r_min) & (fr.max(axis=1) >= prop.r_min)).sum())
    assert all(outside + across <= b.facets <= outside + 2 * across for b in prop.blades)
    # blade 1's angle: the copy's area centroid about X from file y towards z, within a degree (the
    # root cut off changes it a little)
    tri = whole.triangles[fr.min(axis=1) >= prop.r_min]
    area = whole.area_faces[fr.min(axis=1) >= prop.r_min]
    c = (area[:, None] * tri.mean(axis=1)).sum(axis=0)
    first = np.degrees(np.arctan2(c[2], c[1])) % (360.0 / N_BLADES)
    assert prop.blades[0].angle_deg == pytest.approx(first, abs=1.0)
    assert len(prop.blades) == N_BLADES
    assert any("whole propeller: 5 blades" in w for w in blade.warnings)
    # the hub's full circle ends at the hub cylinder, within one of hub_end's bands (tip / 200)
    assert HUB_RADIUS <= prop.hub_end <= HUB_RADIUS + 125.0 / 200 + 1e-9
    assert prop.r_min == pytest.approx(prop.hub_end + HUB_MARGIN * (125.0 - prop.hub_end))
    angles = np.array([b.angle_deg for b in prop.blades])
    assert np.all(np.diff(angles) == pytest.approx(72.0, abs=1e-6))
    for b in prop.blades:
        assert b.r_from == pytest.approx(prop.r_min, abs=1e-9)
        assert b.r_to == pytest.approx(125.0, abs=1e-3)  # (README: the blade spans r 34.375 to 125.0)
    assert blade.hub_radius == pytest.approx(prop.r_min, abs=1e-6)


def test_hub_end_of_a_bare_cylinder_is_its_radius_and_it_has_no_blades():
    hub = trimesh.creation.cylinder(radius=20.0, height=30.0, sections=256)
    assert hub_end(np.asarray(hub.vertices), np.asarray(hub.faces)) == pytest.approx(20.0, abs=20.0 / 200 + 1e-9)
    with pytest.raises(BladeInputError, match="no blades about it"):
        split_propeller(hub.vertices, hub.faces, np.eye(3), np.zeros(3), 1.0)


@pytest.mark.parametrize("k", [1, 4])
def test_blade_k_face_and_back_are_the_pairs_sides(propeller_stl, bladex_parts, k):
    """Every vertex of the picked face and back that is not on the hub cut is a vertex of the BladeX pair
    (float32 STL: 1e-4 mm), every pair vertex outside the cut and off the tip's lid is in them, and
    the face is upper.stl's side:
    it holds the upper vertices that are not on lower.stl except within a few facets of LE and TE."""
    up, lo = bladex_parts["upper"], bladex_parts["lower"]
    blade = load_blade(f"{propeller_stl}?blade={k}", axis="x")
    assert blade.blade_index == k and blade.warnings == []
    picked = blade.propeller.blades[k - 1]
    turn = copy_of(picked.face.vertices, up)
    r_min = blade.propeller.r_min
    sides = {}
    for name, m in (("face", picked.face), ("back", picked.back)):
        v = np.asarray(m.vertices) @ turn.T
        r = np.hypot(v[:, 1], v[:, 2])
        assert r.min() >= r_min - 1e-6
        sides[name] = v[r > r_min + 1e-6]
    d_up = {n: cKDTree(up.vertices).query(v)[0] for n, v in sides.items()}
    d_lo = {n: cKDTree(lo.vertices).query(v)[0] for n, v in sides.items()}
    for n in sides:
        off = np.minimum(d_up[n], d_lo[n]) > 1e-4
        # the only others: tip-lid corners at the tip (lid facets whose corners lie on the sides)
        assert np.all(np.hypot(sides[n][off, 1], sides[n][off, 2]) > 125.0 - 1e-3), n
    both = np.vstack(list(sides.values()))
    for orig in (up, lo):
        r = np.hypot(orig.vertices[:, 1], orig.vertices[:, 2])
        lost = cKDTree(both).query(orig.vertices)[0] > 1e-4
        # the only ones missing: on the tip's lid, facets whose corners all lie within TIP_BAND of the
        # span from the tip (the sides' facets facing the tip stay sides)
        assert np.all(r[lost & (r > r_min + 1e-6)] >= 125.0 - TIP_BAND * (125.0 - r_min) - 1e-4)
    for n, own, other in (("face", d_up, d_lo), ("back", d_lo, d_up)):
        mine = (own[n] < 1e-4) & (other[n] > 1e-4)
        theirs = (other[n] < 1e-4) & (own[n] > 1e-4)
        assert mine.sum() > 3 * theirs.sum(), n


@pytest.mark.parametrize("r", [50.0, 80.0, 110.0])
def test_blade_k_sections_are_the_pairs(propeller_stl, bladex_parts, bladex_dir, r):
    """The picked blade's sections lie on the pair's (the same facets), and its LE and TE within 0.4 mm
    of the pair's (each puts them where its sides meet)."""
    pair = load_blade(f"{bladex_dir / 'lower.stl'},{bladex_dir / 'upper.stl'}", axis="x")
    blade = load_blade(f"{propeller_stl}?blade=2", axis="x")
    turn = copy_of(blade.propeller.blades[1].face.vertices, bladex_parts["upper"])

    def to_file(b, p):  # blade frame -> the file's frame
        return (p - b.transform[:3, 3]) @ b.transform[:3, :3]

    sp, sb = pair.section(r), blade.section(r)
    loop_p = to_file(pair, np.vstack([sp.face, sp.back]))
    loop_b = to_file(blade, np.vstack([sb.face, sb.back])) @ turn.T
    assert np.percentile(cKDTree(loop_p).query(loop_b)[0], 99) < 0.05
    ends_p = to_file(pair, sp.face[[0, -1]])
    ends_b = to_file(blade, sb.face[[0, -1]]) @ turn.T
    assert np.linalg.norm(ends_b - ends_p, axis=1).max() < 0.4


@pytest.mark.parametrize("r", [124.5, 124.8, 124.9, 124.92])
def test_blade_k_sections_next_to_the_tip_are_the_pairs(propeller_stl, bladex_parts, bladex_dir, r):
    """Next to the tip, where the BladeX sides turn outwards into the tip (normals within a few degrees of
    radial), the picked blade's sections exist and lie on the pair's: the pair's points more than 5 mm
    from its loop's ends lie on the picked blade's section (0.01 mm; both on the same facets, float32 STL),
    and its LE and TE within 1.2 mm of the pair loop's farthest pair (each side's end lies where the
    facet normals cross the chord, the pair's where upper.stl meets lower.stl; at this blunt tip the two
    sides' ends lie up to 2 mm apart and the joined end averages them). At 124.92 mm, within 1e-3 of
    the span of the tip, each blade cuts 1e-3 of its own span inside the tip (the two spans start at
    different hub radii: cuts 4 micrometres apart on a surface a few degrees off the cylinder): 0.1 mm."""
    pair = load_blade(f"{bladex_dir / 'lower.stl'},{bladex_dir / 'upper.stl'}", axis="x")
    blade = load_blade(f"{propeller_stl}?blade=3", axis="x")
    turn = copy_of(blade.propeller.blades[2].face.vertices, bladex_parts["upper"])

    def to_file(b, p):  # blade frame -> the file's frame
        return (p - b.transform[:3, 3]) @ b.transform[:3, :3]

    sp, sb = pair.section(r), blade.section(r)
    loop_p = to_file(pair, np.vstack([sp.face, sp.back]))
    loop_b = to_file(blade, np.vstack([sb.face, sb.back])) @ turn.T
    i, j = farthest_pair(loop_p)
    far = loop_p[[i, j]]
    inner = np.linalg.norm(loop_p[:, None] - far[None], axis=2).min(axis=1) > 5.0
    assert cKDTree(loop_b).query(loop_p[inner])[0].max() < (0.01 if r <= 124.9 else 0.1)
    ends = to_file(blade, sb.face[[0, -1]]) @ turn.T
    assert np.linalg.norm(ends[:, None] - far[None], axis=2).min(axis=1).max() < 1.2


def test_hub_cut_given(propeller_stl):
    blade = load_blade(f"{propeller_stl}?blade=2&r_min=45", axis="x")
    assert blade.hub_radius == pytest.approx(45.0, abs=1e-6)
    assert blade.propeller.r_min_given and len(blade.propeller.blades) == N_BLADES
    with pytest.raises(BladeInputError, match="beyond the mesh's tip radius"):
        load_blade(f"{propeller_stl}?r_min=130", axis="x")


def test_blade_info_lists_the_blades_and_names_the_axis_that_fits(propeller_stl, capsys):
    out = cli(capsys, "blade", "info", "--blade", propeller_stl, "--axis", "x", "--blade-index", "3", "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["propeller"]["blades"] == N_BLADES and info["propeller"]["picked"] == 3
    assert info["name"] == "propeller.stl blade 3 of 5"
    text = cli(capsys, "blade", "info", "--blade", propeller_stl, "--axis", "x")
    assert text.returncode == 0 and "axis" not in text.stderr
    rows = [line.split() for line in text.stdout.splitlines() if line.strip()[:1].isdigit()
            and len(line.split()) >= 5]
    assert [int(r[0]) for r in rows] == [1, 2, 3, 4, 5]
    assert [float(r[1]) for r in rows] == pytest.approx([b["angle_deg"] for b in info["propeller"]["found"]],
                                                        abs=1e-3)
    wrong = cli(capsys, "blade", "info", "--blade", propeller_stl, "--axis", "y")
    assert wrong.returncode == 2 and "whole propeller of 5 blades about axis x: try --axis x" in wrong.stderr
    bad = cli(capsys, "blade", "info", "--blade", propeller_stl, "--axis", "x", "--blade-index", "6")
    assert bad.returncode == 2 and "has 5 blades" in bad.stderr and "Traceback" not in bad.stderr


def test_plan_of_blade_k_verifies(propeller_stl, tmp_path, capsys):
    out = tmp_path / "plan"
    res = cli(capsys, "plan", "--blade", propeller_stl, "--axis", "x", "--blade-index", "3", "--dr", "6",
              "--workers", "2", "--out", out)
    assert res.returncode == 0, res.stderr
    summary = json.loads((out / "plan.json").read_text())
    assert summary["inputs"]["blade_source"] == f"{propeller_stl}?blade=3"
    ver = cli(capsys, "verify", out)
    assert ver.returncode == 0, ver.stdout


def test_reading_options_round_trip_and_refuse_bad_ones():
    assert split_options("a.stl?blade=2&r_min=38.5&units=cm") == ("a.stl", SourceOptions(2, 38.5, "cm"))
    assert with_options("a.stl?units=in", make_options(3, None, "mm")) == "a.stl?blade=3"
    assert with_options("sample", SourceOptions()) == "sample"
    for bad in ("a.stl?blade=0", "a.stl?blade=x", "a.stl?r_min=-1", "a.stl?units=ft", "a.stl?colour=red"):
        with pytest.raises(BladeInputError):
            split_options(bad)


def test_surface_samples_cover_thin_triangles_at_about_h():
    """A sliver 100 mm by 0.5 mm and a unit right triangle: every point of a fine sampling lies within
    1.2 h of a sample, and a sliver gets points by its area, not by its longest edge squared."""
    tri = np.array([[[0, 0, 0], [100, 0, 0], [50, 0.5, 0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    h = 0.5
    pts = _sample_points(tri, h)
    fine = _sample_points(tri, 0.01)
    assert cKDTree(pts).query(fine)[0].max() < 1.2 * h
    assert len(pts) < 4 * (100 / h + 2)  # (a square grid on the long edge would take (100 / h)^2 / 2)
