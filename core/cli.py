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
import time

from core import __version__
from core.errors import BladecamError

# (imported up front: with no file descriptor left, no import works)
from core.util.limits import address_space_shortfall, limit_message


def _blade_info(args: argparse.Namespace) -> int:
    from core.blade.source import info_lines, load_blade, merged_options

    blade = load_blade(merged_options(args.blade, args.blade_index, args.r_min, args.units), axis=args.axis)
    for w in blade.warnings:
        if getattr(blade, "propeller", None) is None or "whole propeller" not in w:  # (listed below)
            print(f"warning: {w}", file=sys.stderr)
    info = blade.info()  # (JSON: info refuses a non-finite size)
    text = "\n".join(info_lines(info, args.blade_index is None))
    print(json.dumps(info, indent=2, allow_nan=False) if args.json else text)
    return 0


def _add_blade_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--blade", default="sample", metavar="SOURCE",
                   help="'sample' (default), a geometry table (.csv), a mesh (.stl/.obj/.ply) of one blade or "
                        "of a whole propeller, two mesh files 'face.stl,back.stl', or the same as CAD files "
                        "(.step/.stp/.igs/.iges)")
    p.add_argument("--axis", default="z", metavar="AXIS",
                   help="propeller axis of a mesh or CAD source: x, y, z (default z) or a direction "
                        "DX,DY,DZ, through the origin or, followed by @PX,PY,PZ, through that point "
                        "(e.g. z@200,0,0)")
    p.add_argument("--units", default=None, choices=("mm", "cm", "m", "in"),
                   help="what a mesh's numbers mean (default mm; tables and CAD files state their own); "
                        "a blade whose size is no propeller's gets a warning naming the unit that fits")
    p.add_argument("--blade-index", type=int, default=None, metavar="K",
                   help="blade K (from 1) of a whole propeller in one mesh or CAD file ('bladecam blade info' "
                        "lists them; default 1, with a warning)")
    p.add_argument("--r-min", type=float, default=None, metavar="MM",
                   help="cut a whole propeller's hub off at this radius (default: just outside the hub, "
                        "found from the geometry)")


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


def _plan(args: argparse.Namespace) -> int:
    from core.blade.source import absolute_source, merged_options
    from core.machine.job_figures import slow_feed_line
    from core.machine.tool import resolve_tool
    from core.output.files import check_destination
    from core.output.writer import PlanWriter, unsafe_reason
    from core.paths.collaboration import collaboration_warning
    from core.planner import Planner
    from core.records import PlanJob, PlanParameters

    t0 = time.perf_counter()
    tool = resolve_tool(args.tool, args.tool_radius)  # (the tool file gives the radius and stick-out)
    params = PlanParameters(tool_radius=tool.ball_radius, dr=args.dr, dd=args.dd, h_safe=args.h_safe,
                            k_max=args.k_max, feed=args.feed, a_max=args.a_max, mode=args.mode,
                            tool_length=tool.stick_out, min_feed=args.min_feed)
    check_destination(args.out)  # (refused before any planning, as atomic_folder would at the end)
    source = absolute_source(merged_options(args.blade, args.blade_index, args.r_min, args.units))
    job = PlanJob(source, args.axis, params, args.profile, args.period_ms, args.axes,
                  args.machine, args.chord_tol, None if args.tool is None else os.path.abspath(args.tool))
    job.params.resolved()  # (bad parameters are refused before anything is loaded)
    job.resolved_period()
    job.resolved_chord_tol()
    planner = Planner(workers=args.workers)
    blade = planner.blade(job.source, job.axis)  # (kept by the planner: loaded once; its warnings first)
    for w in blade.warnings:
        print(f"warning: {w}", file=sys.stderr)
    checked: list = []
    with PlanWriter(args.out, args.workers, check=verified(args.force, args.workers, checked)) as writer:
        result = planner.plan(job, progress=terminal_progress(), listener=writer,
                              until="paths" if args.paths_only else "tables")
        if sys.stderr.isatty():
            print("\r\033[K", end="", file=sys.stderr, flush=True)
        planner.release()  # (no re-plan follows: the check before writing reuses its memory)
        out = writer.write(result, force=args.force)
    plan, fig = result.plan, result.figures
    counts = plan.region_counts()
    for w in plan.warnings:
        print(f"warning: {w}", file=sys.stderr)
    unsafe = unsafe_reason(result) if fig is not None else None
    if unsafe is not None:  # written only with --force
        print(f"warning: written with --force although {unsafe}", file=sys.stderr)
    if result.collisions:  # written only with --force
        worst = result.collisions[0]
        print(f"warning: written with --force although the tool assembly collides ({len(result.collisions)} "
              f"stretches; {worst.describe(result.timeline.t)}; see plan.json schedule.collisions)",
              file=sys.stderr)
    if result.limit_findings:  # written only with --force (every kind refuses a plan: ENFORCED_LIMITS)
        kinds = sorted({f"{f.side} {f.axis} {f.kind}" for f in result.limit_findings})
        print(f"warning: written with --force although {len(kinds)} axis limits are exceeded (see plan.json "
              f"schedule.machine): {', '.join(kinds[:6])}{' ...' if len(kinds) > 6 else ''}", file=sys.stderr)
    if checked and checked[0].total:  # written only with --force
        print(f"warning: written with --force although bladecam verify finds {checked[0].summary()}",
              file=sys.stderr)
    collaboration = collaboration_warning(plan)
    if collaboration:
        print(f"warning: {collaboration}", file=sys.stderr)
    mode = job.params.resolved().mode
    tips = f" ({counts['tip_paths']} in the tip region)" if mode == "collaborative" else ""
    head = f"planned {counts['paths']} paths{tips} on {plan.blade.name!r}; "
    if fig is None:
        print(head + f"wrote pairs.csv and plan.json to {out} in {time.perf_counter() - t0:.2f} s")
    else:
        job = fig["job"]
        print(head + f"{mode} schedule {fig['total_time_s'] / 60:.1f} min ({job['time_at_feed_s'] / 60:.1f} at the "
              f"feed; {100 * job['cutting']['both']['share_below_min_feed']:.1f} % of the cutting time below the "
              f"minimum feed {job['min_feed_mm_min']:g} mm/min), minimum tip "
              f"spacing {fig['min_tip_spacing_mm']:.3f} mm, minimum clearance "
              f"{fig['min_capsule_clearance_mm']:.3f} mm; wrote {out} in {time.perf_counter() - t0:.2f} s")
        slow = slow_feed_line(job)
        if slow:
            print(slow)
    return 0


def verified(force: bool, workers: int, reports: list):
    """The check ``bladecam plan`` runs on a written plan folder before it is made visible: bladecam
    verify's own checks (core.verify), so that exit 0 means the plan verifies. With findings the plan
    is refused (PlanningError listing the first ones) unless ``force``; the report goes into
    ``reports``. ``given``: the tables' rows as written, which the plan holds (core.output.writer.
    written_rows): verify checks them instead of reading the files back."""
    def check(folder, given=None) -> None:
        from core.errors import PlanningError
        from core.verify.check import verify

        rep = verify(folder, workers=max(workers, 1), given=given)
        reports.append(rep)
        if rep.total and not force:
            shown = "\n  ".join(rep.findings[:8])
            raise PlanningError(f"the plan fails bladecam verify's checks, nothing was written:\n  {shown}\n"
                                f"{rep.summary()}. This is a defect of the plan (the planner's own checks "
                                "missed it): change the parameters, or give --force to write it anyway")

    return check


def terminal_progress():
    """A progress callback that shows the stage and its share on one line of a terminal's stderr, at
    most five times a second (None when stderr is not a terminal: batch runs and logs stay clean)."""
    if not sys.stderr.isatty():
        return None
    last = [0.0]

    def show(fraction: float, message: str) -> bool:
        now = time.monotonic()
        if now - last[0] >= 0.2:
            last[0] = now
            print(f"\r\033[K{100 * fraction:3.0f} % {message}", end="", file=sys.stderr, flush=True)
        return True

    return show


def _verify(args: argparse.Namespace) -> int:
    from core.output.files import restore_plan
    from core.verify.check import verify

    t0 = time.perf_counter()
    hidden = restore_plan(os.path.abspath(args.dir))
    if hidden is not None:
        print(f"bladecam: restored {args.dir} from {hidden.name} (the previous plan, moved aside by a run "
              "that was killed while it replaced this folder)", file=sys.stderr)
    if not os.path.isdir(args.dir):
        from core.errors import OutputError

        what = "is a file, not a folder" if os.path.exists(args.dir) else "does not exist"
        raise OutputError(f"{args.dir} {what}: give the plan folder, the --out DIR of bladecam plan")
    rep = verify(args.dir)
    for line in [*rep.findings, *rep.figure_lines(), rep.trusted]:  # (one finding per line, then figures)
        print(line)
    print(f"{rep.summary()}; checked in {time.perf_counter() - t0:.2f} s")
    return 1 if rep.total else 0


MAX_WORKERS = 64


def _workers(text: str) -> int:
    """--workers: a whole number from 1 to MAX_WORKERS."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number of processes, got {text!r}") from None
    if not 1 <= n <= MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"must be from 1 to {MAX_WORKERS} processes, got {n}")
    return n


def _add_plan_commands(sub) -> None:
    """``bladecam plan`` and ``bladecam verify``."""
    p = sub.add_parser("plan", help="plan the double-sided tool paths and write them to --out DIR")
    _add_blade_args(p)
    p.add_argument("--tool-radius", type=float, default=None, metavar="MM",
                   help="ball radius (default 1.5; with --tool, the tool file's)")
    p.add_argument("--tool", default=None, metavar="FILE",
                   help="tool.toml: the tool assembly both machines carry (ball, flutes, neck, shank, holder "
                        "stages, spindle nose), checked against the blade and each other (default: the shipped "
                        "3 mm ball-nose mill in an ER16 collet)")
    p.add_argument("--dr", type=float, default=None, metavar="MM", help="radius increment dR (default r/4)")
    p.add_argument("--dd", type=float, default=0.2, metavar="MM", help="interpolation step (default 0.2)")
    p.add_argument("--h-safe", type=float, default=None, metavar="MM",
                   help="minimum tip spacing (default 1.25 r)")
    p.add_argument("--k-max", type=float, default=0.15, metavar="X", help="maximum staggered ratio (0.15)")
    p.add_argument("--mode", default="collaborative", choices=("collaborative", "symmetric", "single"),
                   help="collaborative (default, the paper's), symmetric (unsafe preview) or single")
    p.add_argument("--feed", type=float, default=1000.0, metavar="MM_PER_MIN", help="feed (default 1000)")
    p.add_argument("--min-feed", type=float, default=None, metavar="MM_PER_MIN",
                   help="the slowest a cutting cutter should run, from the tool's minimum chip thickness (default "
                        "30 %% of the feed): the plan reports where and why a cutter cuts slower")
    p.add_argument("--a-max", type=float, default=500.0, metavar="MM_PER_S2",
                   help="maximum acceleration along the path (default 500)")
    p.add_argument("--profile", default="sigmoid", choices=("sigmoid", "smooth"),
                   help="speed stages: the paper's sigmoid (default) or a jerk-limited smooth profile")
    p.add_argument("--period-ms", type=float, default=None, metavar="MS",
                   help="the controllers' period: every row of the CL and axis tables lies on t = k * period "
                        "(default dd / feed)")
    p.add_argument("--chord-tol", type=float, default=1e-3, metavar="MM",
                   help="how far the straight line between two rows may stray from the planned path; the feed "
                        "is slowed where the path turns too sharply for it (default 0.001)")
    p.add_argument("--paths-only", action="store_true",
                   help="stop after the paths: write pairs.csv and plan.json only (no schedule, no CL tables)")
    p.add_argument("--axes", action=argparse.BooleanOptionalAction, default=True,
                   help="write the two XYZ-3RPS machines' axis tables left_axes.csv, right_axes.csv and "
                        "machine.toml (the default); --no-axes: the CL tables only. The job is the same either "
                        "way: timed for the machines (tool axes within the heads' tilt, the feed slowed where an "
                        "axis would exceed its speed or acceleration limit)")
    p.add_argument("--machine", default=None, metavar="FILE",
                   help="machine.toml of the two machines the job is timed for (default: the shipped bench "
                        "machine)")
    p.add_argument("--force", action="store_true",
                   help="write the plan even if it is unsafe, the tool assembly collides, or it breaks a "
                        "machine axis's stroke, speed or acceleration limit")
    p.add_argument("--workers", type=_workers, default=min(os.cpu_count() or 1, 2), metavar="N",
                   help="processes for the path steps (default: 2, or 1 on a one-core machine)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (written atomically)")
    p.set_defaults(func=_plan)
    v = sub.add_parser("verify", help="re-check a written plan folder independently (exit 1 on a violation)",
                       description="Re-check a plan folder written by 'bladecam plan' without the planner's code: "
                                   "its file set and the files' digests, tip spacing, tool clearance, the cutting "
                                   "balls on the blade's offset surface, no ball in the blade at any other row or "
                                   "between rows, speeds and accelerations, every pair point of pairs.csv cut by "
                                   "its cutter in order, the rows' labels, and the machines' axis tables (forward "
                                   "kinematics, limits, velocities that are the derivative of the positions). "
                                   "plan.json's parameters and machine.toml are trusted as written (the report "
                                   "says so). bladecam plan runs these checks before writing. Exit 0: clean; 1: "
                                   "findings (one per line, a few of each kind, then a summary that counts them "
                                   "all); 2: not a readable plan folder.")
    v.add_argument("dir", metavar="DIR", help="the plan folder: the --out DIR of 'bladecam plan'")
    v.set_defaults(func=_verify)


def build_parser() -> Parser:
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

    _add_plan_commands(sub)

    gui = sub.add_parser("gui", help="open the workbench")
    gui.add_argument("project", nargs="?", help="a project file to open, or a plan folder to review (read-only)")
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
    short = address_space_shortfall() if args.func in (_plan, _verify) else None
    if short is not None:
        print(f"bladecam: error: {short}", file=sys.stderr)
        return 2
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
    except ImportError as exc:  # (a signal while an extension module initialises surfaces as its ImportError)
        if not _interrupted(exc):
            raise
        print("bladecam: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output went away (``bladecam verify DIR | head``): stop quietly, as the
        # shell tools do; stdout is pointed at /dev/null so that Python's exit flush does not fail
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except (MemoryError, OSError, RuntimeError) as exc:  # (a process limit: one line naming it)
        message = limit_message(exc)
        if message is None:
            raise
        print(f"bladecam: error: {message}", file=sys.stderr)
        return 2


def _interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` was raised by an interrupt (Ctrl+C or a termination signal) somewhere in its chain."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


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
