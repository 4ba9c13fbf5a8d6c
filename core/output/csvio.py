"""Fast, exact CSV output and atomic writing of a plan folder.

Numbers are written in fixed-point with a chosen number of decimals ('.' decimal point, no
thousands separator, no padding), formatted by vectorised integer arithmetic instead of one Python
format call per value, so that hundreds of thousands of rows take a fraction of a second.

``atomic_folder`` writes a set of files into a temporary sibling folder and renames it into place:
either the whole set appears or nothing changes; an existing plan folder is replaced only after the
new one is complete, and is restored if the swap fails.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import pickle
import re
import shutil
import socket
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from core.errors import BladecamError, OutputError

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


def scratch_owner() -> str:
    """This process as scratch folder names carry it: pid@host (host reduced to safe characters)."""
    host = re.sub(r"[^A-Za-z0-9_.]", "_", socket.gethostname()) or "host"
    return f"{os.getpid()}@{host}"


def _gone(pid: int) -> bool:
    """True if no process ``pid`` runs on this machine (False if that cannot be told)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError, ValueError):  # (it exists, as another user's; or no such pid)
        return False
    return False


#: scratch folders changed (written, renamed) less than this long ago (s) are never swept: a process
#: that did it may still run unseen (another pid namespace on this host, a clone of this machine);
#: the environment variable BLADECAM_SWEEP_AGE_S sets another age
SWEEP_AGE_S = 600.0
_SCRATCH = re.compile(r"^\.(?:bladecam-spool-(\d{1,10})@([A-Za-z0-9_.]+)-.*"
                      r"|(.+)\.(tmp|old|export)-(\d{1,10})@([A-Za-z0-9_.]+)(?:-.*)?)$")


def sweep_scratch(parent: str | Path, name: str | None = None) -> list[Path]:
    """Clear what a bladecam process killed outright (SIGKILL, a power cut) left in ``parent``: its
    helpers' scratch folders (.bladecam-spool-PID@HOST-*) and, for the plan folder ``name``, its
    unfinished copy (.NAME.tmp-PID@HOST-*) or the workbench's export staging (.NAME.export-PID@HOST-*)
    are removed; the previous plan it had moved aside (.NAME.old-PID@HOST) is put back as NAME if NAME
    is missing (the process died between its two renames), else removed. Only folders of processes of
    this machine that no longer run, unchanged for SWEEP_AGE_S, are touched. Returns the paths removed
    or restored; errors are ignored (best effort)."""
    parent = Path(parent)
    host = scratch_owner().split("@", 1)[1]
    done = []
    try:
        entries = list(parent.iterdir())
    except OSError:
        return done
    now = time.time()
    try:
        age = float(os.environ.get("BLADECAM_SWEEP_AGE_S", SWEEP_AGE_S))
    except ValueError:
        age = SWEEP_AGE_S
    for entry in entries:
        try:
            m = _SCRATCH.match(entry.name)
            if m is None:
                continue
            if m.group(1) is not None:
                pid, where, kind, plan = int(m.group(1)), m.group(2), "spool", None
            else:
                plan, kind, pid, where = m.group(3), m.group(4), int(m.group(5)), m.group(6)
                if plan != name:
                    continue
            if where != host or entry.is_symlink() or not entry.is_dir():
                continue
            st = entry.stat()
            if now - max(st.st_mtime, st.st_ctime) < age or not _gone(pid):  # (a rename sets ctime)
                continue
            if kind == "old" and not (parent / plan).exists():
                os.replace(entry, parent / plan)
            else:
                shutil.rmtree(entry)
            done.append(entry)
        except Exception:  # noqa: BLE001 - best effort: a folder that cannot be cleared stays
            continue
    return done


@contextlib.contextmanager
def atomic_folder(out_dir: str | Path, marker: str = "plan.json") -> Iterator[Path]:
    """Yield a temporary folder to write into; on success it replaces ``out_dir`` atomically.

    An existing ``out_dir`` is replaced only if it is empty or holds ``marker`` (a previous plan);
    otherwise OutputError, and nothing is touched. On any exception the temporary folder is removed
    and ``out_dir`` is left as it was.
    """
    out = Path(out_dir).resolve()
    parent = out.parent
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out} exists and is not a folder; choose another --out")
    if out.is_dir() and any(out.iterdir()) and not (out / marker).exists():
        raise OutputError(f"{out} exists and is not a bladecam plan folder (no {marker}); "
                          "choose an empty or new folder")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        sweep_scratch(parent, out.name)  # (what a killed run left beside this folder)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-{scratch_owner()}-", dir=parent))
    except OSError as exc:
        raise OutputError(f"cannot write into {parent}: {exc.strerror or exc}") from None
    try:
        yield tmp
        old = None
        if out.exists():
            old = parent / f".{out.name}.old-{scratch_owner()}"
            shutil.rmtree(old, ignore_errors=True)
            os.replace(out, old)
        try:
            os.replace(tmp, out)
        except OSError:
            if old is not None:
                os.replace(old, out)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise OutputError(f"cannot write the plan to {out}: {exc.strerror or exc}") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def spool_folder(parent: str | Path) -> Path:
    """A new scratch folder in ``parent`` for files written ahead of a plan folder, named with this
    process (.bladecam-spool-PID@HOST-*: sweep_scratch clears it after a kill), once what killed
    processes left there is cleared. OSError when it cannot be made."""
    sweep_scratch(parent)
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

        def child() -> None:
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
