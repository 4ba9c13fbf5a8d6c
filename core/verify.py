"""``bladecam verify DIR``: an independent re-check of a written plan.

It reads only the plan folder and shares no code with the scheduling (core.schedule.steps,
core.schedule.motion, core.schedule.safety): the distances below are implemented again here, by other
means. It trusts, and says so in its report (``Report.trusted``), plan.json's inputs (the blade
source and every parameter) and machine.toml's geometry and limits; everything else is checked:
- the file set: every file plan.json lists (its "files") is there, nothing else is, and the plan's
  own kind needs them all: pairs.csv and plan.json always, both CL tables unless paths only, both
  axis tables with machine.toml for the machines (``file_set``);
- pairs.csv against plan.json: its paths and its pair points per region (``pairs_checks``);
- one common time column, every row on plan.json's period (t = k * period_ms); steps within 1..7;
- tip spacing >= h_safe at every sample and between samples (both tips move linearly between two
  samples: the minimum of a quadratic in the interval parameter);
- the two tool capsules (ball swept along the axis for the stick-out) never touch (alternating
  projections between the two axis segments);
- every cutting sample's ball centre is on the blade's offset surface: its distance to the blade,
  tessellated afresh, is r within [-2e-3, +0.05] mm (no gouge, no air cut beyond the tessellation's
  own error at rounded edges);
- speed <= feed on consecutive cutting samples of one path, acceleration along the path <= a_max
  (5 % sampling slack, as the shared checks use);
- each cutter cuts every pair point of its side, path by path, in order, and nothing else
  (core.verify_side.path_checks);
- the axis tables: forward kinematics, strokes, speeds, accelerations, and velocities that are the
  derivative of the positions (core.verify_side.axes_checks).
Each side's own checks run in a helper process while this one checks the two cutters together.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from core.blade.frame import workpiece_frame
from core.blade.source import load_blade
from core.errors import OutputError
from core.machine.model import load_machine
from core.output.csvio import Helper
from core.paths.gouge import FACET_CANDIDATES, TriangleIndex, distance_to_surface, surface_mesh
from core.records import DEFAULT_CHORD_TOL
from core.util.digest import file_digest, inputs_digest
from core.util.files import parse_json
from core.verify_read import (  # noqa: F401 - CL_HEADER, REGION_CODES, parse_fixed: verify's reading, re-exported
    CL_HEADER,
    REGION_CODES,
    Report,
    parse_fixed,
    read_axes,
    read_cl,
    read_pairs,
)
from core.verify_side import axes_checks, path_checks, reach_tolerance

#: how far a cutting ball centre may sit outside the offset surface (mm): the check's own tessellation
#: (0.25 mm chordwise) lies inside a rounded edge by up to a few hundredths of a millimetre there
MISS_TOLERANCE = 0.05
#: how far a ball centre at a row may lie inside the offset surface (mm): the check's tessellation
#: against the smooth blade
ROW_DIP = 2e-3
SIDES = ("left", "right")


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
        moved = ((np.abs(sn - s[act]) * np.sqrt(la[act]) > 1e-12)
                 | (np.abs(tn - t[act]) * np.sqrt(lb[act]) > 1e-12))
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


def chord_tolerance(summary: dict) -> float | None:
    """The chord tolerance (mm) the plan was made with (plan.json's schedule.machine.chord), None when
    it is not recorded as a positive number (a paths-only plan, an earlier version's)."""
    schedule = summary.get("schedule")
    machine = schedule.get("machine") if isinstance(schedule, dict) else None
    chord = machine.get("chord") if isinstance(machine, dict) else None
    tol = chord.get("tolerance_mm") if isinstance(chord, dict) else None
    if isinstance(tol, bool) or not isinstance(tol, int | float) or not math.isfinite(tol) or tol <= 0:
        return None
    return float(tol)


CL_FILES = ("left_cl.csv", "right_cl.csv")
MACHINE_FILES = ("left_axes.csv", "right_axes.csv", "machine.toml")


def file_set(folder: Path, summary: dict, rep: Report) -> set[str]:
    """Findings for the folder's file set; returns the files it should hold that are there. A plan
    folder holds plan.json and pairs.csv; with a schedule (plan.json's "schedule": not paths only) both
    CL tables; with the machines, both axis tables and machine.toml, all three or none. Every file
    plan.json lists (its "files") must be there, and the list must hold every file the folder should."""
    try:
        entries = {e.name: e.is_file() for e in os.scandir(folder)}
    except OSError as exc:
        raise OutputError(f"{folder}: cannot be read ({exc.strerror or exc})") from None
    present = {name for name, regular in entries.items() if regular}
    listed = summary.get("files")
    if listed is not None and not (isinstance(listed, list) and all(isinstance(n, str) for n in listed)):
        rep.bad("file set", "plan.json's \"files\" is not a list of file names")
        listed = None
    listed = set(listed) if listed is not None else None
    seen = set(entries) | (listed or set())
    expected = {"plan.json", "pairs.csv"}
    if isinstance(summary.get("schedule"), dict):
        expected.update(CL_FILES)
        if seen & set(MACHINE_FILES):
            expected.update(MACHINE_FILES)
    why = {"pairs.csv": "the cutters' completeness cannot be checked",
           "machine.toml": "the axis tables cannot be checked without it",
           **dict.fromkeys(CL_FILES, "the cutters' motion cannot be checked")}
    for name in sorted(expected - present):
        what = why.get(name, "the axis tables and machine.toml come together")
        where = " (listed in plan.json)" if listed and name in listed else ""
        rep.bad("file set", f"{name} is missing{where}: {what}")
    for name in sorted(seen - expected):
        what = ("which bladecam plan did not write" if name not in {*CL_FILES, *MACHINE_FILES} else
                "which a plan without a schedule (paths only) does not write")
        rep.bad("file set", f"the folder holds {name}, {what}" if name in entries
                else f"plan.json lists {name}, {what}")
    for name in sorted(expected - (listed if listed is not None else expected)):
        rep.bad("file set", f"plan.json's file list lacks {name}, which this kind of plan writes")
    return expected & present


def digest_checks(folder: Path, summary: dict, have: set[str], rep: Report) -> bool:
    """Findings for files changed after planning: plan.json's "sha256" (core.util.digest) against the
    folder's files, plan.json's inputs and the blade's source files as they are now. Returns whether
    plan.json carries the digests (a plan of an earlier version does not: nothing to compare)."""
    digests = summary.get("sha256")
    if not isinstance(digests, dict):
        return False
    files = digests.get("files") if isinstance(digests.get("files"), dict) else {}
    for name in sorted(have & set(files)):
        if file_digest(folder / name) != files[name]:
            rep.bad("digest", f"{name} changed after planning (its SHA-256 differs from plan.json's): the "
                              "checks below measure the file as it is now")
    if digests.get("inputs") != inputs_digest(summary.get("inputs")):
        rep.bad("digest", "plan.json's inputs changed after planning (their SHA-256 differs from the one "
                          "recorded): the checks below use them as they are now")
    sources = digests.get("sources") if isinstance(digests.get("sources"), dict) else {}
    for path, digest in sorted(sources.items()):
        now = file_digest(path) if os.path.isfile(path) else None
        if now != digest:
            what = "is missing" if now is None else "changed since planning (its SHA-256 differs)"
            rep.bad("digest", f"the blade file {_short(path)} {what}: the surface checks measure the blade "
                              "as it is now")
    return True


def pairs_checks(pairs: dict, summary: dict, rep: Report) -> dict:
    """pairs.csv against plan.json's "paths" (its number of paths and of pair points per region) and
    itself (k = 0, 1, ... along each path); returns the arrays sorted by path and k."""
    order = np.lexsort((pairs["k"], pairs["path"]))
    pairs = {key: v[order] for key, v in pairs.items()}
    pp, pk = pairs["path"], pairs["k"]
    rep.figures.update({"paths": int(len(np.unique(pp))), "pair_points": int(len(pp))})
    first = np.r_[True, pp[1:] != pp[:-1]]
    start = np.maximum.accumulate(np.where(first, np.arange(len(pp)), 0))
    jump = np.flatnonzero(pk != np.arange(len(pp)) - start)
    rep.many("pairs", np.unique(pp[jump], return_index=True)[1],
             lambda j: f"pairs.csv path {pp[jump[j]]}: k {pk[jump[j]]} where {jump[j] - start[jump[j]]} "
                       "is due (a pair point missing or repeated)")
    info = summary.get("paths") if isinstance(summary.get("paths"), dict) else {}
    n_paths = info.get("paths")
    if isinstance(n_paths, int) and not isinstance(n_paths, bool):
        missing = np.setdiff1d(np.arange(n_paths), pp)
        if missing.size:
            few = ", ".join(str(p) for p in missing[:6]) + (" ..." if missing.size > 6 else "")
            rep.bad("pairs", f"pairs.csv lacks {missing.size} of the {n_paths} paths plan.json counts "
                             f"({few})")
        extra = np.setdiff1d(pp, np.arange(n_paths))
        if extra.size:
            rep.bad("pairs", "pairs.csv has paths plan.json does not count: "
                             f"{', '.join(map(str, extra[:6]))}")
    points = info.get("points")
    if isinstance(points, dict):
        names = {code: name.decode() for name, code in REGION_CODES.items()}
        have = dict(zip(*np.unique(pairs["region"], return_counts=True), strict=True))
        for code, name in names.items():
            want = points.get(name, 0)
            if isinstance(want, int) and have.get(code, 0) != want:
                rep.bad("pairs", f"pairs.csv has {have.get(code, 0)} {name} pair points, plan.json counts "
                                 f"{want}")
    return pairs


def _short(text: str, n: int = 60) -> str:
    return text if len(text) <= n else "..." + text[-(n - 3):]


def blade_source(source: str) -> str:
    """plan.json's blade source as load_blade takes it; OutputError when it names a file by a relative
    path that is not there from here (bladecam plan records absolute paths: an earlier version's plan)."""
    if source.strip().lower() == "sample":
        return source
    lost = [p.strip() for p in source.split(",") if p.strip() and not os.path.isabs(p.strip())
            and not os.path.exists(p.strip())]
    if lost:
        raise OutputError(f"plan.json's blade source {lost[0]!r} is a relative path, not found from "
                          f"{os.getcwd()}: run bladecam verify in the folder the plan was made in, or plan "
                          "again")
    return source


def trusted(inp: dict, machine: bool, digested: bool = False) -> str:
    """The one line that says what verify takes as written (and whether the files' digests were
    compared: a change after planning is then a finding)."""
    line = (f"trusted as written: plan.json's inputs (blade {_short(inp['blade_source'])!r}, tool radius and "
            "length, h_safe, feed, a_max" + (", the chord tolerance" if "chord_tol_mm" in inp else "") + ")")
    line += " and machine.toml's geometry and axis limits" if machine else ""
    return line + ("; every file, the inputs and the blade's files compared with the SHA-256 digests "
                   "plan.json recorded" if digested else "; no digests recorded to compare with")


def _side(folder: Path, side: str, cl: dict, pairs: dict | None, inp: dict, machine: bool) -> Report:
    """One cutter's own checks (core.verify_side), in a helper process."""
    rep = Report()
    if pairs is not None:
        rep.figures.update(path_checks(side, pairs, cl, inp["tool_radius"], rep,
                                       reach_tolerance(inp.get("chord_tol_mm"))))
    if machine:
        name = f"{side}_axes.csv"
        machine_model = load_machine(folder / "machine.toml")
        rep.figures.update(axes_checks(side, read_axes(folder / name), cl, machine_model, rep, name))
    return rep


def verify(folder: str | Path, surface_stride: int = 1, workers: int = 2) -> Report:
    """Re-check a plan folder; the report lists every finding (none = clean). ``workers`` > 1 reads
    both CL tables (and pairs.csv) in forked processes while the blade is tessellated, then checks
    each side's own files in two more while this one checks the two cutters together."""
    folder = Path(folder)
    rep = Report()
    try:
        summary = parse_json((folder / "plan.json").read_text())
    except (OSError, ValueError) as exc:
        raise OutputError(f"{folder}: cannot read plan.json ({exc})") from None
    inp = plan_inputs(summary, folder / "plan.json")
    period = summary.get("period_ms")
    if isinstance(period, int | float) and not isinstance(period, bool) and math.isfinite(period) and period > 0:
        inp = {**inp, "period_ms": float(period)}
    elif "schedule" in summary:
        rep.bad("time column", f"plan.json's period_ms is {json.dumps(period)[:40]}, not a positive number")
    tol = chord_tolerance(summary)
    if tol is not None:
        inp = {**inp, "chord_tol_mm": tol}
    have = file_set(folder, summary, rep)
    digested = digest_checks(folder, summary, have, rep)
    machine = set(MACHINE_FILES) <= have
    rep.trusted = trusted(inp, machine, digested)
    if not set(CL_FILES) <= have:  # (paths only, or a CL table missing: a finding already)
        if "pairs.csv" in have:
            pairs_checks(read_pairs(folder / "pairs.csv"), summary, rep)
        return rep

    # the two CL tables (and pairs.csv) are parsed in two forked processes while this one tessellates
    # the blade and builds the search tree (the parser's many small array operations hold the GIL:
    # two threads took 1.9 times one table's time)
    reads = [[(name, read_cl, (folder / name,))] for name in CL_FILES]
    if "pairs.csv" in have:
        reads[0].append(("pairs.csv", read_pairs, (folder / "pairs.csv",)))
    helpers = [Helper(jobs, workers, doing="reading") for jobs in reads]
    try:
        blade = load_blade(blade_source(inp["blade_source"]), axis=inp.get("axis", "z"))
        index = TriangleIndex(surface_mesh(blade, workpiece_frame(blade)),
                              k=FACET_CANDIDATES if hasattr(blade, "facets") else 8)
        got = {name: v for job in helpers for name, v in job.results().items()}
    finally:
        for job in helpers:
            job.close()
    cl = {"left": got["left_cl.csv"], "right": got["right_cl.csv"]}
    pairs = pairs_checks(got["pairs.csv"], summary, rep) if "pairs.csv" in got else None
    sides = [Helper([(side, _side, (folder, side, cl[side], pairs, inp, machine))], workers,
                    doing="checking") for side in SIDES]
    try:
        _two_cutters(cl["left"], cl["right"], inp, index, surface_stride, rep)
        for job, side in zip(sides, SIDES, strict=True):
            rep.merge(job.results()[side])
    finally:
        for job in sides:
            job.close()
    return rep


def _two_cutters(left: dict, right: dict, inp: dict, index: TriangleIndex, surface_stride: int,
                 rep: Report) -> None:
    """The time column, the tip spacing and tool clearance, feed and acceleration along the path, and
    the cutting balls on the offset surface (module docstring)."""
    h, r, feed, a_max = inp["h_safe"], inp["tool_radius"], inp["feed"], inp["a_max"]
    stick = inp["tool_length"]
    t = left["t"]
    if len(t) != len(right["t"]) or np.abs(t - right["t"]).max(initial=0) > 1e-9:
        rep.bad("time column", f"left and right CL tables do not share one time column ({len(t)} and "
                               f"{len(right['t'])} rows)")
        return
    back = np.flatnonzero(np.diff(t) <= 0)
    rep.many("time column", back[:1], lambda i: f"t = {t[i]:.3f} ms: time column not strictly increasing "
                                                f"({back.size} rows)")
    period = inp.get("period_ms")
    if period is not None:  # every row on the controllers' period, t = k * period (to the file's 1e-6 ms)
        off = np.flatnonzero(np.abs(t - np.round(np.arange(len(t)) * period, 6)) > 1.5e-6)
        rep.many("time column", off[:1], lambda i: f"t = {t[i]:.6f} ms: row {i} is off the period of "
                                                   f"{period:g} ms ({off.size} rows)")
    steps = set(np.unique(left["step"])) | set(np.unique(right["step"]))
    if not steps <= set(range(1, 8)):
        rep.bad("time column", f"steps outside 1..7: {sorted(steps - set(range(1, 8)))}")
    # tip spacing at and between samples
    d = left["p"] - right["p"]
    at = np.linalg.norm(d, axis=1)
    between = _closest_between(d[:-1], d[1:])
    for arr, what in ((at, "at sample"), (between, "between samples")):
        rep.many("tip spacing", np.flatnonzero(arr < h - 1e-6),
                 lambda i, arr=arr, what=what: f"t = {t[i]:.1f} ms: tip spacing {arr[i]:.4f} mm < h_safe "
                                               f"{h} mm ({what})")
    # capsules
    ca, cb = left["p"] + r * left["w"], right["p"] + r * right["w"]
    gap = _capsule_gap(ca, ca + stick * left["w"], cb, cb + stick * right["w"]) - 2 * r
    rep.many("tool clearance", np.flatnonzero(gap <= 0),
             lambda i: f"t = {t[i]:.1f} ms: the tools touch (capsule gap {gap[i]:.4f} mm)")
    # kinematics on cutting stretches (a repeated row, a finding of the time column, divides by zero)
    dt = np.diff(t)
    for name, s in (("left", left), ("right", right)):
        _kinematics(name, s, t, dt, feed, a_max, rep)
    _surface(left, right, t, r, index, surface_stride, rep)
    _clearance(left, right, t, r, index, inp.get("chord_tol_mm") or DEFAULT_CHORD_TOL, rep)
    rep.figures.update({"samples": int(len(t)),
                        "min_tip_spacing_mm": round(float(min(at.min(), between.min(initial=np.inf))), 6),
                        "min_capsule_gap_mm": round(float(gap.min()), 6)})


@np.errstate(divide="ignore", invalid="ignore")
def _kinematics(name: str, s: dict, t: np.ndarray, dt: np.ndarray, feed: float, a_max: float,
                rep: Report) -> None:
    """One cutter's speed and acceleration along its path on cutting stretches."""
    v = np.linalg.norm(np.diff(s["p"], axis=0), axis=1) / dt
    same = s["cutting"][:-1] & s["cutting"][1:] & (s["path"][:-1] == s["path"][1:])
    rep.many("feed", np.flatnonzero(same & (v > feed / 60000.0 * 1.01)),
             lambda i, v=v, name=name: f"t = {t[i]:.1f} ms: {name} cutter at {v[i] * 60000:.1f} mm/min > "
                                       f"feed {feed} mm/min")
    both = same[:-1] & same[1:]
    acc = np.abs(np.diff(v)) / (0.5 * (dt[:-1] + dt[1:]))
    rep.many("path acceleration", np.flatnonzero(both & (acc > a_max / 1e6 * 1.05)),
             lambda i, acc=acc, name=name: f"t = {t[i + 1]:.1f} ms: {name} cutter accelerates at "
                                           f"{acc[i] * 1e6:.1f} mm/s^2 > a_max {a_max} mm/s^2")
    rep.figures[f"{name}_peak_speed_mm_min"] = round(float(v[same].max(initial=0) * 60000), 3)
    rep.figures[f"{name}_peak_accel_mm_s2"] = round(float(acc[both].max(initial=0) * 1e6), 3)


def _surface(left: dict, right: dict, t: np.ndarray, r: float, index: TriangleIndex, surface_stride: int,
             rep: Report) -> None:
    """The cutting balls on the offset surface: no gouge, no air cut beyond MISS_TOLERANCE."""
    cutters = (("left", left), ("right", right))
    picked = {name: np.nonzero(s["cutting"])[0][::surface_stride] for name, s in cutters}
    allc = np.concatenate([s["p"][picked[n]] + r * s["w"][picked[n]] for n, s in cutters])
    alld = distance_to_surface(allc, index) - r if len(allc) else np.empty(0)  # one search tree for both
    dists = {"left": alld[:len(picked["left"])], "right": alld[len(picked["left"]):]}
    for name in SIDES:
        idx, dist = picked[name], dists[name]
        if idx.size == 0:
            continue
        rep.many("surface", np.flatnonzero((dist < -2e-3) | (dist > MISS_TOLERANCE)),
                 lambda j, idx=idx, dist=dist, name=name: (
                     f"t = {t[idx[j]]:.1f} ms: {name} ball {'cuts into' if dist[j] < 0 else 'misses'} "
                     f"the blade by {abs(dist[j]):.4f} mm"))
        rep.figures[f"{name}_surface_offset_mm"] = [round(float(dist.min()), 6), round(float(dist.max()), 6)]


def _clearance(left: dict, right: dict, t: np.ndarray, r: float, index: TriangleIndex, chord_tol: float,
               rep: Report) -> None:
    """No ball in the blade at a row that does not cut (a turn, an idle or a lift: the classic crash is
    a rapid through the workpiece), nor on the straight move a controller makes between two rows,
    cutting or not: sampled every half tool radius along it, so that a move across the blade lands a
    sample within a quarter radius of where it enters, where the ball's centre is nearer the surface
    than r. A row may dip ROW_DIP into the offset surface (as a cutting row may), a move between rows
    that much more than the plan's chord tolerance (its straight line strays that far from the path)."""
    for name, s in (("left", left), ("right", right)):
        c = s["p"] + r * s["w"]
        idle = np.flatnonzero(~s["cutting"])
        length = np.linalg.norm(np.diff(c, axis=0), axis=1)
        pieces = np.maximum(np.ceil(length / (0.5 * r)), 1).astype(np.int64)
        seg = np.repeat(np.arange(len(length)), pieces)
        first = np.repeat(np.cumsum(pieces) - pieces, pieces)
        frac = (np.arange(len(seg)) - first + 0.5) / pieces[seg]
        between = c[seg] + frac[:, None] * (c[seg + 1] - c[seg])
        dist = _near_distance(np.concatenate([c[idle], between]), index, r) - r
        at_rows, on_moves = dist[:len(idle)], dist[len(idle):]
        rep.many("surface", np.flatnonzero(at_rows < -ROW_DIP),
                 lambda j, idle=idle, d=at_rows, name=name, s=s: (
                     f"t = {t[idle[j]]:.1f} ms: {name} ball, not cutting "
                     f"({_region_name(s['region'][idle[j]])}), {abs(d[j]):.4f} mm inside the blade"))
        deep = np.flatnonzero(on_moves < -(chord_tol + ROW_DIP))
        worst = deep[np.unique(seg[deep], return_index=True)[1]]  # (one finding per move)
        rep.many("surface", worst,
                 lambda j, d=on_moves, name=name, seg=seg: (
                     f"t = {t[seg[j]]:.1f} to {t[seg[j] + 1]:.1f} ms: {name} ball's straight move between "
                     f"two rows passes {abs(d[j]):.4f} mm inside the blade"))
        low = float(dist.min(initial=np.inf))
        rep.figures[f"{name}_clearance_mm"] = round(low, 6) if np.isfinite(low) else None


def _near_distance(points: np.ndarray, index: TriangleIndex, r: float) -> np.ndarray:
    """(n,) mm: each point's distance to the tessellation where it is within about ``r`` of it, inf
    elsewhere: a point whose nearest triangle centroid lies farther than r plus the largest triangle's
    reach from its centroid is farther than r from every triangle, and is left out of the exact
    search (tools lifted or parked far off the blade: a search tree is slow far from its points)."""
    a = index.a
    centroid = a + (index.ab + index.ac) / 3.0
    reach = np.sqrt(np.max([((v - centroid) ** 2).sum(0).max() for v in (a, a + index.ab, a + index.ac)]))
    near_centroid, _ = index.tree.query(points, k=1, distance_upper_bound=r + reach + 1e-6)
    out = np.full(len(points), np.inf)
    near = np.flatnonzero(np.isfinite(near_centroid))
    if near.size:
        out[near] = distance_to_surface(points[near], index)
    return out


def _region_name(code: int) -> str:
    return next((name.decode() for name, c in REGION_CODES.items() if c == code), str(code))
