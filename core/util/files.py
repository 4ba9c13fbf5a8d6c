"""Input files named by the operator (a geometry table, a mesh, a machine.toml): what a path that
cannot be read as a file is, told as what it is (missing, a folder, a FIFO, a symbolic-link loop, ...)
rather than "not found", and before anything opens it (a FIFO would block the reader forever)."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from core.errors import BladeInputError, OutputError

#: what a path that is not a regular file is, by its st_mode type
_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def file_problem(path: str | Path) -> str | None:
    """Why ``path`` cannot be read as a regular file (None: it can be opened): 'not found', 'a folder',
    'a FIFO (named pipe)', 'a symbolic link loop', 'a broken symbolic link', ..."""
    p = Path(path)
    try:
        mode = os.stat(p).st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a symbolic link loop (the link points back to itself)"
        if exc.errno == errno.ENOENT:
            return "a broken symbolic link (its target is missing)" if os.path.islink(p) else "not found"
        if exc.errno == errno.ENOTDIR:
            return "not found (a part of the path is a file, not a folder)"
        if exc.errno == errno.ENAMETOOLONG:
            return "not a usable path (the name is too long)"
        return f"not readable ({exc.strerror or exc})"
    except ValueError:  # (a NUL character in the name)
        return "not a usable path (it holds a NUL character)"
    if stat.S_ISREG(mode):
        return None
    for test, kind in _KINDS:
        if test(mode):
            return kind + ", not a file"
    return "not a regular file"


#: what a document nested deeper than the readers' recursion allows is told as (tomllib and json read
#: nested arrays and tables recursively: a few thousand levels exhaust Python's stack)
TOO_DEEP = "arrays or tables nested too deeply to read (beyond Python's recursion limit of {limit} levels)"


#: ... and a number with more digits than Python reads as an integer
TOO_LONG = "a number of more than {limit} digits (beyond Python's limit for reading an integer)"


def parse_toml(text: str) -> dict:
    """tomllib.loads(text); a document nested too deeply raises tomllib.TOMLDecodeError (a ValueError)
    naming the limit, as any other malformed TOML does (so does an integer with more digits than Python
    reads), instead of RecursionError."""
    import sys
    import tomllib

    try:
        return tomllib.loads(text)
    except RecursionError:
        raise tomllib.TOMLDecodeError(TOO_DEEP.format(limit=sys.getrecursionlimit())) from None
    except tomllib.TOMLDecodeError:
        raise
    except ValueError:  # (int() of a number with too many digits)
        raise tomllib.TOMLDecodeError(TOO_LONG.format(limit=sys.get_int_max_str_digits())) from None


def parse_json(text: str | bytes):
    """json.loads(text); a document nested too deeply raises ValueError naming the limit, as any other
    malformed JSON does, instead of RecursionError."""
    import json
    import sys

    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError(TOO_DEEP.format(limit=sys.getrecursionlimit())) from None
    except json.JSONDecodeError:
        raise
    except ValueError:  # (int() of a number with too many digits)
        raise ValueError(TOO_LONG.format(limit=sys.get_int_max_str_digits())) from None


def require_file(path: Path, missing: str, hint: str) -> None:
    """BladeInputError unless ``path`` can be read as a regular file: "PATH: ``missing``" when it is not
    there, "PATH: what it is; ``hint``" otherwise (a blade source named by the operator)."""
    problem = file_problem(path)
    if problem == "not found":
        raise BladeInputError(f"{path}: {missing}")
    if problem is not None:
        raise BladeInputError(f"{path}: {problem}; {hint}")


def write_text_whole(path: str | Path, text: str, what: str) -> Path:
    """Write ``text`` to ``path`` whole or not at all (a temporary file beside it, renamed into place);
    OutputError naming ``what`` and the file on failure."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {what} {path}: {exc.strerror or exc}") from None
    return path


def read_toml(path: str | Path, error: type[Exception], what: str) -> dict:
    """The TOML document of the file ``path`` (``parse_toml``); ``error`` (naming ``what``, e.g.
    'machine file', and the fix) where the file is missing, unreadable or not valid TOML."""
    import tomllib

    p = Path(path)
    problem = file_problem(p)
    if problem is not None:  # (a FIFO would block the read forever)
        raise error(f"cannot read {what} {p}: {problem}")
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise error(f"cannot read {what} {p}: {exc.strerror or exc}") from exc
    try:
        return parse_toml(raw.decode("utf-8-sig"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise error(f"{p}: not valid TOML ({exc}); fix the file or pass another one") from exc
