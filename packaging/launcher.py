"""Entry point of the desktop bundle (``dist/bladecam/bladecam``).

- no arguments: open the workbench (same as ``bladecam gui``);
- ``gui [PROJECT]``: the workbench (bladecam_gui.app.main);
- anything else: the command line, ``core.cli.main`` (``--version``, ``blade info``, ``plan``,
  ``verify``).

One option exists only here, for checking a built bundle on a machine without a screen (under
``xvfb-run``): ``bladecam gui --smoke-ms N`` opens the workbench, waits at most N ms until the sample
blade's plan is shown, prints one line and quits (status 0 when the plan was shown, 1 otherwise).

The launcher also runs unfrozen: ``.venv/bin/python packaging/launcher.py --version``.
"""

from __future__ import annotations

import multiprocessing
import os
import sys


def _pop_smoke(argv: list[str]) -> tuple[list[str], int | None]:
    """Remove ``--smoke-ms N`` / ``--smoke-ms=N`` from ``argv``; returns (argv, N or None)."""
    out, smoke = [], None
    it = iter(argv)
    for arg in it:
        if arg == "--smoke-ms" or arg.startswith("--smoke-ms="):
            value = arg.partition("=")[2] or next(it, "")
            try:
                smoke = int(value)
            except ValueError:
                print(f"bladecam: error: --smoke-ms needs a number of milliseconds, got {value!r}",
                      file=sys.stderr)
                raise SystemExit(2) from None
        else:
            out.append(arg)
    return out, smoke


def _versions() -> str:
    """The About box's version list (it also proves ``import vtk`` works in the bundle)."""
    try:
        from bladecam_gui.about import versions

        return ", ".join(f"{k} {v}" for k, v in versions().items())
    except Exception as exc:  # noqa: BLE001 (reported, not fatal)
        return f"versions unavailable: {exc!r}"


def _smoke(gui_argv: list[str], timeout_ms: int) -> int:
    """Open the workbench as ``bladecam gui`` does, wait for the first plan, quit."""
    from PySide6.QtCore import QElapsedTimer, QTimer
    from PySide6.QtWidgets import QApplication, QMainWindow

    app = QApplication.instance() or QApplication([sys.argv[0]])
    clock = QElapsedTimer()
    clock.start()
    outcome = {"status": 1, "line": f"smoke: FAIL: no plan shown within {timeout_ms} ms"}

    def windows() -> list[QMainWindow]:
        return [w for w in app.topLevelWidgets() if isinstance(w, QMainWindow) and w.isVisible()]

    def poll() -> None:
        wins = windows()
        win = wins[0] if wins else None
        state = getattr(win, "state", None)
        controller = getattr(win, "controller", None)
        plan = getattr(state, "plan", None)
        running = bool(getattr(controller, "running", False))
        if win is not None and plan is not None and not running:
            outcome["status"] = 0
            outcome["line"] = (f"smoke: ok: window {win.windowTitle()!r} showed a plan after "
                               f"{clock.elapsed()} ms; {_versions()}")
        elif clock.elapsed() < timeout_ms:
            QTimer.singleShot(200, poll)
            return
        for w in windows():
            w.close()  # the window's closeEvent stops its worker threads
        app.quit()

    QTimer.singleShot(200, poll)
    from bladecam_gui.app import main as gui_main

    gui_main(gui_argv[1:])
    print(outcome["line"], flush=True)
    return outcome["status"]


def main(argv: list[str] | None = None) -> int:
    multiprocessing.freeze_support()
    os.environ.setdefault("QT_API", "pyside6")  # qtpy (used by pyvistaqt) picks the bundled binding
    if os.environ.get("WAYLAND_DISPLAY") and os.environ.get("DISPLAY"):
        # VTK's render window in pyvistaqt needs X11: on a Wayland desktop use XWayland (pyvistaqt's advice)
        os.environ.setdefault("QT_QPA_PLATFORM", "xcb")
    argv = list(sys.argv[1:] if argv is None else argv)
    argv, smoke_ms = _pop_smoke(argv)
    if not argv:
        argv = ["gui"]
    if argv[0] == "gui":
        from PySide6.QtGui import QGuiApplication

        # ties the window to packaging/bladecam.desktop (its icon and name in docks and task bars)
        QGuiApplication.setDesktopFileName("bladecam")
    if smoke_ms is not None:
        if argv[0] != "gui":
            print("bladecam: error: --smoke-ms only goes with 'gui' (or no command)", file=sys.stderr)
            return 2
        return _smoke(argv, smoke_ms)
    if argv[0] == "gui":  # (the bundle carries no package metadata for core.cli to find the workbench by)
        from bladecam_gui.app import main as gui_main

        return gui_main(argv[1:])
    from core.cli import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
