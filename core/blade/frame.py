"""The workpiece frame W: the blade as clamped on the machine (SPEC.md section 1).

Z_W runs across the blade thickness (the left cutter works from -Z_W, the right from +Z_W), X_W along
the span (radius) and Y_W along the chord, so that one machining path has (nearly) monotonic Y_W. W is
the blade frame B turned about its generator line X_B by minus the reference pitch angle (the pitch
angle of the section at 0.7 R, measured on the blade): p_W = rotation @ p_B + translation. With the
project's blade conventions (core.blade.model) the back then faces -Z_W (left cutter) and the face +Z_W
(right cutter). The clamp (root support surface) is the plane X_W = x_clamp = hub radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.blade.model import Blade, section_pitch_angle

REFERENCE_FRACTION = 0.7


@dataclass(frozen=True)
class WorkpieceFrame:
    """Rigid transform blade frame -> workpiece frame.

    rotation : (3, 3) float, proper rotation; translation : (3,) float, mm; x_clamp : float, mm.
    """

    rotation: np.ndarray
    translation: np.ndarray
    x_clamp: float
    reference_pitch_deg: float

    def points(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) float, mm, blade frame -> (n, 3) float, mm, workpiece frame."""
        return p @ self.rotation.T + self.translation

    def vectors(self, v: np.ndarray) -> np.ndarray:
        """(n, 3) float directions, blade frame -> workpiece frame."""
        return v @ self.rotation.T

    def as_dict(self) -> dict:
        return {
            "rotation": self.rotation.round(12).tolist(),
            "translation_mm": self.translation.round(9).tolist(),
            "x_clamp_mm": round(self.x_clamp, 6),
            "reference_pitch_deg": round(self.reference_pitch_deg, 6),
        }


def workpiece_frame(blade: Blade) -> WorkpieceFrame:
    """The workpiece frame of a blade: rotation about X_B by minus the pitch angle at 0.7 R."""
    r_ref = max(REFERENCE_FRACTION * blade.tip_radius, blade.hub_radius)
    phi = section_pitch_angle(blade.section(r_ref))
    a = -math.radians(phi)
    rot = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)], [0.0, math.sin(a), math.cos(a)]])
    return WorkpieceFrame(rotation=rot, translation=np.zeros(3), x_clamp=float(blade.hub_radius),
                          reference_pitch_deg=phi)
