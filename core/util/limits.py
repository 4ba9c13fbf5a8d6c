"""What a process limit that ended a command was, in one line: the failures the operating system's
limits cause (open files, address space, threads) named as the limit and how to raise it, instead of
the traceback of wherever the limit happened to be reached."""

from __future__ import annotations

import errno
import sys

try:  # (imported up front: with no file descriptor left, no import works)
    import resource
except ImportError:  # (not on Windows)
    resource = None

#: the address space (ulimit -v) below which no plan or verify is started: the imports alone take
#: about 310 MB of it, and the coarsest plan of the sample (dR 8) about 1.5 GB
MIN_ADDRESS_SPACE = 1 << 30

#: open files a plan needs at the most (the path workers' and table helpers' pipes, the files written)
FILES_NEEDED = 256


def _limit(name: str) -> int | None:
    """The soft limit ``resource.RLIMIT_<name>`` of this process (None: unlimited or unknown)."""
    if resource is None:
        return None
    try:
        soft, _ = resource.getrlimit(getattr(resource, f"RLIMIT_{name}"))
    except (AttributeError, OSError, ValueError):
        return None
    return None if soft == resource.RLIM_INFINITY else int(soft)


def _memory() -> str:
    cap = _limit("AS")
    if cap is not None:
        return (f"the address-space limit of this process is {cap / 2**20:,.0f} MB (ulimit -v): a plan at "
                "the defaults needs about 1.5 GB; raise the limit, or plan less (a larger --dr or --dd)")
    return "the machine's memory ran out: close other programs, or plan less (a larger --dr or --dd)"


def address_space_shortfall() -> str | None:
    """The one line refusing to start a plan or a verify in an address space too small for any
    (None: enough, or no limit). Below MIN_ADDRESS_SPACE the first allocation to fail may be one
    that ends the process with no message (OpenBLAS's buffers), so the limit is checked up front."""
    cap = _limit("AS")
    if cap is None or cap >= MIN_ADDRESS_SPACE:
        return None
    return f"out of memory: {_memory()} (and no plan or verify starts in less than {MIN_ADDRESS_SPACE >> 20:,} MB)"


def limit_message(exc: BaseException) -> str | None:
    """The one line for an exception a process limit caused (None: not one of them): too many open
    files (EMFILE, ENFILE), no memory (MemoryError, ENOMEM), no thread or process could be started."""
    if isinstance(exc, MemoryError):
        return f"out of memory: {_memory()}"
    if isinstance(exc, OSError) and exc.errno in (errno.EMFILE, errno.ENFILE):
        cap = _limit("NOFILE")
        if exc.errno == errno.EMFILE and cap is not None:
            return (f"too many open files: this process may open {cap} (ulimit -n), a plan needs up to "
                    f"{FILES_NEEDED}; raise the limit (ulimit -n {max(FILES_NEEDED, 1024)})")
        return "too many open files on this machine (its file table is full): close other programs, try again"
    if isinstance(exc, OSError) and exc.errno in (errno.ENOMEM, errno.EAGAIN):
        return f"the system could not start a process or thread ({exc.strerror}): {_memory()}"
    process = sys.modules.get("concurrent.futures.process")  # (not imported: no process pool broke)
    if process is not None and isinstance(exc, process.BrokenProcessPool):
        return (f"a worker process ended before its work was done (killed, or out of memory): {_memory()}; "
                "or plan in one process (--workers 1)")
    if isinstance(exc, RuntimeError) and "can't start new thread" in str(exc):
        procs = _limit("NPROC")
        more = (f"; or the process limit of {procs} (ulimit -u) is reached" if procs is not None
                and _limit("AS") is None else "")
        return f"the system could not start a thread: {_memory()}{more}"
    return None
