"""Fast, exact CSV output, and helper processes that format it while their caller works.

Numbers are written in fixed-point with a chosen number of decimals ('.' decimal point, no
thousands separator, no padding), formatted by one compiled loop (core.output._csvformat, Cython,
built with the package) that releases the GIL: a plan's 100 MB table takes well under a second, and
the two sides' tables are formatted in two threads.

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

try:  # the compiled formatter, built by pip from _csvformat.pyx (setup.py)
    from core.output._csvformat import format_rows as _format_rows
except ImportError:  # (not built: format_block says how to build it; the rest of core works)
    _format_rows = None

#: rows formatted at a time: the text of a block (~10 MB) stays in memory the allocator reuses
BLOCK_ROWS = 1 << 16


def _kernel_columns(columns: Sequence[tuple[str, np.ndarray, int | None]]) -> list:
    """The columns as core.output._csvformat.format_rows takes them (float64 and int64 arrays, names as
    ASCII bytes; a string column as codes into its distinct values)."""
    out = []
    for kind, values, decimals in columns:
        if kind == "f":
            out.append(("f", np.asarray(values, dtype=np.float64), int(decimals or 0)))
        elif kind == "i":
            out.append(("i", np.asarray(values).astype(np.int64, copy=False), 0))
        else:
            if kind == "c":
                codes, names = values
            else:
                names, codes = np.unique(np.asarray(values), return_inverse=True)
            out.append(("c", np.asarray(codes).astype(np.int64, copy=False).ravel(),
                        [str(name).encode("ascii") for name in names]))
    return out


def format_block(columns: Sequence[tuple[str, np.ndarray, int | None]]) -> tuple[bytes, np.ndarray]:
    """The CSV rows (no header) of equal-length columns and the byte offset where each row ends, by
    the compiled formatter (core.output._csvformat). ``columns`` as for ``csv_body``. OutputError for
    a number that cannot be written (not finite, or beyond 2**53 once scaled), naming its row."""
    cols = _kernel_columns(columns)
    lengths = {len(values) for _, values, _ in cols}
    if len(lengths) > 1:
        raise ValueError("columns of different lengths")
    n = lengths.pop() if lengths else 0
    if _format_rows is None:
        raise OutputError("the compiled CSV formatter (core.output._csvformat) is not built: run "
                          "`pip install -e .` (or `make venv`) in the project folder")
    try:
        return _format_rows(cols, n)
    except ValueError as exc:
        raise OutputError(f"refusing to write the table: {exc}") from None


def csv_body(columns: Sequence[tuple[str, np.ndarray, int | None]], head: bytes = b"") -> tuple[bytes, np.ndarray]:
    """CSV rows (no header) of equal-length columns, and the byte offset where each row ends.

    columns : (kind, values, decimals) with kind 'f' (float, fixed decimals), 'i' (integer), 's'
    (string without commas) or 'c' (strings as codes: values = (codes, names), names indexed by the
    codes). Numbers are written in fixed point: v * 10**decimals rounded half to even, '-' only when
    that is negative, at least one digit before the point (core.output._csvformat). Rows end with
    '\n'. ``head`` (a header line) is put before the rows; the offsets count from the first row.
    """
    _checked(columns)
    body, ends = format_block(columns)
    return head + body if head else body, ends


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


class CsvChunks:
    """The text of ``csv_bytes`` as it is formatted, block by block, for writing a file without holding
    all of it (a plan's table is ~100 MB of text): iterate for the bytes of the header, then of each
    block of BLOCK_ROWS rows (each iteration formats them again), or ``bytes()`` for the whole text.
    The columns are checked when it is made (OutputError for a non-finite number)."""

    def __init__(self, header: Sequence[str], columns: Sequence[tuple[str, np.ndarray, int | None]]):
        self.head = (",".join(header) + "\n").encode()
        self.columns = columns
        self.n = _checked(columns)

    def __iter__(self) -> Iterator[bytes]:
        yield self.head
        for lo in range(0, self.n, BLOCK_ROWS):
            hi = lo + BLOCK_ROWS
            yield format_block([(kind, (values[0][lo:hi], values[1]) if kind == "c" else values[lo:hi], d)
                                for kind, values, d in self.columns])[0]

    def __bytes__(self) -> bytes:
        return b"".join(self)

    def as_written(self, words: dict[bytes, int]) -> np.ndarray:
        """(n, ncols) float64: the values a reader of this text gets, without formatting it: a
        number with d decimals as rint(v * 10**d) / 10**d (the formatter's integer over 10**d: the
        double nearest the decimal written, as an exact reader parses it), an integer as itself, a
        name as ``words[name]``. KeyError for a name not in ``words``."""
        cols = _kernel_columns(self.columns)
        out = np.empty((self.n, len(cols)), dtype=np.float64)
        for j, (kind, values, extra) in enumerate(cols):
            if kind == "f":
                scale = 10.0 ** extra
                np.divide(np.rint(values * scale), scale, out=out[:, j])
            elif kind == "i":
                out[:, j] = values
            else:
                out[:, j] = np.array([words[name] for name in extra], dtype=np.float64)[values]
        return out


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
