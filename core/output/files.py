"""Writing a plan folder (SPEC.md section 10): pairs.csv, plan.json (and later CL and axis tables),
and what a plan folder is.

All files go through ``atomic_folder``: the whole set appears, or nothing changes. plan.json lists
the folder's files ("files"): a folder is taken for a plan folder, and ever replaced, only if it is
provably one bladecam wrote (``plan_folder_files``); ``check_destination`` applies that rule before
any work and ``sweep_scratch`` clears what a killed run left beside the folder.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import secrets
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from core import __version__
from core.blade.source import source_parts
from core.errors import OutputError
from core.machine.tables import AxisTable
from core.output.csvio import CsvChunks, csv_body, split_rows
from core.paths.alignment import AlignedPair
from core.paths.plan import PathPlan
from core.paths.regions import REGION_NAMES, Regions
from core.records import Timings
from core.util.digest import plan_digests
from core.util.scratch import abandoned, scratch_owner

PAIRS_COLUMNS = "path,k,region,xL,yL,zL,iL,jL,kL,xR,yR,zR,iR,jR,kR,spacing_mm,sym_spacing_mm".split(",")
DECIMALS = 9


def pairs_columns(pairs: list[AlignedPair], regions: list[Regions]) -> list[tuple]:
    """pairs.csv's columns (core.output.csvio.csv_body's (kind, values, decimals)) for these paths: the
    pair's tips and axes, their distance (spacing_mm) and the signed tip spacing of the symmetrical
    configuration the regions are decided on (sym_spacing_mm, |c_L - c_R| - 2r: negative where the
    tips have crossed; on a tip path, that of the symmetrical pair at the same path-length ratio)."""
    path = np.concatenate([np.full(len(p.u), p.index) for p in pairs])
    k = np.concatenate([np.arange(len(p.u)) for p in pairs])
    region = np.concatenate([r.labels for r in regions])
    arrays = {key: np.concatenate([getattr(p, key) for p in pairs])
              for key in ("left_tip", "left_axis", "right_tip", "right_axis")}
    cols: list[tuple] = [("i", path, None), ("i", k, None), ("s", region, None)]
    for key in ("left_tip", "left_axis", "right_tip", "right_axis"):
        cols += [("f", arrays[key][:, j], DECIMALS) for j in range(3)]
    cols.append(("f", np.linalg.norm(arrays["left_tip"] - arrays["right_tip"], axis=1), DECIMALS))
    cols.append(("f", np.concatenate([p.spacing for p in pairs]), DECIMALS))
    return cols


def pairs_rows(pairs: list[AlignedPair], regions: list[Regions]) -> list[bytes]:
    """The rows of pairs.csv (no header) for these paths (``pairs_columns``), one bytes block per path."""
    if not pairs:
        return []
    body, ends = csv_body(pairs_columns(pairs, regions))
    return split_rows(body, ends, [len(p.u) for p in pairs])


def pairs_chunks(plan: PathPlan) -> CsvChunks:
    """pairs.csv as a CsvChunks (its values as written: CsvChunks.as_written)."""
    return CsvChunks(PAIRS_COLUMNS, pairs_columns(plan.pairs, plan.regions))


def pairs_csv(plan: PathPlan) -> bytes:
    """pairs.csv: one row per aligned pair point, paths in machining order (tip first)."""
    rows = plan.pairs_rows if plan.pairs_rows is not None else pairs_rows(plan.pairs, plan.regions)
    return (",".join(PAIRS_COLUMNS) + "\n").encode() + b"".join(rows)


def plan_summary(plan: PathPlan, source: str, axis: str, timings: Timings) -> dict:
    """The plan.json content for the geometric plan (``timings``: the plan's and its writing's)."""
    counts = plan.region_counts()
    fallback = plan.fallback_paths()
    return {
        "bladecam_version": __version__,
        "inputs": {"blade_source": source, "axis": axis, **plan.params.as_dict()},
        "blade": plan.blade.info(),
        "workpiece_frame": plan.frame.as_dict(),
        "paths": {
            **counts,
            "radii_mm": [round(p.r, 6) for p in plan.pairs],
            "tip_path_indices": [p.index for p, r in zip(plan.pairs, plan.regions, strict=True) if r.is_tip],
            "arc_length_fallback_paths": fallback,
            "staggered_ratio": [round(r.staggered_ratio, 6) for r in plan.regions],
            "tip_reasons": {str(p.index): r.reason for p, r in zip(plan.pairs, plan.regions, strict=True)
                            if r.is_tip},
            "boundaries": {str(p.index): r.boundaries for p, r in zip(plan.pairs, plan.regions, strict=True)
                           if not r.is_tip},
        },
        "timings_s": {k: round(v, 4) for k, v in timings.items()},
        "warnings": plan.warnings,
    }


def write_plan(plan: PathPlan, out_dir: str | Path, source: str, axis: str, timings: Timings,
               extra_files: dict[str, bytes] | None = None, summary_extra: dict | None = None,
               check: Callable[[Path], None] | None = None) -> Path:
    """Write pairs.csv and plan.json (plus extra files: bytes, a CsvChunks, or the Path of a file written
    already, which is moved in) atomically into out_dir; plan.json reports ``timings`` (and pairs.csv's write
    when it is written here), lists the folder's files ("files", sorted, plan.json included) and records
    the SHA-256 of each, of its inputs and of the blade's files ("sha256", core.util.digest).
    ``check(folder)`` runs on the complete folder before it is made visible (atomic_folder)."""
    t0 = time.perf_counter()
    with atomic_folder(out_dir, check) as tmp:
        if not isinstance((extra_files or {}).get("pairs.csv"), Path):  # (else written already)
            (tmp / "pairs.csv").write_bytes(pairs_csv(plan))
            timings = timings.plus(write_pairs_csv_s=time.perf_counter() - t0)
        summary = plan_summary(plan, source, axis, timings)
        if summary_extra:
            summary.update(summary_extra)
        for name, data in (extra_files or {}).items():
            if isinstance(data, Path):  # written already (core.output.writer.Spooled): moved in
                shutil.move(data, tmp / name)
            elif isinstance(data, CsvChunks):  # (formatted block by block as it is written)
                with open(tmp / name, "wb") as f:
                    for part in data:
                        f.write(part)
            else:
                (tmp / name).write_bytes(data)
        summary["files"] = sorted({p.name for p in tmp.iterdir()} | {"plan.json"})  # (plan_folder_files)
        sources = [] if source.strip().lower() == "sample" else source_parts(source)
        summary["sha256"] = plan_digests(tmp, summary["files"], summary["inputs"], sources)
        (tmp / "plan.json").write_text(json.dumps(summary, indent=1))
    return Path(out_dir)


CL_COLUMNS = "t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k".split(",")


def cl_csv_chunks(t: np.ndarray, samples) -> CsvChunks:
    """left_cl.csv / right_cl.csv: one row per time sample (t in ms, tip in mm and unit axis, W frame),
    formatted block by block as it is written (core.output.csvio.CsvChunks)."""
    cols = [("f", t, 6), ("i", samples.step, None), ("c", (samples.code, REGION_NAMES), None),
            ("i", samples.path, None),
            ("i", samples.cutting.astype(np.int64), None)]
    cols += [("f", samples.tips[:, j], 10) for j in range(3)]
    cols += [("f", samples.axes[:, j], 9) for j in range(3)]
    return CsvChunks(CL_COLUMNS, cols)


def cl_csv(t: np.ndarray, samples) -> bytes:
    """The text of ``cl_csv_chunks`` as one bytes object."""
    return bytes(cl_csv_chunks(t, samples))


AXES_COLUMNS = "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3".split(",")


def axes_csv_chunks(table: AxisTable) -> CsvChunks:
    """left_axes.csv / right_axes.csv: t in ms, axis values in mm to 1e-6, velocities in mm/ms to 1e-9;
    formatted block by block as it is written (core.output.csvio.CsvChunks)."""
    cols = [("f", table.t, 6)]
    cols += [("f", table.values[:, k], 6) for k in range(6)]
    cols += [("f", table.velocities[:, k], 9) for k in range(6)]
    return CsvChunks(AXES_COLUMNS, cols)


def axes_csv(table: AxisTable) -> bytes:
    """The text of ``axes_csv_chunks`` as one bytes object."""
    return bytes(axes_csv_chunks(table))


# -- The plan folder: what one is, and writing one atomically ----------------------------------------

#: the files of a plan folder written before plan.json listed them (its "files"): pairs.csv and
#: plan.json, and any of the others, nothing else
LEGACY_REQUIRED = frozenset({"pairs.csv", "plan.json"})
LEGACY_FILES = LEGACY_REQUIRED | {"left_cl.csv", "right_cl.csv", "left_axes.csv", "right_axes.csv",
                                   "machine.toml"}
_MAX_SUMMARY = 64 << 20  # (a plan.json larger than this is not one bladecam wrote)


def _few(names) -> str:
    return ", ".join(sorted(names)[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")


def plan_folder_files(folder: Path) -> tuple[set[str] | None, str]:
    """(its file names, "") if ``folder`` is empty or provably a plan folder bladecam wrote, else
    (None, why not). A plan folder holds regular files only: exactly those its plan.json lists under
    "files" (a JSON object with "bladecam_version"); without that list (written by an earlier
    version), pairs.csv, plan.json and any of LEGACY_FILES, nothing else."""
    try:
        entries = list(os.scandir(folder))
    except OSError as exc:
        return None, f"it cannot be read ({exc.strerror or exc})"
    names = {e.name for e in entries}
    if not names:
        return names, ""
    odd = {e.name for e in entries if not e.is_file(follow_symlinks=False)}
    summary, why = None, []
    try:
        if "plan.json" in names - odd and (folder / "plan.json").stat().st_size <= _MAX_SUMMARY:
            summary = json.loads((folder / "plan.json").read_bytes())
    except (OSError, ValueError, RecursionError):  # (unreadable, not UTF-8, not JSON)
        pass
    if "plan.json" not in names:
        why.append("it has no plan.json")
    elif not isinstance(summary, dict) or "bladecam_version" not in summary:
        why.append("its plan.json is not one bladecam wrote (no bladecam_version)")
    manifest = summary.get("files") if isinstance(summary, dict) else None
    if manifest is None:  # (an earlier version's plan folder, or none)
        listed = names & LEGACY_FILES
        if not why and not LEGACY_REQUIRED <= names:
            why.append(f"{_few(LEGACY_REQUIRED - names)} missing")
    elif isinstance(manifest, list) and all(isinstance(n, str) for n in manifest):
        listed = set(manifest)
        if listed - names:
            why.append(f"{_few(listed - names)} listed in its plan.json missing")
    else:
        listed = set()
        why.append("its plan.json's file list is malformed")
    foreign = (names - listed) | odd
    if foreign:
        why.append(f"it holds {_few(foreign)}, which bladecam did not write")
    return (None, "; ".join(why)) if why else (names, "")


def _refusal(out: Path) -> str | None:
    """Why ``out`` must not be replaced by a plan folder (None: it may be)."""
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        return f"{out} exists and is not a folder; choose another folder"
    if out.is_dir():
        files, why = plan_folder_files(out)
        if files is None:
            return (f"{out} is not a bladecam plan folder: {why}. Nothing in it is ever deleted or "
                    "replaced: choose an empty or new folder, or move those files out")
    return None


#: the longest scratch-folder name a plan folder's name is kept whole in (bytes): the file systems' limit
#: is 255, and .NAME.tmp-PID@HOST-RANDOM adds up to about 45 more
SCRATCH_NAME_MAX = 160


def scratch_stem(name: str) -> str:
    """The plan folder's name as its scratch folders carry it (.STEM.tmp-..., .STEM.old-...,
    .STEM.export-...): the name itself when short, else its start and a digest of the whole, so that a
    folder name up to the file system's limit still has room for what the scratch name adds."""
    if len(name.encode()) <= SCRATCH_NAME_MAX:
        return name
    import hashlib

    digest = hashlib.sha256(name.encode()).hexdigest()[:16]
    head = name.encode()[:SCRATCH_NAME_MAX - 17].decode("utf-8", "ignore")
    return f"{head}~{digest}"


def _name_problem(out: Path) -> str | None:
    """Why the path ``out`` is too long for the file system (None: it is not): a name longer than the
    folder's NAME_MAX, or a path longer than PATH_MAX."""
    base = out.parent
    while not base.is_dir() and base.parent != base:
        base = base.parent
    try:
        name_max, path_max = os.pathconf(base, "PC_NAME_MAX"), os.pathconf(base, "PC_PATH_MAX")
    except (OSError, ValueError):
        name_max, path_max = 255, 4096
    long = [part for part in out.parts if len(part.encode()) > name_max]
    if long:
        return (f"the folder name {long[0][:40]}... is {len(long[0].encode())} bytes long, beyond the file "
                f"system's limit of {name_max} for one name; choose a shorter name")
    if len(str(out).encode()) >= path_max:
        return (f"the output path is {len(str(out).encode())} bytes long, beyond the file system's limit of "
                f"{path_max} for a path; choose a shorter one")
    return None


def _inside_plan(out: Path) -> Path | None:
    """The plan folder ``out`` would lie inside (None: none of its parents is one): a plan folder in a
    plan folder makes the outer one fail its own check (a file it does not list)."""
    for parent in out.parents:
        if (parent / "plan.json").is_file():
            files, _ = plan_folder_files(parent)
            if files:
                return parent
    return None


def check_destination(out_dir: str | Path) -> Path:
    """The rule for an output folder, applied before any work (``bladecam plan``, the workbench's
    export) and again by atomic_folder: what killed runs left beside it is cleared first and a plan
    one left hidden is put back (sweep_scratch); then ``out_dir`` must be missing, an empty folder or
    a plan folder bladecam wrote (plan_folder_files), and its parent a folder this process may write
    into or create. Returns the resolved path; OutputError when refused (nothing of it is touched)."""
    try:
        out = Path(out_dir).resolve()
    except (OSError, RuntimeError) as exc:  # (a symlink loop, a name too long)
        raise OutputError(f"{str(out_dir)[:80]} cannot be used as the output folder: "
                          f"{_name_problem(Path(os.path.abspath(out_dir))) or exc}") from None
    too_long = _name_problem(out)
    if too_long is not None:
        raise OutputError(too_long)
    holder = _inside_plan(out)
    if holder is not None:
        raise OutputError(f"{out} lies inside the plan folder {holder}, which would then hold a file it does "
                          "not list (bladecam verify refuses it); choose a folder outside it")
    if out.parent.is_dir():
        sweep_scratch(out.parent, out.name)  # (a killed run's leftovers; its hidden plan put back)
    reason = _refusal(out)
    if reason is not None:
        raise OutputError(reason)
    base = out.parent
    while not base.exists() and not base.is_symlink() and base.parent != base:
        base = base.parent
    if not base.is_dir():
        raise OutputError(f"cannot write into {out.parent}: {base} is not a folder; choose another folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write into {base}: no permission, or a read-only file system; "
                          "choose another folder")
    return out


_SCRATCH = re.compile(r"^\.(?:bladecam-spool-(\d{1,10})@([A-Za-z0-9_.]+)-.*"
                      r"|(.+)\.(tmp|old|export)-(\d{1,10})@([A-Za-z0-9_.]+)(?:-.*)?)$")


def _scratch(parent: Path, name: str | None) -> list[tuple[Path, str, int, str]]:
    """(path, kind, pid, host) of the scratch folders in ``parent`` (see sweep_scratch)."""
    try:
        entries = list(parent.iterdir())
    except OSError:
        return []
    found = []
    for entry in entries:
        m = _SCRATCH.match(entry.name)
        if m is not None and m.group(1) is not None:
            found.append((entry, "spool", int(m.group(1)), m.group(2)))
        elif m is not None and m.group(3) == scratch_stem(name or ""):
            found.append((entry, m.group(4), int(m.group(5)), m.group(6)))
    return found


def restore_plan(out_dir: str | Path) -> Path | None:
    """Put back the plan a run killed between atomic_folder's two renames left hidden beside a
    missing ``out_dir`` (.NAME.old-PID@HOST, moved aside complete), when that run no longer runs;
    returns the folder put back (None: nothing to do). No age guard here: if its process still ran
    unseen (another pid namespace), its second rename would fail on the restored folder and it would
    report that nothing was written; nothing is lost either way, and the plan is visible at once."""
    out = Path(out_dir)
    if out.exists() or out.is_symlink():
        return None
    hidden = [e for e, kind, pid, where in _scratch(out.parent, out.name)
              if kind == "old" and abandoned(e, pid, where, age_guard=False)]
    for entry in sorted(hidden, key=_changed, reverse=True):  # (the newest first)
        try:
            os.replace(entry, out)
            return entry
        except OSError:
            continue
    return None


def _changed(path: Path) -> float:
    try:
        return path.stat().st_ctime
    except OSError:
        return 0.0


def _remove_plan_folder(folder: Path) -> bool:
    """Remove a plan folder bladecam wrote, file by file (plan_folder_files); anything else is left."""
    files, _ = plan_folder_files(folder)
    if files is None:
        return False
    for name in files:
        (folder / name).unlink(missing_ok=True)
    os.rmdir(folder)  # (fails if a file appeared meanwhile: it stays)
    return True


def sweep_scratch(parent: str | Path, name: str | None = None) -> list[Path]:
    """Clear what a bladecam process killed outright (SIGKILL, a power cut) left in ``parent``: its
    helpers' scratch folders (.bladecam-spool-PID@HOST-*) and, for the plan folder ``name``, its
    unfinished copy (.NAME.tmp-PID@HOST-*) or the workbench's export staging (.NAME.export-PID@HOST-*)
    are removed; the previous plan it had moved aside (.NAME.old-PID@HOST) is put back as NAME if NAME
    is missing (restore_plan), else removed (only a plan folder's own files). Only folders of
    processes that no longer run are touched (core.util.scratch.abandoned: at once for this boot and
    pid namespace, else after SWEEP_AGE_S). Returns the paths removed or restored (best effort)."""
    parent = Path(parent)
    done = []
    if name is not None and (back := restore_plan(parent / name)) is not None:
        done.append(back)
    for entry, kind, pid, where in _scratch(parent, name):
        try:
            if entry in done or not abandoned(entry, pid, where):
                continue
            if kind == "old":
                if not (parent / name).exists() or not _remove_plan_folder(entry):
                    continue
            else:
                shutil.rmtree(entry)
            done.append(entry)
        except Exception:  # noqa: BLE001 - best effort: a folder that cannot be cleared stays
            continue
    return done


def new_folder(parent: Path, prefix: str) -> Path:
    """A new folder parent/PREFIX<random>, made by mkdir: its mode follows the umask (and a default
    ACL) as any folder the user makes (tempfile.mkdtemp's are 0700). OSError when it cannot be made."""
    for _ in range(100):
        path = parent / f"{prefix}{secrets.token_hex(4)}"
        try:
            path.mkdir()
            return path
        except FileExistsError:
            continue
    raise FileExistsError(f"no free name {prefix}* in {parent}")


@contextlib.contextmanager
def atomic_folder(out_dir: str | Path, check: Callable[[Path], None] | None = None) -> Iterator[Path]:
    """Yield a temporary folder to write into; on success it replaces ``out_dir`` atomically, once
    ``check(folder)`` (when given) has passed on it: an exception it raises leaves ``out_dir`` as it was.

    ``out_dir`` must pass check_destination (an existing folder is replaced only if it is empty or a
    plan folder bladecam wrote, checked again just before the swap); otherwise OutputError, and
    nothing is touched. On any exception the temporary folder is removed and ``out_dir`` is left as
    it was. The new folder's mode follows the umask (new_folder).
    """
    out = check_destination(out_dir)
    parent = out.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = new_folder(parent, f".{scratch_stem(out.name)}.tmp-{scratch_owner()}-")
    except OSError as exc:
        raise OutputError(f"cannot write into {parent}: {exc.strerror or exc}") from None
    try:
        yield tmp
        if check is not None:
            check(tmp)
        old = None
        if out.exists() or out.is_symlink():
            reason = _refusal(out)  # (the folder may have changed while the plan was made)
            if reason is not None:
                raise OutputError(reason)
            old = parent / f".{scratch_stem(out.name)}.old-{scratch_owner()}"
            if old.exists():
                _remove_plan_folder(old)
            os.replace(out, old)
        try:
            os.replace(tmp, out)
        except OSError:
            if old is not None:
                os.replace(old, out)
            raise
        if old is not None:
            with contextlib.suppress(OSError):
                _remove_plan_folder(old)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise OutputError(f"cannot write the plan to {out}: {exc.strerror or exc}") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
