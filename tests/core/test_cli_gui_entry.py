"""`bladecam gui` reaches the workbench through the installed entry point (core never imports it)."""

from __future__ import annotations

from importlib.metadata import entry_points

from core.cli import COMMANDS_GROUP

from ..conftest import bladecam


def test_the_gui_command_is_an_installed_entry_point():
    (gui,) = entry_points(group=COMMANDS_GROUP, name="gui")
    assert gui.value == "bladecam_gui.app:main"


def test_bladecam_gui_calls_the_entry_point_with_the_project(monkeypatch):
    import core.cli as cli

    called = []

    class Found:
        def load(self):
            return lambda argv: called.append(argv) or 0

    monkeypatch.setattr("importlib.metadata.entry_points",
                        lambda group=None, name=None: [Found()] if (group, name) == (COMMANDS_GROUP, "gui") else [])
    assert cli.main(["gui", "p.toml"]) == 0 and cli.main(["gui"]) == 0
    assert called == [["p.toml"], []]


def test_the_entry_point_loads_the_workbench_main():
    import bladecam_gui.app

    (gui,) = entry_points(group=COMMANDS_GROUP, name="gui")
    assert gui.load() is bladecam_gui.app.main
    res = bladecam("gui", "--help", timeout=120)
    assert res.returncode == 0 and "bladecam gui" in res.stdout, res.stderr


def test_without_the_entry_point_the_command_says_what_to_do(monkeypatch, capsys):
    import core.cli as cli

    monkeypatch.setattr("importlib.metadata.entry_points", lambda **kw: [])
    assert cli.main(["gui"]) == 2
    assert "the workbench is not installed" in capsys.readouterr().err


def test_plan_progress_shows_on_a_terminal_only(monkeypatch, capsys):
    """bladecam plan shows its progress on stderr when that is a terminal, and nothing in a batch."""
    import io

    from core.cli import terminal_progress

    monkeypatch.setattr("sys.stderr", io.StringIO())
    assert terminal_progress() is None

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty = Tty()
    monkeypatch.setattr("sys.stderr", tty)
    show = terminal_progress()
    assert show(0.5, "schedule") is True
    assert "50 % schedule" in tty.getvalue()
