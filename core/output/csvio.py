"""Fast, exact CSV output, and helper processes that format it while their caller works.

Numbers are written in fixed-point with a chosen number of decimals ('.' decimal point, no
thousands separator, no padding), formatted by vectorised integer arithmetic instead of one Python
format call per value, so that hundreds of thousands of rows take a fraction of a second.

``Helper`` runs jobs in a forked process that dies with its caller; its files go into a scratch folder
named with the caller (``spool_folder``; core.output.files.sweep_scratch clears it after a kill).
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import pickle
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from core.errors import BladecamError, OutputError
from core.util.scratch import die_with_parent, scratch_owner

_PAD = 0
#: "0000" .. "9999" as ASCII: digits are cut four at a time
_DIGITS4 = np.frombuffer("".join(f"{i:04d}" for i in range(10000)).encode(), dtype=np.uint32)


class _Field:
    """One column laid out right-aligned in ``width`` bytes per row (0 = padding, removed at the end):
    ``lengths`` (n,) the characters each row really uses; ``fill(view)`` writes the (n, width) block."""

    def __init__(self, width: int, lengths: np.ndarray, fill):
        self.width, self.lengths, self.fill = width, lengths, fill


def _fixed_field(values: np.ndarray, decimals: int, integers: bool = False) -> _Field:
    """Numbers in fixed point with ``decimals`` decimals ('-' only when the rounded value is negative)."""
    if integers:
        scaled = np.asarray(values).astype(np.int64)
    else:
        values = np.asarray(values, float)
        scaled = np.rint(values * 10.0**decimals).astype(np.int64)
    neg = scaled < 0
    mag = np.abs(scaled)
    ndig = max(len(str(int(mag.max(initial=0)))), decimals + 1)
    # digits each value needs (at least one before the dot), by exact integer comparisons
    need = np.full(len(mag), decimals + 1, dtype=np.int64)
    for k in range(decimals + 1, ndig):
        need += mag >= 10**k
    dot = 1 if decimals else 0
    m = ndig - decimals                  # integer digit columns
    lead = m - (need - decimals)         # blank (leading zero) columns of the integer part, per row

    def fill(view: np.ndarray) -> None:
        groups = -(-ndig // 4)
        rest = mag
        chunks = np.empty((len(mag), groups), dtype=np.int64)
        for g in range(groups - 1, -1, -1):      # least significant group last
            rest, chunks[:, g] = np.divmod(rest, 10000)
        digits = _DIGITS4.take(chunks).view(np.uint8)[:, 4 * groups - ndig:]
        block = np.zeros((len(mag), 1 + ndig + dot), dtype=np.uint8)  # contiguous, copied once
        block[:, 1:1 + m] = digits[:, :m]
        for j in range(m - 1):                   # blank the leading zeros
            block[lead > j, 1 + j] = _PAD
        if decimals:
            block[:, 1 + m] = 46  # '.'
            block[:, 2 + m:] = digits[:, m:]
        rows = np.flatnonzero(neg)
        block[rows, lead[rows]] = 45  # '-' just before the first digit
        view[:] = block

    return _Field(1 + ndig + dot, need + dot + neg, fill)


def _names_field(codes: np.ndarray, names: Sequence[str]) -> _Field:
    """Strings given as indices into ``names`` (left-aligned)."""
    table = np.asarray([str(s) for s in names]).astype("S")
    width = max(table.dtype.itemsize, 1)
    lut = np.frombuffer(table.tobytes(), dtype=np.uint8).reshape(len(table), width)
    lengths = np.array([len(s) for s in table], dtype=np.int64)
    codes = np.asarray(codes, np.int64)

    def fill(view: np.ndarray) -> None:
        view[:] = lut[codes]

    return _Field(width, lengths[codes], fill)


def _str_field(values: Sequence[str] | np.ndarray) -> _Field:
    names, codes = np.unique(np.asarray(values), return_inverse=True)
    return _names_field(codes.ravel(), names)


#: rows formatted at a time: the byte table of a block (~10 MB) stays in memory the allocator reuses
BLOCK_ROWS = 1 << 16


def csv_body(columns: Sequence[tuple[str, np.ndarray, int | None]], head: bytes = b"") -> tuple[bytes, np.ndarray]:
    """CSV rows (no header) of equal-length columns, and the byte offset where each row ends.

    columns : (kind, values, decimals) with kind 'f' (float, fixed decimals), 'i' (integer), 's'
    (string without commas) or 'c' (strings as codes: values = (codes, names), names indexed by the
    codes). Rows end with '\n'. Each column is laid out right-aligned in a fixed-width block of
    one byte table, BLOCK_ROWS rows at a time; the padding bytes are deleted in one pass per block.
    ``head`` (a header line) is put before the rows in the same copy; the offsets count from the
    first row.
    """
    parts, ends, offset = [head], [], 0
    for data, row_ends in _blocks(columns):
        parts.append(data)
        ends.append(row_ends + offset)
        offset += len(data)
    if not ends:
        return head, np.zeros(0, dtype=np.int64)
    return b"".join(parts), np.concatenate(ends)


def _checked(columns: Sequence[tuple[str, np.ndarray, int | None]]) -> int:
    """The columns' common length; ValueError for different lengths, OutputError for a non-finite
    number (before anything is formatted)."""
    lengths = {len(values[0] if kind == "c" else values) for kind, values, _ in columns}
    if len(lengths) > 1:
        raise ValueError("columns of different lengths")
    n = lengths.pop() if lengths else 0
    for kind, values, _ in columns:
        if kind == "f" and n and not np.isfinite(values).all():
            i = int(np.argmax(~np.isfinite(np.asarray(values, float))))
            raise OutputError(f"refusing to write a non-finite number (row {i})")
    return n


def _blocks(columns: Sequence[tuple[str, np.ndarray, int | None]], n: int | None = None
            ) -> Iterator[tuple[bytes, np.ndarray]]:
    """(bytes, row ends) of each block of BLOCK_ROWS rows (csv_body); the columns are checked first
    unless their length ``n`` is given (checked already)."""
    n = _checked(columns) if n is None else n
    for lo in range(0, n, BLOCK_ROWS):
        hi = lo + BLOCK_ROWS
        yield _block([(kind, (values[0][lo:hi], values[1]) if kind == "c" else values[lo:hi], decimals)
                      for kind, values, decimals in columns])


class CsvChunks:
    """The text of ``csv_bytes`` as it is formatted, block by block, for writing a file without holding
    all of it (a plan's table is ~100 MB of text): iterate for the bytes
    of the header, then of each block of rows (each iteration formats them again), or ``bytes()`` for
    the whole text. The columns are checked when it is made (OutputError for a non-finite number)."""

    def __init__(self, header: Sequence[str], columns: Sequence[tuple[str, np.ndarray, int | None]]):
        self.head = (",".join(header) + "\n").encode()
        self.columns = columns
        self.n = _checked(columns)

    def __iter__(self) -> Iterator[bytes]:
        yield self.head
        for data, _ in _blocks(self.columns, self.n):
            yield data

    def __bytes__(self) -> bytes:
        return b"".join(self)


def _block(columns: Sequence[tuple[str, np.ndarray, int | None]]) -> tuple[bytes, np.ndarray]:
    """csv_body for one block of rows."""
    fields = []
    for kind, values, decimals in columns:
        if kind == "f":
            fields.append(_fixed_field(values, int(decimals or 0)))
        elif kind == "i":
            fields.append(_fixed_field(values, 0, integers=True))
        elif kind == "c":
            fields.append(_names_field(*values))
        else:
            fields.append(_str_field(values))
    n = len(fields[0].lengths)
    table = np.zeros((n, sum(f.width + 1 for f in fields)), dtype=np.uint8)
    at = 0
    for j, field in enumerate(fields):
        field.fill(table[:, at:at + field.width])
        at += field.width
        table[:, at] = 10 if j == len(fields) - 1 else 44
        at += 1
    row_ends = np.cumsum(sum(f.lengths for f in fields) + len(fields))
    return table.tobytes().translate(None, bytes([_PAD])), row_ends


def csv_bytes(header: Sequence[str], columns: Sequence[tuple[str, np.ndarray, int | None]]) -> bytes:
    """CSV text with a header row: see ``csv_body`` for the columns."""
    return csv_body(columns, (",".join(header) + "\n").encode())[0]


def split_rows(body: bytes, row_ends: np.ndarray, counts: Sequence[int]) -> list[bytes]:
    """Cut a CSV body into consecutive blocks of ``counts`` rows each."""
    ends = np.concatenate([[0], row_ends])[np.cumsum(np.concatenate([[0], counts]))]
    return [body[a:b] for a, b in zip(ends[:-1], ends[1:], strict=True)]


def spool_folder(parent: str | Path) -> Path:
    """A new scratch folder in ``parent`` for files written ahead of a plan folder, named with this
    process (.bladecam-spool-PID@HOST-*: core.output.files.sweep_scratch clears it after a kill).
    OSError when it cannot be made."""
    return Path(tempfile.mkdtemp(prefix=f".bladecam-spool-{scratch_owner()}-", dir=parent))


class Helper:
    """Jobs [(name, function, args), ...] run in a forked process from the moment the Helper is made
    (workers > 1 and fork available; else in the caller when it asks for the results), while the
    caller works. ``results()`` returns {name: value}: bytes as they are (formatted tables; no
    pickling of 60 MB), anything else pickled. A job that raises a bladecam error raises the same
    error in the caller; another failure, or a helper that dies, is an OutputError naming the job.
    ``close()`` (always call it) ends the helper, finished or not.

    ``spool_in``: a folder (on the file system the results will be written to) in which the helper
    writes its bytes results into a scratch folder of its own instead of sending them back:
    ``results()`` then gives their Paths, to be moved (renamed) into place; ``close()`` removes the
    scratch folder with whatever is left in it. Without the folder (missing, not writable) the
    results come back as bytes."""

    def __init__(self, jobs: list, workers: int, doing: str = "formatting",
                 spool_in: str | Path | None = None):
        self.jobs, self.doing = jobs, doing
        self.proc = self.recv = self.spool = None
        if workers <= 1 or "fork" not in mp.get_all_start_methods():
            return
        if spool_in is not None:
            try:
                self.spool = spool_folder(spool_in)
            except OSError:
                self.spool = None
        spool = self.spool
        ctx = mp.get_context("fork")
        self.recv, send = ctx.Pipe(duplex=False)
        parent = os.getpid()

        def child() -> None:
            die_with_parent(parent)  # (a kill -9 of the caller ends its helpers too)
            try:
                for name, fn, args in jobs:
                    value = fn(*args)
                    if spool is not None and isinstance(value, (bytes, CsvChunks)):
                        with open(spool / name, "wb") as f:
                            for part in ([value] if isinstance(value, bytes) else value):
                                f.write(part)
                        send.send_bytes(b"\0file:" + os.fsencode(spool / name))
                        continue
                    if isinstance(value, CsvChunks):
                        value = bytes(value)
                    send.send_bytes(value if isinstance(value, bytes) else b"\0pickle:" + pickle.dumps(value, 5))
            except BladecamError as exc:
                send.send_bytes(b"\0raise:" + pickle.dumps(exc))
            except BaseException as exc:  # noqa: BLE001 - reported to the parent, which raises
                send.send_bytes(b"\0error:" + repr(exc).encode())
            finally:
                send.close()

        try:
            self.proc = ctx.Process(target=child, daemon=True)
            self.proc.start()
        except BaseException:  # (no process: nothing of this helper is left behind)
            self.proc = None
            self.recv.close()
            if self.spool is not None:
                shutil.rmtree(self.spool, ignore_errors=True)
            raise
        finally:
            send.close()

    def results(self) -> dict:
        """{name: value}; a job's CsvChunks comes as bytes (or as the Path of the file written)."""
        if self.proc is None:
            out = {name: fn(*args) for name, fn, args in self.jobs}
            return {name: bytes(v) if isinstance(v, CsvChunks) else v for name, v in out.items()}
        out = {}
        for name, _, _ in self.jobs:
            try:
                data = self.recv.recv_bytes()
            except (EOFError, OSError):  # the helper died (killed, out of memory)
                self.proc.join(timeout=5)
                raise OutputError(f"{self.doing} {name} failed: its helper process ended without a "
                                  f"result (exit code {self.proc.exitcode}); nothing was written") from None
            if data.startswith(b"\0raise:"):
                raise pickle.loads(data[7:])
            if data.startswith(b"\0error:"):
                raise OutputError(f"{self.doing} {name} failed: {data[7:].decode(errors='replace')}")
            if data.startswith(b"\0file:"):
                out[name] = Path(os.fsdecode(data[6:]))
            else:
                out[name] = pickle.loads(data[8:]) if data.startswith(b"\0pickle:") else data
        return out

    def close(self) -> None:
        if self.proc is None:
            return
        self.recv.close()
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join(timeout=5)
        self.proc = None
        if self.spool is not None:
            shutil.rmtree(self.spool, ignore_errors=True)
            self.spool = None


@contextlib.contextmanager
def beside(jobs: list, workers: int):
    """A Helper for the jobs while the caller works: yields its ``results``; closed on leaving."""
    helper = Helper(jobs, workers)
    try:
        yield helper.results
    finally:
        helper.close()
