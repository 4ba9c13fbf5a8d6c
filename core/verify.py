"""``bladecam verify DIR``: an independent re-check of a written plan.

It reads only the plan folder (plan.json for the parameters and the blade source, left_cl.csv and
right_cl.csv) and shares no code with the scheduling (core.schedule.steps, core.schedule.motion, core.schedule.safety): the
distances below are implemented again here, by other means. Checks:
- one common, strictly increasing time column; steps within 1..7;
- tip spacing >= h_safe at every sample and between samples (both tips move linearly between two
  samples: the minimum of a quadratic in the interval parameter);
- the two tool capsules (ball swept along the axis for the stick-out) never touch (alternating
  projections between the two axis segments);
- every cutting sample's ball centre is on the blade's offset surface: its distance to the blade,
  tessellated afresh, is r within [-2e-3, +0.05] mm (no gouge, no air cut beyond the tessellation's
  own error at rounded edges);
- speed <= feed on consecutive cutting samples of one path, acceleration along the path <= a_max
  (5 % sampling slack, as the shared checks use).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.blade.frame import workpiece_frame
from core.blade.source import load_blade
from core.errors import MachineError, OutputError
from core.machine.kinematics import forward_kinematics
from core.machine.model import AXES, load_machine
from core.output.csvio import Helper
from core.paths.gouge import FACET_CANDIDATES, TriangleIndex, distance_to_surface, surface_mesh

#: how far a cutting ball centre may sit outside the offset surface (mm): the check's own tessellation
#: (0.25 mm chordwise) lies inside a rounded edge by up to a few hundredths of a millimetre there
MISS_TOLERANCE = 0.05
REGION_CODES = {b"tip": 0, b"edge": 1, b"variable": 2, b"internal": 3, b"turn": 4, b"idle": 5}
CL_HEADER = "t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k"


_POW10 = 10.0 ** np.arange(-30, 31)


def parse_fixed(body: bytes, ncols: int) -> np.ndarray | None:
    """Parse comma/newline separated fixed-point decimals ("-12.345", "7") into an (n, ncols) float
    array with whole-array operations; None when the text holds anything else (the caller then uses
    a general parser)."""
    a = np.frombuffer(body, np.uint8)
    if a.size == 0:
        return np.empty((0, ncols))
    if a[-1] != 10:
        a = np.append(a, np.uint8(10))
    is_sep = (a == 44) | (a == 10)
    is_digit = (a >= 48) & (a <= 57)
    is_dot = a == 46
    is_minus = a == 45
    if not (is_sep | is_digit | is_dot | is_minus).all():
        return None
    ends = np.flatnonzero(is_sep)
    starts = np.concatenate([[0], ends[:-1] + 1])
    if (ends <= starts).any() or len(ends) % ncols:
        return None
    tok = np.cumsum(is_sep, dtype=np.int64)
    tok -= is_sep                                  # token index of every byte
    dots = np.flatnonzero(is_dot)
    dot_tok = tok[dots]
    if (np.diff(dot_tok) == 0).any():              # two dots in one token
        return None
    dot_pos = ends.copy()                          # each token's dot, or its end without one
    dot_pos[dot_tok] = dots
    pos = np.flatnonzero(is_digit)
    ptok = tok[pos]
    dp = dot_pos[ptok]
    power = dp - pos - (pos < dp)                  # 10^(dot - pos - 1) left of the dot, 10^(dot - pos) right
    if power.size and (power.min() < -30 or power.max() > 30):
        return None
    vals = (a[pos] - 48).astype(np.float64) * _POW10[power + 30]
    out = np.bincount(ptok, weights=vals, minlength=len(ends))
    minus = np.flatnonzero(is_minus)
    if (minus != starts[tok[minus]]).any():        # a minus sign only in front
        return None
    out[tok[minus]] *= -1.0
    return out.reshape(-1, ncols)


def parse_fixed_chunked(body: bytes, ncols: int, chunk: int = 1 << 17) -> np.ndarray | None:
    parts = []
    i, n = 0, len(body)
    while i < n:
        j = body.find(b"\n", min(i + chunk, n - 1))
        j = n if j < 0 else j + 1
        part = parse_fixed(body[i:j], ncols)
        if part is None:
            return None
        parts.append(part)
        i = j
    return np.concatenate(parts) if parts else np.empty((0, ncols))


def _words_to_codes(body: bytes, codes: dict[bytes, int]) -> bytes | None:
    """Every run of lowercase letters (a word of at most 8, e.g. a region name) replaced by its
    one-digit code, with whole-array operations (no GIL held: both tables are read at once); None
    when a word is not in ``codes`` (the caller's general parser then names the bad line)."""
    a = np.frombuffer(body, np.uint8)
    alpha = (a >= 97) & (a <= 122)
    edge = np.diff(alpha.astype(np.int8), prepend=np.int8(0), append=np.int8(0))
    starts, ends = np.flatnonzero(edge == 1), np.flatnonzero(edge == -1)
    if starts.size == 0:
        return body
    length = ends - starts
    if length.max() > 8:
        return None
    # each word as the 8 bytes of one integer key (zero padded): exact, no hashing
    take = starts[:, None] + np.arange(8)[None, :]
    inside = np.arange(8)[None, :] < length[:, None]
    word = np.where(inside, a[np.minimum(take, len(a) - 1)], 0).astype(np.uint8)
    keys = np.ascontiguousarray(word).view(np.uint64).ravel()
    known = np.array([np.frombuffer(w.ljust(8, b"\0"), np.uint64)[0] for w in codes], np.uint64)
    order = np.argsort(known)
    k = np.clip(np.searchsorted(known[order], keys), 0, len(known) - 1)
    if (known[order][k] != keys).any():
        return None
    digit = np.array([48 + c for c in codes.values()], np.uint8)[order][k]
    out = a.copy()
    out[starts] = digit
    keep = ~alpha
    keep[starts] = True
    return out[keep].tobytes()


def read_cl(path: str | Path) -> dict[str, np.ndarray]:
    """Parse a CL table quickly (region names mapped to codes, then one numeric parse)."""
    path = Path(path)
    if not path.is_file():
        raise OutputError(f"{path} is missing: not a complete plan folder")
    data = path.read_bytes()
    head, _, body = data.partition(b"\n")
    if head.decode("utf-8", "replace").strip() != CL_HEADER:
        raise OutputError(f"{path}: unexpected header {head[:120]!r}; expected {CL_HEADER}")
    coded = _words_to_codes(body, REGION_CODES)
    a = parse_fixed_chunked(coded, 11) if coded is not None else None
    if a is None:  # not plain fixed-point decimals: the general parser names the bad line
        import io

        for name, code in REGION_CODES.items():
            body = body.replace(b"," + name + b",", b"," + str(code).encode() + b",")
        try:
            a = np.loadtxt(io.BytesIO(body), delimiter=",", ndmin=2)
        except ValueError as exc:
            raise OutputError(f"{path}: {exc}") from None
        if a.shape[1] != 11:
            raise OutputError(f"{path}: rows do not all have 11 columns")
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if bad.size:  # (the fast parser reads digits only: nan and inf reach the general one)
            raise OutputError(f"{path}, line {int(bad[0]) + 2}: a cell is not a finite number "
                              f"({bad.size} such rows): not a table bladecam wrote")
    if len(a) == 0:
        raise OutputError(f"{path}: no rows under its header: not a complete plan folder")
    return {"t": a[:, 0], "step": a[:, 1].astype(int), "region": a[:, 2].astype(int), "path": a[:, 3].astype(int),
            "cutting": a[:, 4] > 0.5, "p": a[:, 5:8], "w": a[:, 8:11]}


@dataclass
class Report:
    findings: list[str] = field(default_factory=list)
    figures: dict = field(default_factory=dict)

    def bad(self, msg: str) -> None:
        self.findings.append(msg)


def _closest_between(d0: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """Minimum of |d0 + s (d1 - d0)| over s in [0, 1], row by row (a quadratic in s)."""
    e = d1 - d0
    qa = np.einsum("ij,ij->i", e, e)
    qb = np.einsum("ij,ij->i", d0, e)
    s = np.zeros(len(d0))
    np.divide(-qb, qa, out=s, where=qa > 1e-18)
    s = np.clip(s, 0.0, 1.0)
    return np.sqrt(np.einsum("ij,ij->i", d0 + s[:, None] * e, d0 + s[:, None] * e))


def _capsule_gap(a0, a1, b0, b1, iterations: int = 40) -> np.ndarray:
    """Distance between segments by alternating projections (convex sets: converges to the minimum);
    a row stops once neither projection moves by more than 1e-12 mm."""
    da, db = a1 - a0, b1 - b0
    la, lb = np.einsum("ij,ij->i", da, da), np.einsum("ij,ij->i", db, db)
    la1, lb1 = np.where(la > 0, la, 1.0), np.where(lb > 0, lb, 1.0)
    s = np.full(len(a0), 0.5)
    t = np.full(len(a0), 0.5)
    act = np.arange(len(a0))
    for _ in range(iterations):
        if act.size == 0:
            break
        pa = a0[act] + s[act, None] * da[act]
        tn = np.clip(np.einsum("ij,ij->i", pa - b0[act], db[act]) / lb1[act], 0.0, 1.0)
        pb = b0[act] + tn[:, None] * db[act]
        sn = np.clip(np.einsum("ij,ij->i", pb - a0[act], da[act]) / la1[act], 0.0, 1.0)
        moved = (np.abs(sn - s[act]) * np.sqrt(la[act]) > 1e-12) | (np.abs(tn - t[act]) * np.sqrt(lb[act]) > 1e-12)
        s[act], t[act] = sn, tn
        act = act[moved]
    return np.linalg.norm(a0 + s[:, None] * da - (b0 + t[:, None] * db), axis=1)


#: plan.json's inputs that verify reads, each a positive number
PLAN_NUMBERS = ("h_safe", "tool_radius", "feed", "a_max", "tool_length")


def plan_inputs(summary: object, path: Path) -> dict:
    """plan.json's "inputs" as verify needs them (OutputError naming the key that is missing or of the
    wrong kind: the folder was not written by bladecam plan, or was edited)."""
    def bad(what: str) -> OutputError:
        return OutputError(f"{path}: {what}; not a plan.json written by bladecam plan (plan again)")

    if not isinstance(summary, dict):
        raise bad(f"a JSON {type(summary).__name__}, not an object")
    inp = summary.get("inputs")
    if not isinstance(inp, dict):
        raise bad("no \"inputs\" object")
    for key in PLAN_NUMBERS:
        v = inp.get(key)
        if key not in inp:
            raise bad(f"inputs.{key} is missing")
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v <= 0:
            raise bad(f"inputs.{key} is {json.dumps(v)[:40]}, not a positive number")
    if not isinstance(inp.get("blade_source"), str) or not inp["blade_source"].strip():
        raise bad("inputs.blade_source is missing or not a text")
    if inp.get("axis", "z") not in ("x", "y", "z"):
        raise bad(f"inputs.axis is {json.dumps(inp.get('axis'))[:40]}, not one of x, y, z")
    return inp


def verify(folder: str | Path, surface_stride: int = 1, workers: int = 2) -> Report:
    """Re-check a plan folder; the report lists every finding (empty = clean). ``workers`` > 1 reads
    both CL tables in forked processes while the blade is tessellated."""
    folder = Path(folder)
    rep = Report()
    try:
        summary = json.loads((folder / "plan.json").read_text())
    except (OSError, ValueError) as exc:
        raise OutputError(f"{folder}: cannot read plan.json ({exc})") from None
    inp = plan_inputs(summary, folder / "plan.json")
    h, r, feed, a_max = inp["h_safe"], inp["tool_radius"], inp["feed"], inp["a_max"]
    stick = inp["tool_length"]

    # the two CL tables are parsed in two forked processes while this one tessellates the blade and
    # builds the search tree (the parser's many small array operations hold the GIL: two threads
    # took 1.9 times one table's time)
    helpers = [Helper([(name, read_cl, (folder / name,))], workers, doing="reading")
               for name in ("left_cl.csv", "right_cl.csv")]
    try:
        blade = load_blade(inp["blade_source"], axis=inp.get("axis", "z"))
        index = TriangleIndex(surface_mesh(blade, workpiece_frame(blade)),
                              k=FACET_CANDIDATES if hasattr(blade, "facets") else 8)
        left, right = (job.results()[name] for job, name in zip(helpers, ("left_cl.csv", "right_cl.csv"), strict=True))
    finally:
        for job in helpers:
            job.close()
    t = left["t"]
    if len(t) != len(right["t"]) or np.abs(t - right["t"]).max(initial=0) > 1e-9:
        rep.bad("left and right CL tables do not share one time column")
        return rep
    if (np.diff(t) <= 0).any():
        i = int(np.argmax(np.diff(t) <= 0))
        rep.bad(f"t = {t[i]:.3f} ms: time column not strictly increasing")
    steps = set(np.unique(left["step"])) | set(np.unique(right["step"]))
    if not steps <= set(range(1, 8)):
        rep.bad(f"steps outside 1..7: {sorted(steps - set(range(1, 8)))}")
    # tip spacing at and between samples
    d = left["p"] - right["p"]
    at = np.linalg.norm(d, axis=1)
    between = _closest_between(d[:-1], d[1:])
    for arr, what, times in ((at, "at sample", t), (between, "between samples", t[:-1])):
        low = np.nonzero(arr < h - 1e-6)[0]
        for i in low[:10]:
            rep.bad(f"t = {times[i]:.1f} ms: tip spacing {arr[i]:.4f} mm < h_safe {h} mm ({what})")
        if len(low) > 10:
            rep.bad(f"... and {len(low) - 10} more tip spacings below h_safe ({what})")
    # capsules
    ca, cb = left["p"] + r * left["w"], right["p"] + r * right["w"]
    gap = _capsule_gap(ca, ca + stick * left["w"], cb, cb + stick * right["w"]) - 2 * r
    touch = np.nonzero(gap <= 0)[0]
    for i in touch[:10]:
        rep.bad(f"t = {t[i]:.1f} ms: the tools touch (capsule gap {gap[i]:.4f} mm)")
    if len(touch) > 10:
        rep.bad(f"... and {len(touch) - 10} more samples where the tools touch")
    # kinematics on cutting stretches
    dt = np.diff(t)
    for name, s in (("left", left), ("right", right)):
        v = np.linalg.norm(np.diff(s["p"], axis=0), axis=1) / dt
        same = s["cutting"][:-1] & s["cutting"][1:] & (s["path"][:-1] == s["path"][1:])
        fast = np.nonzero(same & (v > feed / 60000.0 * 1.01))[0]
        for i in fast[:5]:
            rep.bad(f"t = {t[i]:.1f} ms: {name} cutter at {v[i] * 60000:.1f} mm/min > feed {feed} mm/min")
        both = same[:-1] & same[1:]
        acc = np.abs(np.diff(v)) / (0.5 * (dt[:-1] + dt[1:]))
        hard = np.nonzero(both & (acc > a_max / 1e6 * 1.05))[0]
        for i in hard[:5]:
            rep.bad(f"t = {t[i + 1]:.1f} ms: {name} cutter accelerates at {acc[i] * 1e6:.1f} mm/s^2 > a_max")
        rep.figures[f"{name}_peak_speed_mm_min"] = round(float(v[same].max(initial=0) * 60000), 3)
        rep.figures[f"{name}_peak_accel_mm_s2"] = round(float(acc[both].max(initial=0) * 1e6), 3)
    # cutting points on the offset surface

    picked = {name: np.nonzero(s["cutting"])[0][::surface_stride] for name, s in (("left", left), ("right", right))}
    allc = np.concatenate([s["p"][picked[n]] + r * s["w"][picked[n]] for n, s in (("left", left), ("right", right))])
    alld = distance_to_surface(allc, index) - r if len(allc) else np.empty(0)  # one search tree for both
    dists = {"left": alld[:len(picked["left"])], "right": alld[len(picked["left"]):]}
    for name in ("left", "right"):
        idx = picked[name]
        if idx.size == 0:
            continue
        dist = dists[name]
        off = np.nonzero((dist < -2e-3) | (dist > MISS_TOLERANCE))[0]
        for j in off[:5]:
            i = idx[j]
            kind = "cuts into" if dist[j] < 0 else "misses"
            rep.bad(f"t = {t[i]:.1f} ms: {name} ball {kind} the blade by {abs(dist[j]):.4f} mm")
        if len(off) > 5:
            rep.bad(f"... and {len(off) - 5} more {name} cutting samples off the offset surface")
        rep.figures[f"{name}_surface_offset_mm"] = [round(float(dist.min()), 6), round(float(dist.max()), 6)]
    if (folder / "left_axes.csv").is_file() or (folder / "right_axes.csv").is_file():
        _check_axes(folder, {"left": left, "right": right}, t, rep)
    rep.figures.update({"samples": int(len(t)), "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
                        "min_capsule_gap_mm": round(float(gap.min()), 6)})
    return rep


AXES_HEADER = "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3"


def _check_axes(folder: Path, cl: dict, t: np.ndarray, rep: Report) -> None:
    """Axis tables: forward kinematics of every row (core.machine.kinematics, the mechanism solved by Newton's
    method, not the planner's closed-form inverse) reproduces the CL tip and axis (1e-3 mm, 1e-4 rad);
    every stroke, speed and acceleration limit of the machine.toml in the folder holds (acceleration:
    the change of the velocity column between two rows over their time step)."""

    machine = load_machine(folder / "machine.toml")
    for side in ("left", "right"):
        path = folder / f"{side}_axes.csv"
        if not path.is_file():
            rep.bad(f"{path.name} is missing (the other side's table is there)")
            continue
        head, _, body = path.read_bytes().partition(b"\n")
        if head.decode("utf-8", "replace").strip() != AXES_HEADER:
            raise OutputError(f"{path}: unexpected header {head[:120]!r}; expected {AXES_HEADER}")
        a = parse_fixed_chunked(body, 13)
        if a is None:
            raise OutputError(f"{path}: not plain decimal numbers in 13 columns")
        if len(a) != len(t) or np.abs(a[:, 0] - t).max(initial=0) > 1e-9:
            rep.bad(f"{path.name}: its time column differs from the CL tables'")
            continue
        try:
            tips, axes = forward_kinematics(machine, side, a[:, 1:7])
        except MachineError as exc:
            rep.bad(f"{path.name}: {exc}")
            continue
        ep = np.linalg.norm(tips - cl[side]["p"], axis=1)
        w = cl[side]["w"] / np.linalg.norm(cl[side]["w"], axis=1)[:, None]
        ew = np.arccos(np.clip((axes * w).sum(axis=1), -1.0, 1.0))
        for arr, tol, what, unit in ((ep, 1e-3, "tip", "mm"), (ew, 1e-4, "axis", "rad")):
            bad = np.flatnonzero(arr > tol)
            for i in bad[:3]:
                rep.bad(f"t = {t[i]:.1f} ms: {side} forward kinematics misses the CL {what} by {arr[i]:.2e} {unit}")
        rep.figures[f"{side}_fk_error_mm"] = float(f"{ep.max(initial=0):.3g}")
        for k, name in enumerate(AXES):
            lim = machine.limits.axis(name)
            v = a[:, 1 + k]
            out = np.flatnonzero((v < lim.min_mm - 1e-6) | (v > lim.max_mm + 1e-6))
            for i in out[:3]:
                rep.bad(f"t = {t[i]:.1f} ms: {side} {name} = {v[i]:.4f} mm outside its stroke "
                        f"[{lim.min_mm:g}, {lim.max_mm:g}]")
            speed = np.abs(a[:, 7 + k]) * 1000.0
            fast = np.flatnonzero(speed > lim.max_speed_mm_s * (1 + 1e-6) + 1e-6)
            for i in fast[:3]:
                rep.bad(f"t = {t[i]:.1f} ms: {side} {name} moves at {speed[i]:.3f} mm/s > "
                        f"{lim.max_speed_mm_s:g} mm/s")
            # the mean acceleration between two rows' velocities (as the planner's feed override
            # bounds it), allowing for the rounding of the written velocities (1e-9 mm/ms) and times
            dv = np.diff(a[:, 7 + k])
            dt = np.diff(a[:, 0])
            acc = np.abs(dv) / dt * 1e6
            slack = (2e-9 / dt + np.abs(dv) * 2e-6 / dt**2) * 1e6
            hard = np.flatnonzero(acc > lim.max_accel_mm_s2 * (1 + 1e-6) + slack)
            for i in hard[np.argsort(-acc[hard])][:3]:
                rep.bad(f"t = {t[i]:.1f} ms: {side} {name} accelerates at {acc[i]:.1f} mm/s^2 > "
                        f"{lim.max_accel_mm_s2:g} mm/s^2 (to the next row)")
            rep.figures[f"{side}_{name}_peak_accel_mm_s2"] = round(float(acc.max(initial=0)), 2)
