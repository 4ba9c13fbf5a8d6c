"""Propeller geometry tables (the convention of propeller design tools such as OpenProp).

File format (CSV, UTF-8)::

    # name: paper test blade            (optional)
    # blades: 5
    # diameter_mm: 458.72
    # hub_ratio: 0.2
    # meanline: NACA a=0.8
    # thickness: NACA 66 mod
    r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D
    0.2,0.233018,0.85,0.1871,0.030,0.0,0.0
    ...
    1.0,0.0,0.92,0.15,0.014,20.0,0.0

Other lines starting with '#' are comments. One row per radius, r/R strictly increasing; a last row
with c/D = 0 closes the tip. Between rows every column is interpolated by splines: a monotone cubic
(PCHIP) for the chord, so that a closing tip never overshoots to a negative chord, and not-a-knot cubic
splines for the others.

Section construction at radius r (x = r/R): chord c, pitch angle phi = atan((P/D) / (pi x)), thickness
t0 = (t0/c) c and camber f0 = (f0/c) c applied to the named forms (core.blade.naca): camber line
y_c = f0 F(xi), half thickness y_t = t0 T(xi) / 2 laid off normal to the camber line. The section is
placed in the unrolled cylinder plane (r theta, z) with its mid-chord at theta = skew and
z = r skew tan(phi) - rake (so the nose-tail line lies on the pitch helix through the skewed mid-chord,
rake positive aft, towards -Z), LE at the larger r theta, then wrapped onto the cylinder.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.blade import naca
from core.blade.bounds import check_interpolated, check_metadata, check_rows
from core.blade.model import Blade, Section
from core.errors import BladeInputError
from core.util.files import require_file
from core.util.spline import pchip, spline

COLUMNS = ("r/R", "c/D", "P/D", "t0/c", "f0/c", "skew_deg", "rake/D")
REQUIRED_KEYS = ("blades", "diameter_mm", "hub_ratio", "meanline", "thickness")
#: chordwise station whose mean-line slope orients the thickness at the LE (NACA convention)
LE_SLOPE_STATION = 0.005
#: exponent of the smooth closure of a blunt TE (see TableBlade._thickness_closed)
TE_CLOSURE_POWER = 60
#: chordwise stations per section side (cosine spacing: dense at LE and TE)
DEFAULT_POINTS = 241
#: a line longer than this is no table row (and Python's csv module refuses cells over 131,072 characters)
MAX_LINE_CHARS = 10_000
#: r/R stations per unit of span where the splines between the rows are checked (core.blade.bounds)
CHECK_STATIONS = 2000


@dataclass(frozen=True)
class GeometryTable:
    """A parsed propeller geometry table.

    rows : (n, 7) float, the columns of COLUMNS, r/R strictly increasing.
    """

    path: str
    name: str
    blades: int
    diameter: float
    hub_ratio: float
    meanline: str
    thickness: str
    rows: np.ndarray = field(repr=False)
    warnings: tuple[str, ...] = ()  # unusual but possible values (core.blade.bounds)


def _fail(path: str, line: int | None, msg: str) -> BladeInputError:
    where = f"{path}, line {line}" if line else path
    return BladeInputError(f"{where}: {msg}")


def parse_table(text: str, path: str = "<table>") -> GeometryTable:
    """Parse the text of a geometry table; raises BladeInputError naming the line and column."""
    meta: dict[str, tuple[str, int]] = {}
    data_lines: list[tuple[int, str]] = []
    text = text.removeprefix("\ufeff")  # (the byte order mark of Excel's "CSV UTF-8")
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if len(line) > MAX_LINE_CHARS:
            raise _fail(path, lineno, f"a line of {len(line):,} characters (at most {MAX_LINE_CHARS:,}): not a "
                                      "geometry table row; check the file")
        if line.startswith("#"):
            body = line[1:].strip()
            if ":" in body:
                key, _, value = body.partition(":")
                key = key.strip().lower()
                if key in REQUIRED_KEYS or key == "name":
                    if key in meta:
                        raise _fail(path, lineno, f"'{key}' is given twice (lines {meta[key][1]} and {lineno}); "
                                                  "keep one")
                    meta[key] = (value.strip(), lineno)
            continue
        data_lines.append((lineno, line))

    for key in REQUIRED_KEYS:
        if key not in meta:
            raise _fail(path, None, f"missing metadata line '# {key}: ...' (required keys: "
                                    f"{', '.join(REQUIRED_KEYS)}; 'name' is optional)")

    def number(key: str) -> float:
        value, lineno = meta[key]
        try:
            x = float(value)
        except ValueError:
            raise _fail(path, lineno, f"'{key}' must be a number, got {value!r}") from None
        if not math.isfinite(x):
            raise _fail(path, lineno, f"'{key}' must be a finite number, got {value!r}")
        return x

    blades_value = number("blades")
    diameter = number("diameter_mm")
    hub_ratio = number("hub_ratio")
    if blades_value < 1 or blades_value != int(blades_value):
        raise _fail(path, meta["blades"][1], f"'blades' must be a whole number of at least 1, got "
                                             f"{meta['blades'][0]!r}")
    blades = int(blades_value)
    if diameter <= 0:
        raise _fail(path, meta["diameter_mm"][1], f"'diameter_mm' must be positive, got {diameter}")
    warnings = check_metadata(path, blades, meta["blades"][1], diameter, meta["diameter_mm"][1])
    if not 0 < hub_ratio < 1:
        raise _fail(path, meta["hub_ratio"][1], f"'hub_ratio' must lie between 0 and 1, got {hub_ratio}")
    try:
        meanline = meta["meanline"][0]
        naca.meanline(meanline, np.array([0.5]))
    except BladeInputError as exc:
        raise _fail(path, meta["meanline"][1], str(exc)) from None
    try:
        thickness = meta["thickness"][0]
        naca.thickness(thickness, np.array([0.5]))
    except BladeInputError as exc:
        raise _fail(path, meta["thickness"][1], str(exc)) from None

    if not data_lines:
        raise _fail(path, None, f"no header row: expected the columns {','.join(COLUMNS)}")
    header_line, header_text = data_lines[0]
    header = [h.strip() for h in _cells(path, header_line, header_text)]
    for col in COLUMNS:
        if col not in header:
            raise _fail(path, header_line, f"missing column '{col}' in the header {header}; the header "
                                           f"must have exactly the columns {','.join(COLUMNS)}")
    extra = [h for h in header if h not in COLUMNS]
    if extra or len(header) != len(COLUMNS):
        raise _fail(path, header_line, f"unknown or repeated column(s) {extra or header} in the header; "
                                       f"expected exactly {','.join(COLUMNS)}")
    index = [header.index(c) for c in COLUMNS]

    rows = []
    lines = []
    for lineno, text_row in data_lines[1:]:
        cells = [c.strip() for c in _cells(path, lineno, text_row)]
        if len(cells) != len(header):
            raise _fail(path, lineno, f"{len(cells)} cells, expected {len(header)} ({','.join(header)})")
        values = []
        for col, i in zip(COLUMNS, index, strict=True):
            try:
                v = float(cells[i])
            except ValueError:
                raise _fail(path, lineno, f"column '{col}': {cells[i]!r} is not a number") from None
            if not math.isfinite(v):
                raise _fail(path, lineno, f"column '{col}': {cells[i]!r} is not a finite number")
            values.append(v)
        rows.append(values)
        lines.append(lineno)
    if len(rows) < 3:
        raise _fail(path, None, f"{len(rows)} data rows; at least 3 radii are needed to fit splines")
    arr = np.array(rows)
    for j, col in enumerate(COLUMNS):
        if col in ("c/D", "t0/c"):
            neg = np.nonzero(arr[:, j] < 0)[0]
            if neg.size:
                raise _fail(path, lines[neg[0]], f"column '{col}' is negative ({arr[neg[0], j]}); "
                                                 "chord and thickness must be >= 0")
    r = arr[:, 0]
    if r[0] <= 0 or r[-1] > 1.0 + 1e-9:
        bad = 0 if r[0] <= 0 else len(r) - 1
        raise _fail(path, lines[bad], f"column 'r/R' = {r[bad]} is outside (0, 1]")
    dec = np.nonzero(np.diff(r) <= 0)[0]
    if dec.size:
        k = dec[0] + 1
        raise _fail(path, lines[k], f"column 'r/R' must increase strictly: {r[k]} follows {r[k - 1]}")
    zero = np.nonzero(arr[:-1, 1] == 0)[0]
    if zero.size:
        raise _fail(path, lines[zero[0]], "column 'c/D' is 0 before the last row; only the tip row may "
                                          "have zero chord")
    if (arr[:, 3][arr[:, 1] > 0] == 0).any():
        k = int(np.nonzero((arr[:, 3] == 0) & (arr[:, 1] > 0))[0][0])
        raise _fail(path, lines[k], "column 't0/c' is 0 where the chord is not: a section needs thickness")
    if hub_ratio >= r[-1]:
        raise _fail(path, meta["hub_ratio"][1], f"'hub_ratio' = {hub_ratio:g} is not inside the blade: the last "
                                                f"row (the tip) is at r/R = {r[-1]:g}")
    warnings += check_rows(path, COLUMNS, arr, lines, diameter, hub_ratio)
    if hub_ratio < r[0] - 1e-9:
        hub_ratio = float(r[0])
    name = meta.get("name", (Path(path).stem, 0))[0] or Path(path).stem
    return GeometryTable(path=path, name=name, blades=blades, diameter=diameter, hub_ratio=hub_ratio,
                         meanline=meanline, thickness=thickness, rows=arr, warnings=tuple(warnings))


def _cells(path: str, lineno: int, text_row: str) -> list[str]:
    """The comma-separated cells of one line (BladeInputError for a line the csv module refuses)."""
    try:
        return next(csv.reader(io.StringIO(text_row)))
    except csv.Error as exc:
        raise _fail(path, lineno, f"not a row of comma-separated cells ({exc})") from None


def read_table(path: str | Path) -> GeometryTable:
    """Read and parse a geometry table file; raises BladeInputError for every problem."""
    p = Path(path)
    require_file(p, "geometry table not found (give a path to a .csv geometry table)",
                 "give a path to a .csv geometry table")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise BladeInputError(f"{p}: cannot read the geometry table ({exc})") from None
    return parse_table(text, str(p))


class TableBlade(Blade):
    """A blade generated from a geometry table; sections are exact cylindrical sections."""

    def __init__(self, table: GeometryTable, n_points: int = DEFAULT_POINTS):
        self.table = table
        self.name = table.name
        self.source = table.path
        self.n_points = int(n_points)
        self._R = table.diameter / 2.0
        x = table.rows[:, 0]
        D = table.diameter
        self._chord = pchip(x, table.rows[:, 1] * D)
        self._spl = {
            name: spline(x, table.rows[:, j])
            for j, name in ((2, "P/D"), (4, "f0/c"), (5, "skew_deg"), (6, "rake/D"))
        }
        self._spl["t0/c"] = pchip(x, table.rows[:, 3])
        self._x_min, self._x_max = float(x[0]), float(x[-1])
        self.warnings = list(table.warnings)
        grid = np.linspace(max(table.hub_ratio, self._x_min), self._x_max,
                           int(CHECK_STATIONS * (self._x_max - self._x_min)) + 2)
        check_interpolated(table.path, COLUMNS, grid, {
            "c/D": self._chord(grid) / D, "t0/c": self._spl["t0/c"](grid),
            **{k: f(grid) for k, f in self._spl.items()}})
        u = np.linspace(0.0, 1.0, self.n_points)
        self._xi = 0.5 * (1.0 - np.cos(np.pi * u))

    @property
    def stations(self) -> np.ndarray:
        """(n_points,) float: the chordwise fractions (0 at the LE, 1 at the TE, cosine-spaced) of a
        section by default (``section(r)``); a copy."""
        return self._xi.copy()

    @property
    def hub_radius(self) -> float:
        return max(self.table.hub_ratio, self._x_min) * self._R

    @property
    def tip_radius(self) -> float:
        return self._x_max * self._R

    def parameters(self, r: float) -> dict[str, float]:
        """Interpolated section parameters at radius r (mm): chord_mm, pitch_angle_deg, t0_mm, f0_mm,
        skew_deg, rake_mm."""
        x = r / self._R
        chord = max(float(self._chord(x)), 0.0)
        pd = float(self._spl["P/D"](x))
        return {
            "chord_mm": chord,
            "pitch_angle_deg": math.degrees(math.atan2(pd, math.pi * x)),
            "t0_mm": float(self._spl["t0/c"](x)) * chord,
            "f0_mm": float(self._spl["f0/c"](x)) * chord,
            "skew_deg": float(self._spl["skew_deg"](x)),
            "rake_mm": float(self._spl["rake/D"](x)) * self.table.diameter,
        }

    def _thickness_closed(self, xi: np.ndarray) -> np.ndarray:
        """t/t0 of the table's form with a blunt TE closed smoothly: T(x) - T(1) x^TE_CLOSURE_POWER.

        (NACA 66 mod has t/t0 = 0.0666 at the TE; closing it lets face and back meet at one TE point
        that both cutters share. The change is below 0.3 % of t0 for x <= 0.9.)"""
        t = naca.thickness(self.table.thickness, xi)
        t_te = float(naca.thickness(self.table.thickness, np.array([1.0]))[0])
        return t - t_te * xi**TE_CLOSURE_POWER

    def surface_points(self, r: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Face and back points at radii r (n,) and chordwise fractions xi (n,) (0 at the LE, 1 at the
        TE), elementwise: two (n, 3) float arrays, mm, blade frame. Vectorised over any mix of radii."""
        return self._points(np.asarray(r, float), np.asarray(xi, float))

    def _points(self, r: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Face and back points at radii r (n,) and chordwise fractions xi (n,), elementwise.

        Returns two (n, 3) float arrays, mm, blade frame."""
        r = np.asarray(r, float)
        x = r / self._R
        c = np.maximum(self._chord(x), 0.0)
        phi = np.arctan2(self._spl["P/D"](x), np.pi * x)
        t0 = self._spl["t0/c"](x) * c
        f0 = self._spl["f0/c"](x) * c
        skew = np.radians(self._spl["skew_deg"](x))
        rake = self._spl["rake/D"](x) * self.table.diameter
        yc_n = naca.meanline(self.table.meanline, xi)[0]
        # thickness is laid off normal to the camber line; near the LE the slope of the mean line
        # is taken at x/c = 0.005 (the NACA convention for the LE radius: a-series slopes are
        # singular at the LE), so the nose is a smooth rounded curve
        dyc_n = naca.meanline(self.table.meanline, np.maximum(xi, LE_SLOPE_STATION))[1]
        yt = 0.5 * t0 * self._thickness_closed(xi)
        yc = f0 * yc_n
        beta = np.arctan(np.divide(f0, c, out=np.zeros_like(c), where=c > 0) * dyc_n)
        sb, cb = np.sin(beta), np.cos(beta)
        s_chord = xi * c
        cphi, sphi = np.cos(phi), np.sin(phi)
        # LE in the unrolled plane: mid-chord (r skew, r skew tan(phi) - rake) + c/2 e_c,
        # e_c = (cos phi, sin phi) points TE -> LE, e_b = (sin phi, -cos phi) towards the back
        le_a = r * skew + 0.5 * c * cphi
        le_z = r * skew * np.tan(phi) - rake + 0.5 * c * sphi

        def wrap(s_: np.ndarray, v: np.ndarray) -> np.ndarray:
            a = le_a - s_ * cphi + v * sphi
            z = le_z - s_ * sphi - v * cphi
            th = a / r
            return np.column_stack([r * np.cos(th), r * np.sin(th), z])

        return wrap(s_chord + yt * sb, yc - yt * cb), wrap(s_chord - yt * sb, yc + yt * cb)

    def section(self, r: float, xi: np.ndarray | None = None) -> Section:
        """Cylindrical section at radius r (mm) on the chordwise stations xi (default: cosine spacing,
        n_points per side). Normals: cross product of the chordwise and radial surface tangents."""
        self._check_radius(r)
        if r >= self.tip_radius * (1 - 1e-9) and float(self._chord(r / self._R)) <= 0:
            raise BladeInputError(f"blade {self.name!r} has no section at its closed tip r = {r} mm")
        xi = self._xi if xi is None else np.asarray(xi, float)
        h = 1e-6
        xp, xm = np.minimum(xi + h, 1.0), np.maximum(xi - h, 0.0)
        dr = 1e-4 * self._R
        rp, rm = min(r + dr, self.tip_radius * (1 - 1e-7)), max(r - dr, self.hub_radius)
        n = len(xi)
        # one vectorised evaluation: the section, its chordwise and its radial neighbours
        rr = np.concatenate([np.full(3 * n, float(r)), np.full(n, rp), np.full(n, rm)])
        ff, bb = self._points(rr, np.concatenate([xi, xp, xm, xi, xi]))
        face, fp, fm, fr1, fr0 = np.split(ff, 5)
        back, bp, bm, br1, br0 = np.split(bb, 5)
        dxi = (xp - xm)[:, None]
        normals = []
        for side, (tp, tm, r1, r0) in (("face", (fp, fm, fr1, fr0)), ("back", (bp, bm, br1, br0))):
            t_chord = (tp - tm) / dxi
            t_rad = (r1 - r0) / (rp - rm)
            n = np.cross(t_chord, t_rad)
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            # outward: walking LE -> TE the back lies on the left of the chordwise tangent in the
            # unrolled plane, the face on the right; the radial direction completes the frame.
            radial = np.column_stack([np.cos(np.arctan2(face[:, 1], face[:, 0])),
                                      np.sin(np.arctan2(face[:, 1], face[:, 0])), np.zeros(len(xi))])
            left = np.cross(radial, t_chord)  # in the cylinder, left of the walking direction
            sign = np.sign(np.einsum("ij,ij->i", n, left))
            sign[sign == 0] = 1.0
            n *= (sign if side == "back" else -sign)[:, None]
            normals.append(n)
        return Section(r=float(r), face=face, back=back, face_normals=normals[0], back_normals=normals[1])


def load_table_blade(path: str | Path, n_points: int = DEFAULT_POINTS) -> TableBlade:
    """Read a geometry table file and build its blade."""
    return TableBlade(read_table(path), n_points=n_points)
