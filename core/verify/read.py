"""What ``bladecam verify`` reads: the plan folder's tables, each parsed once by verify's own compiled
reader (core.verify._tables, independent of core.output, which writes them), or given as the rows a
plan holds in memory, exactly as written (``Tables``).

The tables (SPEC.md section 10): pairs.csv, left_cl.csv / right_cl.csv, left_axes.csv / right_axes.csv.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from core.errors import OutputError
from core.paths.regions import REGION_CODE
from core.verify._tables import parse_rows

#: region names as they appear in the tables -> their codes (core.paths.regions, the one region table)
REGION_CODES = {name.encode(): code for name, code in REGION_CODE.items()}
CL_HEADER = "t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k"
AXES_HEADER = "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3"
#: pairs.csv's columns; sym_spacing_mm (a 17th) is optional: a plan of an earlier version lacks it
PAIRS_HEADER = "path,k,region,xL,yL,zL,iL,jL,kL,xR,yR,zR,iR,jR,kR,spacing_mm"


def read_table(path: str | Path, header: str, ncols: int | None = None, words: bool = False) -> np.ndarray:
    """An (n, ncols) float table under ``header`` (``ncols``: its number of names unless given; a
    header may then carry more names than ``header`` lists), region names as their REGION_CODES when
    ``words``. OutputError names the file (and line) when it is missing, has another header, a cell
    that is not a finite number, or no rows."""
    path = Path(path)
    if not path.is_file():
        raise OutputError(f"{path} is missing: not a complete plan folder")
    data = path.read_bytes()
    end = data.find(b"\n")
    head, body = (data, b"") if end < 0 else (data[:end], memoryview(data)[end + 1:])  # (the body not copied)
    names = head.decode("utf-8", "replace").strip()
    ncols = ncols or len(header.split(","))
    if not names.startswith(header) or len(names.split(",")) != ncols:
        raise OutputError(f"{path}: unexpected header {head[:120]!r}; expected {header}")
    a, bad = parse_rows(body, ncols, REGION_CODES if words else {})
    if bad != -1:  # not plain fixed-point decimals: the general parser names the bad line
        text = bytes(body)
        if words:
            for name, code in REGION_CODES.items():
                text = text.replace(b"," + name + b",", b"," + str(code).encode() + b",")
        try:
            a = np.loadtxt(io.BytesIO(text), delimiter=",", ndmin=2)
        except ValueError as exc:
            raise OutputError(f"{path}: {exc}") from None
        if a.shape[1] != ncols:
            raise OutputError(f"{path}: rows do not all have {ncols} columns")
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if bad.size:  # (the fast parser reads digits only: nan and inf reach the general one)
            raise OutputError(f"{path}, line {int(bad[0]) + 2}: a cell is not a finite number "
                              f"({bad.size} such rows): not a table bladecam wrote")
    if len(a) == 0:
        raise OutputError(f"{path}: no rows under its header: not a complete plan folder")
    return a


#: the tables of a plan folder: file name -> (its header, whether its cells hold region names)
TABLES = {"left_cl.csv": (CL_HEADER, True), "right_cl.csv": (CL_HEADER, True),
          "left_axes.csv": (AXES_HEADER, False), "right_axes.csv": (AXES_HEADER, False),
          "pairs.csv": (PAIRS_HEADER, True)}


def table_rows(folder: str | Path, name: str, given: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """The (n, ncols) rows of the folder's table ``name`` (one of TABLES): ``given[name]`` when the
    caller holds them (a plan verified before it is written: the rows exactly as written, region names
    as their REGION_CODES; or a function making them, called here), else parsed from the file
    (``read_table``)."""
    if given is not None and name in given:
        rows = given[name]
        return rows() if callable(rows) else rows
    header, words = TABLES[name]
    path = Path(folder) / name
    ncols = None
    if name == "pairs.csv":  # (sym_spacing_mm, a 17th column, is optional: an earlier version's plan)
        head = path.read_bytes()[:400].partition(b"\n")[0] if path.is_file() else b""
        ncols = 17 if head.decode("utf-8", "replace").strip().endswith(",sym_spacing_mm") else 16
    return read_table(path, header, ncols, words=words)


def cl_columns(a: np.ndarray) -> dict[str, np.ndarray]:
    """One CL table's rows (n, 11) as t (n,) ms, step, region (REGION_CODES), path (n,) int, cutting
    (n,) bool, p (n, 3) tips mm and w (n, 3) axes, W frame."""
    return {"t": a[:, 0], "step": a[:, 1].astype(int), "region": a[:, 2].astype(int),
            "path": a[:, 3].astype(int), "cutting": a[:, 4] > 0.5, "p": a[:, 5:8], "w": a[:, 8:11]}


def pairs_columns(a: np.ndarray) -> dict[str, np.ndarray]:
    """pairs.csv's rows (m, 16 or 17) as path, k (m,) int, region (m,) REGION_CODES, left/right tips
    (m, 3) mm and axes (m, 3), in the file's order."""
    return {"path": a[:, 0].astype(int), "k": a[:, 1].astype(int), "region": a[:, 2].astype(int),
            "left_tip": a[:, 3:6], "left_axis": a[:, 6:9], "right_tip": a[:, 9:12], "right_axis": a[:, 12:15]}


def read_cl(path: str | Path) -> dict[str, np.ndarray]:
    """One CL table file (``cl_columns``)."""
    path = Path(path)
    return cl_columns(table_rows(path.parent, path.name) if path.name in TABLES else
                      read_table(path, CL_HEADER, words=True))


def read_pairs(path: str | Path) -> dict[str, np.ndarray]:
    """pairs.csv (``pairs_columns``)."""
    path = Path(path)
    return pairs_columns(table_rows(path.parent, "pairs.csv") if path.name == "pairs.csv" else
                         read_table(path, PAIRS_HEADER, words=True))


def read_axes(path: str | Path) -> np.ndarray:
    """An axis table: (n, 13) t ms, x, y, z, d1, d2, d3 mm, then their velocities mm/ms."""
    return read_table(path, AXES_HEADER)
