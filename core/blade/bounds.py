"""Physical plausibility of a propeller geometry table (core.blade.table): bounds on its metadata, on
every cell and on the splines between the rows.

Two levels per quantity: past ``WARN`` a real propeller could still be shaped so (an unusual blade:
the table is used, with a warning that says so); past ``ERROR`` the geometry is impossible or
meaningless as a blade (a thickness larger than the chord, a pitch of zero, a blade wrapped round its
axis, a diameter of a few atoms or of a continent) and the table is refused (BladeInputError) with
the file, line, column and what to do.

Ranges seen on real propellers (Carlton, Marine Propellers and Propulsion; ITTC and OpenProp tables):
c/D up to ~0.5 (wide-bladed), t0/c up to ~0.3 at the root, |f0/c| up to ~0.1, P/D 0.4 to 2.5, skew up
to ~70 deg (highly skewed), rake/D up to ~0.2, diameters from a model's ~30 mm to ~11 m.
"""

from __future__ import annotations

import numpy as np

from core.errors import BladeInputError

#: diameter_mm: (error below, warn below, warn above, error above)
DIAMETER_MM = (1.0, 20.0, 12_000.0, 100_000.0)
#: more blades than this: a warning (a fan or a turbine rather than a propeller?)
BLADES_WARN = 12
#: the blade's r/R span (from the hub or first row to the tip): an error below the first, a warning below the second
SPAN = (0.02, 0.2)
#: two rows closer than this in r/R: an error (near-duplicate radii make the splines swing)
MIN_ROW_STEP = 1e-4
#: a chord below this (mm) before the tip row is no section: only the tip row may have (nearly) zero chord
MIN_CHORD_MM = 1e-3
#: per column: (warn outside [lo, hi], error outside [lo, hi]); c/D's and t0/c's lower bounds are checked
#: by the table itself (>= 0); P/D must be positive
COLUMN_BOUNDS = {
    "c/D": ((0.0, 0.6), (0.0, 1.0)),
    "P/D": ((0.3, 3.0), (0.0, 10.0)),
    "t0/c": ((0.0, 0.35), (0.0, 1.0)),
    "f0/c": ((-0.05, 0.15), (-0.5, 0.5)),
    "skew_deg": ((-75.0, 75.0), (-120.0, 120.0)),
    "rake/D": ((-0.25, 0.25), (-1.0, 1.0)),
}
#: what each column's error means, for the message
_WHY = {
    "c/D": "a chord longer than the propeller's diameter",
    "P/D": "a pitch that is zero, negative (give a left-handed blade as its right-handed table) or nearly axial",
    "t0/c": "a section thicker than it is long",
    "f0/c": "a camber of more than half the chord",
    "skew_deg": "a blade wrapped a third of the way round its axis",
    "rake/D": "a blade raked by more than the diameter",
}


def _fail(path: str, line: int | None, msg: str) -> BladeInputError:
    return BladeInputError(f"{path}, line {line}: {msg}" if line else f"{path}: {msg}")


def check_metadata(path: str, blades: int, blades_line: int, diameter: float, diameter_line: int) -> list[str]:
    """Bounds on the number of blades and the diameter: warnings (list of str); BladeInputError."""
    warnings = []
    lo_err, lo_warn, hi_warn, hi_err = DIAMETER_MM
    if not lo_err <= diameter <= hi_err:
        raise _fail(path, diameter_line, f"'diameter_mm' = {diameter:g} mm is not a propeller's diameter "
                                         f"(accepted: {lo_err:g} to {hi_err:g} mm); give it in millimetres")
    if not lo_warn <= diameter <= hi_warn:
        warnings.append(f"{path}, line {diameter_line}: 'diameter_mm' = {diameter:g} mm is outside the usual "
                        f"{lo_warn:g} to {hi_warn:g} mm of propellers; check that it is in millimetres")
    if blades > BLADES_WARN:
        warnings.append(f"{path}, line {blades_line}: {blades} blades is more than a propeller's usual "
                        f"2 to {BLADES_WARN}")
    return warnings


def check_rows(path: str, columns: tuple[str, ...], rows: np.ndarray, lines: list[int], diameter: float,
               hub_ratio: float) -> list[str]:
    """Bounds on every cell of the rows (n, len(columns)) and on the radii: warnings; BladeInputError
    naming the line and column of the first impossible value."""
    col = {c: rows[:, j] for j, c in enumerate(columns)}
    r = col["r/R"]
    span = r[-1] - max(hub_ratio, r[0])
    if span < SPAN[0]:
        raise _fail(path, None, f"the blade spans r/R {max(hub_ratio, r[0]):g} to {r[-1]:g} ({span:.3g} of the "
                                f"radius; at least {SPAN[0]:g} is needed): check the r/R column and hub_ratio")
    step = np.diff(r)
    close = np.flatnonzero(step < MIN_ROW_STEP)
    if close.size:
        k = int(close[0]) + 1
        raise _fail(path, lines[k], f"column 'r/R': {r[k]:.10g} is only {step[k - 1]:.3g} from the row before "
                                    f"({r[k - 1]:.10g}); rows closer than {MIN_ROW_STEP:g} make the splines between "
                                    "them swing: remove one of the two rows")
    chord_mm = col["c/D"] * diameter
    tiny = np.flatnonzero((chord_mm[:-1] > 0) & (chord_mm[:-1] < MIN_CHORD_MM))
    if tiny.size:
        k = int(tiny[0])
        raise _fail(path, lines[k], f"column 'c/D' = {col['c/D'][k]:g} is a chord of {chord_mm[k]:.3g} mm: no section; "
                                    "only the tip (last) row may have zero chord")
    has_chord = col["c/D"] > 0
    warnings = []
    if span < SPAN[1]:
        warnings.append(f"{path}: the blade spans only {span:.3g} of the radius (r/R {max(hub_ratio, r[0]):g} "
                        f"to {r[-1]:g})")
    for name, ((wlo, whi), (elo, ehi)) in COLUMN_BOUNDS.items():
        v = col[name]
        rows_of = has_chord if name in ("t0/c", "f0/c") else np.ones(len(v), bool)  # (the tip row's are unused)
        low = (v <= elo) if name == "P/D" else (v < elo)
        bad = np.flatnonzero(rows_of & (low | (v > ehi)))
        if bad.size:
            k = int(bad[0])
            raise _fail(path, lines[k], f"column '{name}' = {v[k]:g} is impossible for a blade ({_WHY[name]}); "
                                        f"accepted: {_range(name, elo, ehi)}")
        odd = np.flatnonzero(rows_of & ((v < wlo) | (v > whi)))
        if odd.size:
            k = int(odd[0])
            warnings.append(f"{path}, line {lines[k]}: column '{name}' = {v[k]:g} is outside the usual {wlo:g} to "
                            f"{whi:g} of propellers{f' ({odd.size} rows)' if odd.size > 1 else ''}")
    return warnings


def _range(name: str, lo: float, hi: float) -> str:
    return f"above {lo:g} up to {hi:g}" if name == "P/D" else f"{lo:g} to {hi:g}"


def check_interpolated(path: str, columns: tuple[str, ...], r: np.ndarray, values: dict[str, np.ndarray]) -> None:
    """The splines between the rows stay within the error bounds: ``values`` maps a column to its spline
    evaluated at the r/R values ``r`` (a fine grid); BladeInputError naming the two rows around the
    first value out of bounds."""
    for name, (_, (elo, ehi)) in COLUMN_BOUNDS.items():
        if name not in values:
            continue
        v = values[name]
        low = (v <= elo) if name == "P/D" else (v < elo - 1e-9)  # (a closing chord's spline ends at -1e-18)
        bad = np.flatnonzero(~np.isfinite(v) | low | (v > ehi))
        if bad.size:
            k = int(bad[0])
            raise _fail(path, None, f"between the rows the spline of column '{name}' reaches {v[k]:.6g} at r/R = "
                                    f"{r[k]:.6g} ({_WHY[name]}): the rows there swing too steeply for a smooth "
                                    "interpolation; space the rows more evenly or smooth the column's values")
