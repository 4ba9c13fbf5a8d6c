"""The project's own exceptions. Each message says what was wrong, where, and what to do."""


class BladecamError(Exception):
    """Base class: an input or planning problem the operator can act on (no traceback shown)."""


class BladeInputError(BladecamError):
    """A blade source (geometry table or mesh) is missing, malformed or unusable."""


class PlanningError(BladecamError):
    """Planning parameters are impossible, or the blade cannot be planned with them."""


class PathScheduleError(PlanningError):
    """Paths whose collaborative machining cannot be scheduled (a speed stage that cannot keep a_max on
    a variable region too short for the feed): ``paths`` their indices. The planner machines such
    paths single-sided."""

    def __init__(self, paths: set[int], message: str):
        super().__init__(message)
        self.paths = paths


class MachineError(BladecamError):
    """A machine.toml is malformed, or a pose is outside what the machine can reach."""


class OutputError(BladecamError):
    """An output folder or file cannot be written."""


class ProjectError(BladecamError):
    """A project file is missing, malformed, or holds an impossible value (the message names the key)."""


class Cancelled(Exception):
    """Raised inside the planning when the progress callback asks to stop (not an input error)."""


class ToolError(MachineError):
    """A tool file (tool.toml) is missing, malformed, or describes an impossible tool assembly."""


class CollisionError(PlanningError):
    """A part of a tool assembly or head would collide (with the blade, its clamp or the other side's
    assembly) where the tool axis cannot be turned clear; ``findings`` the collisions found."""

    def __init__(self, message: str, findings: list | None = None):
        super().__init__(message)
        self.findings = findings or []
