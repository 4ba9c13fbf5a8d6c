"""The command line: ``bladecam blade info``, ``bladecam plan``, ``bladecam verify``, ``bladecam gui``.

Input errors (the project's own exceptions) print one clear message and exit with status 2; no
Python traceback is shown for them.
"""

from __future__ import annotations

import argparse
import difflib
import json
import os
import re
import sys

from core import __version__, cli_plan
from core.errors import BladecamError
from core.util.limits import limit_message  # (imported up front: with no file descriptor left, no import works)


def _blade_info(args: argparse.Namespace) -> int:
    from core.blade.source import load_blade

    blade = load_blade(args.blade, axis=args.axis)
    for w in blade.warnings:
        print(f"warning: {w}", file=sys.stderr)
    info = blade.info()
    if args.json:
        print(json.dumps(info, indent=2, allow_nan=False))  # (info refuses a non-finite size)
        return 0
    print(f"blade {info['name']!r} from {info['source']}")
    print(f"  tip radius  {info['tip_radius_mm']:10.3f} mm")
    print(f"  hub radius  {info['hub_radius_mm']:10.3f} mm")
    print("  r/R      chord mm   max thickness mm")
    for key, chord in info["chord_mm"].items():
        thick = info["max_thickness_mm"][key]
        if chord is None:
            print(f"  {key:<6}   (inside the hub)")
        else:
            print(f"  {key:<6} {chord:10.3f} {thick:12.3f}")
    return 0


def _add_blade_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--blade", default="sample", metavar="SOURCE",
                   help="'sample' (default), a geometry table (.csv), a mesh (.stl/.obj/.ply) or "
                        "two mesh files 'face.stl,back.stl'")
    p.add_argument("--axis", default="z", choices=("x", "y", "z"),
                   help="propeller axis of a mesh source (default z)")


class Parser(argparse.ArgumentParser):
    """argparse's parser, whose errors suggest the nearest command or option for a misspelt one, and
    which reads every negative number as a value (``--dr -1e-5``, ``--feed -inf``: argparse's own
    pattern knows only -12 and -1.5, and took -1e-5 for an option: "expected one argument")."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$",
                                                   re.IGNORECASE)

    def error(self, message: str):
        choice = re.match(r"argument .*: invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            options = re.findall(r"'([^']*)'", choice.group(2))
            message += _did_you_mean(choice.group(1), options)
        super().error(message)

    def option_strings(self) -> list[str]:
        return [o for a in self._actions for o in a.option_strings if o.startswith("--")]


def _did_you_mean(word: str, options: list[str]) -> str:
    close = difflib.get_close_matches(word, options, n=2, cutoff=0.6)
    return f"; did you mean {' or '.join(close)}?" if close else ""


DESCRIPTION = ("bladecam plans the double-sided tool paths of a propeller blade for two XYZ-3RPS machines: "
               "'bladecam blade info' measures a blade, 'bladecam plan' plans and writes the machines' tables, "
               "'bladecam verify' re-checks a written plan, 'bladecam gui' opens the workbench.")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="bladecam", description=DESCRIPTION,
                    epilog="'bladecam COMMAND --help' lists a command's options.")
    parser.add_argument("--version", action="version", version=f"bladecam {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    blade = sub.add_parser("blade", help="blade geometry commands (blade info)")
    blade_sub = blade.add_subparsers(dest="blade_command", metavar="COMMAND")
    info = blade_sub.add_parser("info", help="sizes of a blade: radii, chord and thickness")
    _add_blade_args(info)
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.set_defaults(func=_blade_info)

    cli_plan.add_commands(sub, _add_blade_args)

    gui = sub.add_parser("gui", help="open the workbench")
    gui.add_argument("project", nargs="?", help="a project file to open")
    gui.set_defaults(func=_gui)
    return parser


#: the entry-point group where installed front ends name their commands (pyproject.toml): core never
#: imports the workbench, it finds it here at run time
COMMANDS_GROUP = "bladecam.commands"


def _gui(args: argparse.Namespace) -> int:
    from importlib.metadata import entry_points

    found = entry_points(group=COMMANDS_GROUP, name="gui")
    if not found:
        raise BladecamError("the workbench is not installed with this bladecam (no 'gui' entry point in "
                            f"{COMMANDS_GROUP}); install the package with its GUI (make run)")
    gui_main = next(iter(found)).load()
    return gui_main([args.project] if args.project else [])


_CHILD_RESET = False  # the fork hook that gives children the default action back is registered


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised as an interrupt (caught wherever KeyboardInterrupt is). A subclass,
    not KeyboardInterrupt itself: CPython 3.11 ends a process by SIGINT at exit when it saw a
    KeyboardInterrupt leave code it ran (it compares the exception's type exactly), and a SIGTERM
    that landed in a module's import (in the code dataclasses exec() to build their methods) made
    `bladecam plan` die by SIGINT after printing "interrupted" and returning 130: 4 times in 140
    runs; 0 in 140 with this subclass."""


def _terminate_as_exit() -> None:
    """SIGTERM and SIGHUP (a batch job killed, a closed terminal) end the command as an interrupt
    does: through the normal clean-up (temporary and scratch folders removed, helpers ended), never
    leaving half a plan beside the output folder. Only in the main thread (signal's rule)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return
    pid = os.getpid()

    def stop(signum, _frame):
        if os.getpid() != pid:  # (a child that kept the handler: ends as it would have)
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        raise Terminated(f"signal {signum}")

    names = [name for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)]
    for name in names:
        signal.signal(getattr(signal, name), stop)

    def default_in_child() -> None:
        # forked workers and helpers keep the default action (a worker waiting on a lock it inherited
        # would never run a Python handler; terminate() and kill() must end it)
        for name in names:
            try:
                signal.signal(getattr(signal, name), signal.SIG_DFL)
            except ValueError:  # (not the main thread)
                pass

    global _CHILD_RESET
    if not _CHILD_RESET:
        os.register_at_fork(after_in_child=default_in_child)
        _CHILD_RESET = True


def _parse(parser: Parser, argv: list[str] | None) -> argparse.Namespace | None:
    """The command line's arguments; None when no command was given (its help is printed). A misspelt
    option is reported by its command's parser with the nearest option it has (argparse exits 2)."""
    args, extra = parser.parse_known_args(argv)
    sub = parser
    for dest in ("command", "blade_command"):
        name = getattr(args, dest, None)
        if name is None:
            break
        sub = next(a for a in sub._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
    if extra:
        known = sub.option_strings()
        hints = [f"for {x.split('=')[0]}{_did_you_mean(x.split('=')[0], known)[1:]}"
                 for x in extra if x.startswith("--") and _did_you_mean(x.split("=")[0], known)]
        sub.error(f"unrecognized arguments: {' '.join(extra)}" + "".join(f"; {h}" for h in hints))
    if getattr(args, "func", None) is None:
        sub.print_help()
        return None
    return args


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = _parse(parser, argv)
    if args is None:
        return 0
    from core.util.memory import tune_allocator

    tune_allocator()
    if args.func is not _gui:  # (the workbench has its own event loop and closes as a window does)
        _terminate_as_exit()
    try:
        return int(args.func(args) or 0)
    except BladecamError as exc:
        print(f"bladecam: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bladecam: interrupted", file=sys.stderr)
        return 130
    except (MemoryError, OSError, RuntimeError) as exc:  # (a process limit: one line naming it)
        message = limit_message(exc)
        if message is None:
            raise
        print(f"bladecam: error: {message}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader of our output went away (``bladecam verify DIR | head``): stop quietly, as the
        # shell tools do; stdout is pointed at /dev/null so that Python's exit flush does not fail
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


#: the commands after which a successful run ends the process at once (``run``)
QUICK_EXIT_COMMANDS = ("plan", "verify")
_end_process = os._exit  # (a test replaces it to see that run ends the process this way)


def run(argv: list[str] | None = None) -> None:
    """The console entry point (``bladecam``, ``python -m core``): ``main``, then the process ends.

    A plan leaves ~1 GB of arrays and objects behind, and Python's own teardown frees them one by one:
    ~0.1 s of a 7.5 s ``bladecam plan``. After a ``plan`` or ``verify`` that succeeded with no thread
    or child process left, the output streams are flushed and the process ends at once (os._exit);
    every other case (an error, the other commands, the workbench, a flush that fails) exits as
    Python does."""
    import threading

    from core.util.process import configure_process

    configure_process()  # (before numpy is imported)
    args = sys.argv[1:] if argv is None else argv
    command = next((a for a in args if not a.startswith("-")), None)
    code = main(argv)
    mp = sys.modules.get("multiprocessing")
    if (code == 0 and command in QUICK_EXIT_COMMANDS and threading.active_count() == 1
            and (mp is None or not mp.active_children())):
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except (OSError, ValueError):
            sys.exit(code)
        logging = sys.modules.get("logging")
        if logging is not None:
            logging.shutdown()
        _end_process(0)
    sys.exit(code)


if __name__ == "__main__":
    run()
