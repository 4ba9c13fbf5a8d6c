"""The one internal representation of a blade, whatever its source.

Blade frame (SPEC.md section 1): propeller axis = +Z, the blade's generator line along +X, radius
r = sqrt(x^2 + y^2), angle theta = atan2(y, x). A blade is two sided surfaces, the face (pressure
side) and the back (suction side), meeting at the leading edge (LE) and the trailing edge (TE). By the
project's convention the LE is the end of a section with the larger unrolled arc coordinate r*theta
(the blade turns towards +theta), and the face is the side to the right of the chord line walked
from LE to TE in the unrolled (r*theta, z) plane (the side of larger z for a positive pitch).

Every source implements ``Blade.section(r)``: the cylindrical section at radius r split into its face
and back parts, both ordered LE -> TE, with outward unit normals. Measurements (chord, thickness,
pitch angle) are computed from those sections alone, the same way for every source.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from core.errors import BladeInputError

#: fractions of the tip radius reported by ``bladecam blade info``
INFO_FRACTIONS = (0.2, 0.5, 0.95)


@dataclass(frozen=True)
class Section:
    """The cylindrical section of a blade at one radius, split at LE and TE.

    r : float, mm, radius of the cylinder
    face, back : (n, 3) and (m, 3) float, mm, blade frame; each ordered LE -> TE, the first points of
        both are the LE and the last points the TE (shared end points)
    face_normals, back_normals : same shapes, unit outward surface normals
    """

    r: float
    face: np.ndarray
    back: np.ndarray
    face_normals: np.ndarray
    back_normals: np.ndarray

    @property
    def leading_edge(self) -> np.ndarray:
        """(3,) float, mm."""
        return self.face[0]

    @property
    def trailing_edge(self) -> np.ndarray:
        """(3,) float, mm."""
        return self.face[-1]


def unroll(points: np.ndarray, r: float) -> np.ndarray:
    """Unrolled cylindrical coordinates of points on the cylinder of radius r.

    points : (n, 3) float, mm, blade frame -> (n, 2) float, mm: (r * theta, z)
    """
    theta = np.arctan2(points[:, 1], points[:, 0])
    return np.column_stack([r * theta, points[:, 2]])


def chord_frame(section: Section) -> tuple[np.ndarray, np.ndarray, float]:
    """Face and back in the chord frame of the unrolled section.

    Returns (face_uv, back_uv, chord): (n, 2) and (m, 2) float, mm, u along the chord from the LE
    (0 at LE, chord at TE), v normal to it (positive to the left, towards the back); chord in mm.
    """
    f2, b2 = unroll(section.face, section.r), unroll(section.back, section.r)
    le, te = f2[0], f2[-1]
    chord_vec = te - le
    chord = float(np.hypot(*chord_vec))
    if chord <= 0:
        return np.zeros_like(f2), np.zeros_like(b2), 0.0
    eu = chord_vec / chord
    ev = np.array([-eu[1], eu[0]])
    to_uv = lambda p: np.column_stack([(p - le) @ eu, (p - le) @ ev])  # noqa: E731
    return to_uv(f2), to_uv(b2), chord


def section_chord(section: Section) -> float:
    """Chord, mm: straight LE-TE distance in the unrolled section (ISO 484 convention)."""
    return chord_frame(section)[2]


def section_max_thickness(section: Section, samples: int = 2001) -> float:
    """Maximum thickness, mm, measured normal to the chord line of the unrolled section.

    Face and back are resampled on a common chordwise grid; thickness = max |v_back - v_face|.
    """
    fuv, buv, chord = chord_frame(section)
    if chord <= 0:
        return 0.0
    u = np.linspace(0.0, chord, samples)

    def v_of_u(uv: np.ndarray) -> np.ndarray:
        order = np.argsort(uv[:, 0], kind="stable")
        return np.interp(u, uv[order, 0], uv[order, 1])

    return float(np.max(np.abs(v_of_u(buv) - v_of_u(fuv))))


def section_pitch_angle(section: Section) -> float:
    """Geometric pitch angle, degrees: angle of the chord line (TE -> LE) from the circumferential
    direction in the unrolled section, positive when the LE lies at larger z."""
    f2 = unroll(section.face, section.r)
    d = f2[0] - f2[-1]
    return float(np.degrees(np.arctan2(d[1], d[0])))


class Blade(ABC):
    """A propeller blade: face and back surfaces with LE, TE and outward normals (blade frame, mm)."""

    name: str
    source: str
    #: what is unusual but possible in the source (an odd table value, a mesh's sides swapped), for the operator
    warnings: tuple[str, ...] | list[str] = ()

    @property
    @abstractmethod
    def hub_radius(self) -> float:
        """Innermost radius of the blade surface, mm."""

    @property
    @abstractmethod
    def tip_radius(self) -> float:
        """Outermost radius of the blade, mm."""

    @abstractmethod
    def section(self, r: float) -> Section:
        """The cylindrical section at radius r (mm), hub_radius <= r < tip_radius.

        Raises BladeInputError when r is outside the blade or the blade has no section there.
        """

    def _check_radius(self, r: float) -> None:
        if not np.isfinite(r) or r < self.hub_radius - 1e-9 or r > self.tip_radius + 1e-9:
            raise BladeInputError(
                f"radius {r} mm is outside the blade {self.name!r} "
                f"({self.hub_radius:.3f} to {self.tip_radius:.3f} mm)"
            )

    def surface_grids(self, n_radii: int = 60) -> tuple[np.ndarray, np.ndarray]:
        """Face and back sampled on sections for display or export.

        Returns two (n_radii, n, 3) float arrays, mm, blade frame: rows from hub to near the tip, each
        row a section resampled to n points by normalised arc length, LE -> TE.
        """
        span = self.tip_radius - self.hub_radius
        radii = self.hub_radius + span * (1.0 - np.cos(np.linspace(0.0, np.pi / 2, n_radii))) * 0.999
        n = 81
        face, back = [], []
        for r in radii:
            s = self.section(float(r))
            face.append(resample_polyline(s.face, n))
            back.append(resample_polyline(s.back, n))
        return np.array(face), np.array(back)

    def info(self) -> dict:
        """The figures of ``bladecam blade info``: tip and hub radius, chord and maximum thickness at
        0.2, 0.5 and 0.95 of the tip radius, all in mm and measured on the sections."""
        chord: dict[str, float | None] = {}
        thick: dict[str, float | None] = {}
        for frac in INFO_FRACTIONS:
            r = frac * self.tip_radius
            key = f"{frac:g}"
            if r < self.hub_radius:
                chord[key] = None
                thick[key] = None
                continue
            s = self.section(r)
            chord[key] = round(section_chord(s), 4)
            thick[key] = round(section_max_thickness(s), 4)
        sizes = [self.tip_radius, self.hub_radius, *(v for v in (*chord.values(), *thick.values()) if v is not None)]
        if not np.isfinite(sizes).all():
            raise BladeInputError(f"blade {self.name!r} ({self.source}): its sections measure no finite size "
                                  f"(tip radius {self.tip_radius:g} mm, chords {list(chord.values())}); check the "
                                  "source's numbers and units")
        return {
            "name": self.name,
            "source": self.source,
            "tip_radius_mm": round(self.tip_radius, 4),
            "hub_radius_mm": round(self.hub_radius, 4),
            "chord_mm": chord,
            "max_thickness_mm": thick,
        }


def resample_polyline(points: np.ndarray, n: int) -> np.ndarray:
    """Resample a polyline at n points equally spaced in arc length.

    points : (m, 3) float, mm -> (n, 3) float, mm (first and last points kept)
    """
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return np.repeat(points[:1], n, axis=0)
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, points[:, i]) for i in range(points.shape[1])])
