"""The lifetime of forked processes and of scratch folders: the path workers (core.paths.planning)
and the table helpers (core.output.csvio) die with the process that forked them (``die_with_parent``);
scratch folders carry their process (``scratch_owner``) so that what a killed run left behind is
known and swept (``abandoned``, ``sweep_worker_scratch``; the plan folder's own in core.output.files)."""

from __future__ import annotations

import ctypes
import hashlib
import os
import re
import shutil
import signal
import socket
import sys
import tempfile
import time
from pathlib import Path


def scratch_dir() -> str | None:
    """A RAM-backed folder for worker results when there is one (Linux /dev/shm)."""
    shm = "/dev/shm"
    return shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else None


def _instance() -> str:
    """8 hex digits naming this boot of this machine and this pid namespace (Linux), '' elsewhere."""
    try:
        with open("/proc/sys/kernel/random/boot_id") as fh:
            boot = fh.read().strip()
        return hashlib.sha1(f"{boot}{os.readlink('/proc/self/ns/pid')}".encode()).hexdigest()[:8]
    except OSError:
        return ""


_INSTANCE = _instance()


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_.]", "_", socket.gethostname()) or "host"


def scratch_owner() -> str:
    """This process as scratch folder names carry it: PID@HOST_INSTANCE (host reduced to safe
    characters; INSTANCE: this boot and pid namespace, so that a folder of a process that no longer
    runs is known dead at once; see ``abandoned``)."""
    return f"{os.getpid()}@{_host()}" + (f"_{_INSTANCE}" if _INSTANCE else "")


def process_gone(pid: int) -> bool:
    """True if no process ``pid`` runs in this pid namespace (False if that cannot be told)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (OSError, OverflowError, ValueError):  # (it exists, as another user's; or no such pid)
        return False
    return False


#: scratch folders of a process of this host but of another boot or pid namespace (or named by a
#: version before the INSTANCE tag) changed less than this long ago (s) are never swept: their
#: process may still run unseen (a container with this host name, a clone of this machine); the
#: environment variable BLADECAM_SWEEP_AGE_S sets another age
SWEEP_AGE_S = 600.0


def abandoned(folder: Path, pid: int, where: str, age_guard: bool = True) -> bool:
    """Whether the scratch folder ``folder`` (a real folder, not a symlink) named by process PID@WHERE
    may be cleared: its process is of this host and no longer runs, and it is of this boot and pid
    namespace (then it is dead for sure) or (``age_guard``) unchanged for SWEEP_AGE_S."""
    host = _host()
    ours = bool(_INSTANCE) and where == f"{host}_{_INSTANCE}"
    if not (ours or where == host or re.fullmatch(re.escape(host) + r"_[0-9a-f]{8}", where)):
        return False
    if folder.is_symlink() or not folder.is_dir() or not process_gone(pid):
        return False
    if ours or not age_guard:
        return True
    try:
        age = float(os.environ.get("BLADECAM_SWEEP_AGE_S", SWEEP_AGE_S))
    except ValueError:
        age = SWEEP_AGE_S
    st = folder.stat()
    return time.time() - max(st.st_mtime, st.st_ctime) >= age  # (a rename sets ctime)


def die_with_parent(parent: int) -> None:
    """Called first thing in a forked child of process ``parent``: the kernel kills it (SIGKILL) when
    the parent's thread that forked it ends, a kill -9 of the parent included (Linux
    prctl(PR_SET_PDEATHSIG); elsewhere nothing); a parent that died before this call ends it at once.
    So a child must be forked by a thread that outlives it (the main thread, or the thread that
    waits for it)."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(1)


_SHM_SCRATCH = re.compile(r"^bladecam-(\d{1,10})@([A-Za-z0-9_.]+)-")


def sweep_worker_scratch() -> list[str]:
    """Remove the path workers' result folders (/dev/shm/bladecam-PID@HOST-*, or in the temporary
    folder without /dev/shm) of processes that no longer run (``abandoned``); returns those removed
    (best effort)."""
    shm, done = scratch_dir() or tempfile.gettempdir(), []
    try:
        entries = os.listdir(shm)
    except OSError:
        entries = []
    for name in entries:
        m = _SHM_SCRATCH.match(name)
        try:
            if m and abandoned(Path(shm, name), int(m.group(1)), m.group(2)):
                shutil.rmtree(os.path.join(shm, name))
                done.append(os.path.join(shm, name))
        except OSError:
            continue
    return done
