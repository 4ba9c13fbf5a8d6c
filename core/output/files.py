"""Writing a plan folder (SPEC.md section 10): pairs.csv, plan.json (and later CL and axis tables).

All files go through ``csvio.atomic_folder``: the whole set appears, or nothing changes.
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import numpy as np

from core import __version__
from core.machine.postprocess import AxisTable
from core.output.csvio import CsvChunks, atomic_folder, csv_body, split_rows
from core.paths.alignment import AlignedPair
from core.paths.regions import Regions
from core.records import PathPlan, Timings
from core.schedule.motion import REGION_NAMES

PAIRS_COLUMNS = "path,k,region,xL,yL,zL,iL,jL,kL,xR,yR,zR,iR,jR,kR,spacing_mm,sym_spacing_mm".split(",")
DECIMALS = 9


def pairs_rows(pairs: list[AlignedPair], regions: list[Regions]) -> list[bytes]:
    """The rows of pairs.csv (no header) for these paths, one bytes block per path: the pair's tips and
    axes, their distance (spacing_mm) and the signed tip spacing of the symmetrical configuration the
    regions are decided on (sym_spacing_mm, |c_L - c_R| - 2r: negative where the tips have crossed;
    on a tip path, that of the symmetrical pair at the same path-length ratio)."""
    if not pairs:
        return []
    path = np.concatenate([np.full(len(p.u), p.index) for p in pairs])
    k = np.concatenate([np.arange(len(p.u)) for p in pairs])
    region = np.concatenate([r.labels for r in regions])
    arrays = {key: np.concatenate([getattr(p, key) for p in pairs])
              for key in ("left_tip", "left_axis", "right_tip", "right_axis")}
    cols = [("i", path, None), ("i", k, None), ("s", region, None)]
    for key in ("left_tip", "left_axis", "right_tip", "right_axis"):
        cols += [("f", arrays[key][:, j], DECIMALS) for j in range(3)]
    cols.append(("f", np.linalg.norm(arrays["left_tip"] - arrays["right_tip"], axis=1), DECIMALS))
    cols.append(("f", np.concatenate([p.spacing for p in pairs]), DECIMALS))
    body, ends = csv_body(cols)
    return split_rows(body, ends, [len(p.u) for p in pairs])


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
               extra_files: dict[str, bytes] | None = None, summary_extra: dict | None = None) -> Path:
    """Write pairs.csv and plan.json (plus extra files: bytes, or the Path of a file written already,
    which is moved in) atomically into out_dir; plan.json reports ``timings`` (and pairs.csv's write
    when it is written here)."""
    t0 = time.perf_counter()
    with atomic_folder(out_dir) as tmp:
        if not isinstance((extra_files or {}).get("pairs.csv"), Path):  # (else written already)
            (tmp / "pairs.csv").write_bytes(pairs_csv(plan))
            timings = timings.plus(write_pairs_csv_s=time.perf_counter() - t0)
        summary = plan_summary(plan, source, axis, timings)
        if summary_extra:
            summary.update(summary_extra)
        for name, data in (extra_files or {}).items():
            if isinstance(data, Path):  # written already (core.output.csvio.Helper's spool): moved in
                shutil.move(data, tmp / name)
            else:
                (tmp / name).write_bytes(data)
        (tmp / "plan.json").write_text(json.dumps(summary, indent=1))
    return Path(out_dir)


CL_COLUMNS = "t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k".split(",")


def cl_csv_chunks(t: np.ndarray, samples) -> CsvChunks:
    """left_cl.csv / right_cl.csv: one row per time sample (t in ms, tip in mm and unit axis, W frame),
    formatted block by block as it is written (core.output.csvio.CsvChunks)."""
    cols = [("f", t, 6), ("i", samples.step, None), ("c", (samples.code, REGION_NAMES), None), ("i", samples.path, None),
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
