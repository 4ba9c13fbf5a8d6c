"""Region division (paper section 4, Table 1; SPEC.md section 6).

Per aligned symmetrical pair, from the signed tip spacing of the symmetrical configuration:
- edge: the stretches at both ends where the spacing <= h_safe;
- variable: the stretch next to each edge stretch, with as many points (so, at step dd, as long);
- internal: the rest (spacing > h_safe);
- staggered ratio = (edge + variable length at both ends) / pair length, measured along the template
  side; a pair whose ratio >= k_max is wholly in the tip region (single-sided alternating machining).
A pair whose spacing drops to <= h_safe anywhere between its end stretches (a thin middle) cannot be
machined symmetrically either, and goes to the tip region too (reason 'thin middle').

The six boundary points of paper section 5 (Figure 6), as indices into the aligned pair in machining
order: S_vl = first variable point at the start, E_vl = E_ss = first internal point at the start,
S_vs = S_sl = first variable point at the end, E_vs = first edge point at the end.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.errors import PlanningError
from core.util.polyline import cumulative_length

#: the regions of a path (section 4), in the order the plan reports them
REGIONS = ("tip", "edge", "variable", "internal")
#: the one region table: every region a sample or pair point can be in (SPEC.md section 10: a path's
#: four, the turns between paths, the idle moves), its integer code its index here; the schedule's
#: samples, verify's reading and the workbench's render data all use these codes
REGION_NAMES = ("tip", "internal", "variable", "edge", "turn", "idle")
REGION_CODE = {name: k for k, name in enumerate(REGION_NAMES)}
REGION_NAMES_ARRAY = np.array(REGION_NAMES)
_SORTED_NAMES = np.sort(REGION_NAMES_ARRAY)
_SORTED_TO_CODE = np.array([REGION_NAMES.index(n) for n in _SORTED_NAMES])


def region_codes(regions) -> np.ndarray:
    """Region names (a str or an array of str) -> their codes (indices into REGION_NAMES, int array)."""
    names = np.asarray(regions)
    codes = np.searchsorted(_SORTED_NAMES, names)
    if np.any(_SORTED_NAMES[np.clip(codes, 0, len(_SORTED_NAMES) - 1)] != names):
        raise PlanningError(f"unknown region name among {np.unique(names)}")
    return _SORTED_TO_CODE[codes]


@dataclass(frozen=True)
class Regions:
    """Region labels of one aligned pair.

    labels : (N,) str array; staggered_ratio : float; is_tip : bool; reason : str ('' or why tip)
    boundaries : dict name -> index (empty for tip paths)
    """

    labels: np.ndarray
    staggered_ratio: float
    is_tip: bool
    reason: str = ""
    boundaries: dict = field(default_factory=dict)


def divide(spacing: np.ndarray, template_tips: np.ndarray, h_safe: float, k_max: float) -> Regions:
    """Regions of one pair from its signed tip spacing (N,) mm and its template tips (N, 3) mm."""
    n = len(spacing)
    s = cumulative_length(template_tips)
    length = s[-1]
    high = spacing > h_safe
    labels = np.full(n, "tip", dtype=object)
    if not high.any() or length <= 0:
        return Regions(labels=labels.astype(str), staggered_ratio=1.0, is_tip=True,
                       reason="spacing <= h_safe everywhere")
    a = int(np.argmax(high))                  # first point above h_safe
    b = n - int(np.argmax(high[::-1]))        # one past the last point above h_safe
    edge_len = (s[a] - s[0]) + (s[-1] - s[b - 1] if b < n else 0.0)
    ratio = float(2.0 * edge_len / length)
    if not high[a:b].all():
        return Regions(labels=labels.astype(str), staggered_ratio=ratio, is_tip=True,
                       reason="thin middle: spacing <= h_safe inside the path")
    na, nb = a, n - b
    if ratio >= k_max or a + na >= b - nb:
        return Regions(labels=labels.astype(str), staggered_ratio=ratio, is_tip=True,
                       reason="staggered ratio >= k_max")
    labels[:] = "internal"
    labels[:a] = "edge"
    labels[a:a + na] = "variable"
    labels[b - nb:b] = "variable"
    labels[b:] = "edge"
    bounds = {"S_vl": a, "E_vl": a + na, "E_ss": a + na, "S_vs": b - nb, "S_sl": b - nb, "E_vs": b}
    return Regions(labels=labels.astype(str), staggered_ratio=ratio, is_tip=False, boundaries=bounds)
