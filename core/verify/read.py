"""What ``bladecam verify`` reads: the plan folder's tables parsed quickly (and independently of
core.output, which writes them).

The tables (SPEC.md section 10): pairs.csv, left_cl.csv / right_cl.csv, left_axes.csv / right_axes.csv.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from core.errors import OutputError
from core.paths.regions import REGION_CODE

#: region names as they appear in the tables -> their codes (core.paths.regions, the one region table)
REGION_CODES = {name.encode(): code for name, code in REGION_CODE.items()}
CL_HEADER = "t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k"
AXES_HEADER = "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3"
#: pairs.csv's columns; sym_spacing_mm (a 17th) is optional: a plan of an earlier version lacks it
PAIRS_HEADER = "path,k,region,xL,yL,zL,iL,jL,kL,xR,yR,zR,iR,jR,kR,spacing_mm"

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


def read_table(path: str | Path, header: str, ncols: int | None = None, words: bool = False) -> np.ndarray:
    """An (n, ncols) float table under ``header`` (``ncols``: its number of names unless given; a
    header may then carry more names than ``header`` lists), region names as their REGION_CODES when
    ``words``. OutputError names the file (and line) when it is missing, has another header, a cell
    that is not a finite number, or no rows."""
    path = Path(path)
    if not path.is_file():
        raise OutputError(f"{path} is missing: not a complete plan folder")
    head, _, body = path.read_bytes().partition(b"\n")
    names = head.decode("utf-8", "replace").strip()
    ncols = ncols or len(header.split(","))
    if not names.startswith(header) or len(names.split(",")) != ncols:
        raise OutputError(f"{path}: unexpected header {head[:120]!r}; expected {header}")
    coded = _words_to_codes(body, REGION_CODES) if words else body
    a = parse_fixed_chunked(coded, ncols) if coded is not None else None
    if a is None:  # not plain fixed-point decimals: the general parser names the bad line
        if words:
            for name, code in REGION_CODES.items():
                body = body.replace(b"," + name + b",", b"," + str(code).encode() + b",")
        try:
            a = np.loadtxt(io.BytesIO(body), delimiter=",", ndmin=2)
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


def read_cl(path: str | Path) -> dict[str, np.ndarray]:
    """One CL table: t (n,) ms, step, region (REGION_CODES), path (n,) int, cutting (n,) bool, p (n, 3)
    tips mm and w (n, 3) axes, W frame."""
    a = read_table(path, CL_HEADER, words=True)
    return {"t": a[:, 0], "step": a[:, 1].astype(int), "region": a[:, 2].astype(int),
            "path": a[:, 3].astype(int), "cutting": a[:, 4] > 0.5, "p": a[:, 5:8], "w": a[:, 8:11]}


def read_pairs(path: str | Path) -> dict[str, np.ndarray]:
    """pairs.csv: path, k (m,) int, region (m,) REGION_CODES, left/right tips (m, 3) mm and axes (m, 3),
    in the file's order."""
    head = Path(path).read_bytes()[:400].partition(b"\n")[0] if Path(path).is_file() else b""
    ncols = 17 if head.decode("utf-8", "replace").strip().endswith(",sym_spacing_mm") else 16
    a = read_table(path, PAIRS_HEADER, ncols, words=True)
    return {"path": a[:, 0].astype(int), "k": a[:, 1].astype(int), "region": a[:, 2].astype(int),
            "left_tip": a[:, 3:6], "left_axis": a[:, 6:9], "right_tip": a[:, 9:12], "right_axis": a[:, 12:15]}


def read_axes(path: str | Path) -> np.ndarray:
    """An axis table: (n, 13) t ms, x, y, z, d1, d2, d3 mm, then their velocities mm/ms."""
    return read_table(path, AXES_HEADER)
