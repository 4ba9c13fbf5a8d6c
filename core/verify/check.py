"""``bladecam verify DIR``: an independent re-check of a written plan.

It reads only the plan folder (or the rows ``bladecam plan`` holds, exactly as written) and shares no
checking code with the planner: its tables are parsed by its own compiled reader (core.verify._tables)
and every distance comes from its own compiled engine (core.verify.distance, core.verify._distance)
over the blade tessellated afresh. It trusts, and says so in its report (``Report.trusted``),
plan.json's inputs (the blade source and every parameter) and machine.toml's geometry and limits;
everything else is checked:
- the file set: every file plan.json lists (its "files") is there, nothing else is, and the plan's
  own kind needs them all: pairs.csv and plan.json always, both CL tables unless paths only, both
  axis tables with machine.toml for the machines (``file_set``);
- pairs.csv against plan.json: its paths and its pair points per region (``pairs_checks``);
- one common time column, every row on plan.json's period (t = k * period_ms); steps within 1..7;
- tip spacing >= h_safe at every sample and between samples (both tips move linearly between two
  samples: the minimum of a quadratic in the interval parameter);
- the two tool capsules (ball swept along the axis for the stick-out) never touch (the closed-form
  distance of the two axis segments);
- every cutting sample's ball centre is on the blade's offset surface: its distance to the blade,
  tessellated afresh, is r within [-2e-3, +0.05] mm (no gouge, no air cut beyond the tessellation's
  own error at rounded edges);
- speed <= feed on consecutive cutting samples of one path, acceleration along the path <= a_max
  (5 % sampling slack, as the shared checks use);
- each cutter cuts every pair point of its side, path by path, in order, and nothing else
  (core.verify.coverage.path_checks);
- the axis tables: forward kinematics, strokes, speeds, accelerations, and velocities that are the
  derivative of the positions (core.verify.axes.axes_checks);
- the whole tool assembly and the heads against the blade, the clamp and the other side, at every
  row and between rows (core.verify.assembly), and blade.stl against the blade.
Each side's own checks run in a helper process while this one makes the blade's index (and compares
the files' digests in a thread) and checks the two cutters together.
"""

from __future__ import annotations

import json
import math
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from core.blade.frame import workpiece_frame
from core.blade.placement import parse_axis
from core.blade.source import load_blade
from core.errors import BladeInputError, OutputError
from core.machine.model import load_machine
from core.output.csvio import Helper
from core.paths.regions import REGION_NAMES
from core.paths.tessellation import SurfaceMesh, surface_mesh
from core.util.digest import file_digest, inputs_digest
from core.util.files import parse_json
from core.verify.assembly import ASSEMBLY_FILES, assembly_checks
from core.verify.axes import axes_checks
from core.verify.coverage import path_checks, reach_tolerance
from core.verify.cutters import SIDES, two_cutters
from core.verify.distance import DistanceIndex
from core.verify.read import cl_columns, pairs_columns, table_rows
from core.verify.report import Report

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
    try:
        parse_axis(inp.get("axis", "z"))
    except BladeInputError:
        raise bad(f"inputs.axis is {json.dumps(inp.get('axis'))[:40]}, not x, y, z or DX,DY,DZ[@PX,PY,PZ]") from None
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
        if seen & set(ASSEMBLY_FILES) or "collisions" in summary["schedule"]:
            expected.update(ASSEMBLY_FILES)
    why = {"pairs.csv": "the cutters' completeness cannot be checked",
           "machine.toml": "the axis tables cannot be checked without it",
           **dict.fromkeys(ASSEMBLY_FILES, "the tool assembly cannot be checked against the blade"),
           **dict.fromkeys(CL_FILES, "the cutters' motion cannot be checked")}
    for name in sorted(expected - present):
        what = why.get(name, "the axis tables and machine.toml come together")
        where = " (listed in plan.json)" if listed and name in listed else ""
        rep.bad("file set", f"{name} is missing{where}: {what}")
    for name in sorted(seen - expected):
        what = ("which bladecam plan did not write" if name not in {*CL_FILES, *MACHINE_FILES, *ASSEMBLY_FILES} else
                "which a plan without a schedule (paths only) does not write")
        rep.bad("file set", f"the folder holds {name}, {what}" if name in entries
                else f"plan.json lists {name}, {what}")
    for name in sorted(expected - (listed if listed is not None else expected)):
        rep.bad("file set", f"plan.json's file list lacks {name}, which this kind of plan writes")
    return expected & present


def digest_checks(folder: Path, summary: dict, have: set[str], rep: Report,
                  skip: frozenset[str] | set[str] = frozenset()) -> bool:
    """Findings for files changed after planning: plan.json's "sha256" (core.util.digest) against the
    folder's files (but ``skip``: tables checked as the rows in memory, whose digests were just made
    of them), plan.json's inputs and the blade's source files as they are now. Returns whether
    plan.json carries the digests (a plan of an earlier version does not: nothing to compare)."""
    digests = summary.get("sha256")
    if not isinstance(digests, dict):
        return False
    files = digests.get("files") if isinstance(digests.get("files"), dict) else {}
    for name in sorted((have - skip) & set(files)):
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
        names = dict(enumerate(REGION_NAMES))
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
    line = (f"trusted as written: plan.json's inputs (blade {_short(inp['blade_source'], 30)!r}, tool, h_safe, "
            "feed, a_max" + (", chord tol." if "chord_tol_mm" in inp else "") + ")")
    line += ", machine.toml" if machine else ""
    return line + ("; files and inputs checked by their SHA-256 digests" if digested else
                   "; no digests recorded")


def _side(folder: Path, side: str, cl: dict, pairs: dict | None, inp: dict, machine: bool,
          given: dict | None) -> Report:
    """One cutter's own checks (core.verify.coverage, core.verify.axes), in a helper process."""
    rep = Report()
    if pairs is not None:
        rep.figures.update(path_checks(side, pairs, cl, inp["tool_radius"], rep,
                                       reach_tolerance(inp.get("chord_tol_mm"))))
    if machine:
        name = f"{side}_axes.csv"
        machine_model = load_machine(folder / "machine.toml")
        rep.figures.update(axes_checks(side, table_rows(folder, name, given), cl, machine_model, rep, name))
    return rep


def verify(folder: str | Path, surface_stride: int = 1, workers: int = 2, given: dict | None = None,
           mesh: SurfaceMesh | None = None) -> Report:
    """Re-check a plan folder; the report lists every finding (none = clean). ``given``: file name ->
    the table's rows (n, ncols) exactly as written (core.verify.read.table_rows), for the tables a
    caller holds in memory (``bladecam plan`` verifying the folder it is about to make visible): they
    are not read again, nor their digests compared. ``mesh``: the blade's tessellation where the
    caller has made it, core.paths.tessellation.surface_mesh of plan.json's blade in its workpiece
    frame with its defaults (deterministic: the triangles verify would make; a tessellation, not a
    check of the planner's), so that it is not made twice. ``workers`` > 1 checks each side's own files in
    two forked processes (from the moment the tables are read) while this one makes the blade's
    index, its files' digests compared in a thread meanwhile, and then checks the two cutters
    together and the tool assembly (in a thread of its own)."""
    folder = Path(folder)
    rep = Report()
    try:
        summary = parse_json((folder / "plan.json").read_text())
    except (OSError, ValueError) as exc:
        raise OutputError(f"{folder}: cannot read plan.json ({exc})") from None
    inp = _inputs(summary, folder, rep)
    have = file_set(folder, summary, rep)
    machine = set(MACHINE_FILES) <= have
    skip = set(given or ())
    if not set(CL_FILES) <= have:  # (paths only, or a CL table missing: a finding already)
        rep.trusted = trusted(inp, machine, digest_checks(folder, summary, have, rep, skip))
        if "pairs.csv" in have:
            pairs_checks(pairs_columns(table_rows(folder, "pairs.csv", given)), summary, rep)
        return rep
    names = [*CL_FILES, *(["pairs.csv"] if "pairs.csv" in have else [])]
    with ThreadPoolExecutor(2) as pool:  # (the compiled reader releases the GIL; the pool ends before the forks)
        got = dict(zip(names, pool.map(lambda name: table_rows(folder, name, given), names), strict=True))
    cl = {"left": cl_columns(got["left_cl.csv"]), "right": cl_columns(got["right_cl.csv"])}
    paired = Report()  # (pairs.csv's findings, listed after the digests')
    pairs = pairs_checks(pairs_columns(got["pairs.csv"]), summary, paired) if "pairs.csv" in got else None
    sides = [Helper([(side, _side, (folder, side, cl[side], pairs, inp, machine, given))], workers,
                    doing="checking") for side in SIDES]
    try:
        with ThreadPoolExecutor(1) as pool:  # (hashing releases the GIL: the digests while the index is made)
            digests = Report()
            digested = pool.submit(digest_checks, folder, summary, have, digests, skip)
            blade = load_blade(blade_source(inp["blade_source"]), axis=inp.get("axis", "z"))
            index = DistanceIndex(mesh if mesh is not None else surface_mesh(blade, workpiece_frame(blade)))
            rep.trusted = trusted(inp, machine, digested.result())
        rep.merge(digests)
        rep.merge(paired)
        with ThreadPoolExecutor(1) as pool:  # (the assembly's checks alongside the cutters': both search
            # without the GIL, and each keeps the two cores busy where the other waits on its threads)
            assembled = None
            if set(ASSEMBLY_FILES) <= have:
                frame = summary.get("workpiece_frame") or {}
                x_clamp = float(frame.get("x_clamp_mm", workpiece_frame(blade).x_clamp))
                assembled = pool.submit(assembly_checks, folder, cl["left"], cl["right"], inp, x_clamp, index, machine)
            two_cutters(cl["left"], cl["right"], inp, index, surface_stride, rep)
            if assembled is not None:
                rep.merge(assembled.result())
        for job, side in zip(sides, SIDES, strict=True):
            rep.merge(job.results()[side])
    finally:
        for job in sides:
            job.close()
    return rep


def _inputs(summary: dict, folder: Path, rep: Report) -> dict:
    """plan.json's inputs (``plan_inputs``) with its period (period_ms) and chord tolerance
    (chord_tol_mm) where recorded; a finding where a schedule's period is not a positive number."""
    inp = plan_inputs(summary, folder / "plan.json")
    period = summary.get("period_ms")
    if isinstance(period, int | float) and not isinstance(period, bool) and math.isfinite(period) and period > 0:
        inp = {**inp, "period_ms": float(period)}
    elif "schedule" in summary:
        rep.bad("time column", f"plan.json's period_ms is {json.dumps(period)[:40]}, not a positive number")
    tol = chord_tolerance(summary)
    if tol is not None:
        inp = {**inp, "chord_tol_mm": tol}
    return inp
