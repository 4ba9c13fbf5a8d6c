"""Geometry tables: the sample blade's golden sizes, round trips, and every bad input."""

import math

import numpy as np
import pytest

from core.blade.model import section_chord, section_max_thickness, section_pitch_angle, unroll
from core.blade.source import load_blade, sample_table_path
from core.blade.table import parse_table, read_table
from core.errors import BladeInputError

PAPER = {0.2: 106.89, 0.5: 142.18, 0.95: 17.17}  # Wang, Ge, Guo 2023, Table 5 (ideal sizes)


@pytest.fixture(scope="module")
def sample():
    return load_blade("sample")


def test_sample_golden_sizes(sample):
    assert sample.tip_radius == pytest.approx(229.36, abs=1e-9)
    assert sample.hub_radius == pytest.approx(0.2 * 229.36)
    for frac, chord in PAPER.items():
        measured = section_chord(sample.section(frac * 229.36))
        assert measured == pytest.approx(chord, rel=0.005), frac
    info = sample.info()
    assert info["tip_radius_mm"] == pytest.approx(229.36)
    assert set(info["chord_mm"]) == {"0.2", "0.5", "0.95"}
    # realistic propeller thickness: thick root, thin tip
    t = info["max_thickness_mm"]
    assert t["0.2"] > t["0.5"] > t["0.95"] > 0
    assert 15 < t["0.2"] < 25 and 1 < t["0.95"] < 4


@pytest.mark.parametrize("x", [0.2, 0.27, 0.5, 0.63, 0.81, 0.93, 0.97])
def test_round_trip_chord_thickness_pitch(sample, x):
    """table -> surfaces -> section measured geometrically gives back the table's values."""
    r = x * sample.tip_radius
    p = sample.parameters(r)
    s = sample.section(r)
    assert section_chord(s) == pytest.approx(p["chord_mm"], rel=1e-6)
    # thickness is laid off normal to the camber line, measured normal to the chord: camber slopes
    # of a few per cent change it by well under 1 %
    assert section_max_thickness(s) == pytest.approx(p["t0_mm"], rel=0.01)
    assert section_pitch_angle(s) == pytest.approx(p["pitch_angle_deg"], abs=1e-6)


def test_pitch_angle_from_table_formula(sample):
    table = read_table(sample_table_path())
    for row in table.rows[:-1]:
        x, pd = row[0], row[2]
        want = math.degrees(math.atan(pd / (math.pi * x)))
        got = section_pitch_angle(sample.section(x * sample.tip_radius))
        assert got == pytest.approx(want, abs=1e-9)


def test_interpolation_is_smooth_not_linear(sample):
    # between rows the chord follows a spline: the midpoint differs from the linear average
    r = np.array([0.3, 0.35, 0.4]) * sample.tip_radius
    c = [sample.parameters(x)["chord_mm"] for x in r]
    assert abs(c[1] - 0.5 * (c[0] + c[2])) > 1e-3
    # and is continuous with a continuous slope across a row
    eps = 1e-4
    r0 = 0.5 * sample.tip_radius
    left = (sample.parameters(r0)["chord_mm"] - sample.parameters(r0 - eps)["chord_mm"]) / eps
    right = (sample.parameters(r0 + eps)["chord_mm"] - sample.parameters(r0)["chord_mm"]) / eps
    assert left == pytest.approx(right, abs=0.05)


def test_section_structure_and_normals(sample):
    r = 0.6 * sample.tip_radius
    s = sample.section(r)
    for pts in (s.face, s.back):
        assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), r, atol=1e-9)
    assert np.allclose(s.face[0], s.back[0]) and np.allclose(s.face[-1], s.back[-1])
    # LE at larger r*theta (project convention)
    a = unroll(s.face, r)[:, 0]
    assert a[0] > a[-1]
    for pts, nrm, other in ((s.face, s.face_normals, s.back), (s.back, s.back_normals, s.face)):
        assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)
        # normal to the section curve and to the radial direction of the surface (independent:
        # finite differences of the sections themselves)
        tangent = np.gradient(pts, axis=0)
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        assert np.abs(np.einsum("ij,ij->i", tangent[5:-5], nrm[5:-5])).max() < 2e-2
        # outward: away from the other side at mid chord
        mid = len(pts) // 2
        j = np.argmin(np.linalg.norm(other - pts[mid], axis=1))
        assert np.dot(nrm[mid], pts[mid] - other[j]) > 0


def test_normals_perpendicular_to_radial_direction(sample):
    r, dr = 0.45 * sample.tip_radius, 1e-3
    s0, s1, s2 = sample.section(r - dr), sample.section(r), sample.section(r + dr)
    radial = (s2.face - s0.face) / (2 * dr)
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.abs(np.einsum("ij,ij->i", radial, s1.face_normals)).max() < 1e-4


def test_radius_outside_blade_raises(sample):
    with pytest.raises(BladeInputError, match="outside the blade"):
        sample.section(300.0)
    with pytest.raises(BladeInputError, match="closed tip"):
        sample.section(sample.tip_radius)


GOOD = """# name: test
# blades: 4
# diameter_mm: 300
# hub_ratio: 0.2
# meanline: NACA a=0.8
# thickness: NACA 66 mod
r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D
0.2,0.20,0.9,0.15,0.03,0,0
0.5,0.30,1.0,0.08,0.03,2,0
0.8,0.25,1.0,0.05,0.02,8,0
1.0,0.00,0.9,0.05,0.01,15,0
"""


def test_good_table_parses():
    t = parse_table(GOOD, "good.csv")
    assert t.blades == 4 and t.diameter == 300 and t.rows.shape == (4, 7)


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda s: s.replace("t0/c", "t0c"), r"line 7: missing column 't0/c'"),
        (lambda s: s.replace(",rake/D", ""), r"line 7: missing column 'rake/D'"),
        (lambda s: s.replace("0.5,0.30", "0.5,abc"), r"line 9: column 'c/D': 'abc' is not a number"),
        (lambda s: s.replace("0.5,0.30", "0.5,nan"), r"line 9: column 'c/D': 'nan' is not a finite"),
        (lambda s: s.replace("0.8,0.25", "0.4,0.25"), r"line 10: column 'r/R' must increase"),
        (lambda s: s.replace("0.5,0.30", "0.5,-0.30"), r"line 9: column 'c/D' is negative"),
        (lambda s: s.replace("1.0,0.08", "1.0,-0.08"), r"line 9: column 't0/c' is negative"),
        (lambda s: s.replace("NACA 66 mod", "NACA 99 foo"), r"line 6: .*NACA 99 foo"),
        (lambda s: s.replace("NACA a=0.8", "banana"), r"line 5: .*banana"),
        (lambda s: s.replace("# diameter_mm: 300\n", ""), r"missing metadata line '# diameter_mm"),
        (lambda s: s.replace("diameter_mm: 300", "diameter_mm: -3"), r"line 3: 'diameter_mm' must be"),
        (lambda s: s.replace("0.2,0.20,0.9,0.15,0.03,0,0", "0.2,0.20,0.9,0.15,0.03,0"), r"line 8: 6 cells"),
    ],
)
def test_bad_tables_name_file_line_column(tmp_path, change, match):
    path = tmp_path / "bad.csv"
    path.write_text(change(GOOD))
    with pytest.raises(BladeInputError, match=match) as exc:
        load_blade(str(path))
    assert "bad.csv" in str(exc.value)


def test_missing_table_file(tmp_path):
    with pytest.raises(BladeInputError, match="not found"):
        load_blade(str(tmp_path / "nope.csv"))


def test_unknown_source_kind(tmp_path):
    with pytest.raises(BladeInputError, match="unknown blade source"):
        load_blade(str(tmp_path / "blade.docx"))
