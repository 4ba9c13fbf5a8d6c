"""The workbench state: the inputs being edited, the plan shown and the timeline cursor, with signals.

Widgets receive this object in ``__init__``, react to its signals in ``_on_<thing>_changed`` slots and
never compute geometry. The inputs (blade source, axis, parameters, profile, period) may run ahead of
the plan shown: the plan controller re-plans them in a worker and calls ``set_plan`` when done; until
then the previous valid plan stays shown. Every job asks for the machines' axis tables: core times a
job for the machines whether or not it returns them, so the plan shown is the job an export writes,
and the tables pose the machines and fill the axes plot.
"""

from __future__ import annotations

from dataclasses import fields, replace

from PySide6.QtCore import QObject, Signal

from core.records import PlanParameters

from .plan_data import PlanData, PlanJob


def default_parameters() -> PlanParameters:
    """The core defaults with the derived values (dR = r/4, h_safe = 1.25 r) written out."""
    return PlanParameters().resolved()


class WorkbenchState(QObject):
    """Inputs, the shown plan and the cursor.

    inputs_changed(str): what changed, 'blade' | 'params' | 'schedule' | 'project' (re-plan needed)
    params_changed(PlanParameters); blade_changed(BladeData): a new blade is shown;
    plan_changed(PlanData): a new plan (or preview) is shown; cursor_changed(int): time sample index;
    busy_changed(bool); progress_changed(float, str); stale_changed(bool): inputs differ from the plan;
    regions_changed(PlanData): the paths and regions to draw, which run ahead of the plan while the new
    plan's schedule is computed (a preview), and come back to the plan's when it arrives or fails
    """

    inputs_changed = Signal(str)
    params_changed = Signal(object)
    blade_changed = Signal(object)
    plan_changed = Signal(object)
    cursor_changed = Signal(int)
    busy_changed = Signal(bool)
    progress_changed = Signal(float, str)
    stale_changed = Signal(bool)
    regions_changed = Signal(object)

    def __init__(self, parent: QObject | None = None, params: PlanParameters | None = None):
        super().__init__(parent)
        self.source = "sample"
        self.axis = "z"
        self.params = params or default_parameters()
        self.profile = "sigmoid"
        self.period: float | None = None
        self.tool: str | None = None  # the tool file (None: the shipped assembly)
        self.plan: PlanData | None = None
        self.preview: PlanData | None = None
        self.cursor = 0
        self.busy = False
        self.stale = False

    # -- inputs ----------------------------------------------------------------------------------
    def job(self) -> PlanJob:
        return PlanJob(self.source, self.axis, self.params, self.profile, self.period, axes=True, tool=self.tool)

    def set_params(self, params: PlanParameters) -> None:
        if params == self.params:
            return
        self.params = params
        self.params_changed.emit(params)
        self.inputs_changed.emit("params")

    def set_param(self, name: str, value) -> None:
        self.set_params(replace(self.params, **{name: value}))

    def set_blade_source(self, source: str, axis: str = "z") -> None:
        self.source, self.axis = source, axis
        self.inputs_changed.emit("blade")

    def set_schedule_option(self, name: str, value) -> None:
        """'profile' (sigmoid | smooth) or 'period' (ms or None)."""
        if name not in ("profile", "period"):
            raise KeyError(name)
        if getattr(self, name) != value:
            setattr(self, name, value)
            self.inputs_changed.emit("schedule")

    def set_project(self, source: str, axis: str, params: PlanParameters, profile: str,
                    period: float | None) -> None:
        """All inputs at once (a project file); dR and h_safe 'auto' are written out."""
        self.source, self.axis, self.profile, self.period = source, axis, profile, period
        if params != self.params:
            self.params = params
            self.params_changed.emit(params)
        self.inputs_changed.emit("project")

    def revert_blade(self) -> None:
        """Back to the blade shown (after a blade that failed to load)."""
        if self.plan is not None:
            self.source, self.axis = self.plan.blade.source, self.plan.blade.axis

    def unplanned(self) -> dict[str, tuple]:
        """The inputs that differ from the shown plan's: name -> (input value, the plan's value);
        names as the InputEditor's ('h_safe', 'profile', ...), or 'blade'."""
        if self.plan is None:
            return {}
        job, shown = self.job(), self.plan.job
        out = {f.name: (getattr(job.params, f.name), getattr(shown.params, f.name))
               for f in fields(job.params) if getattr(job.params, f.name) != getattr(shown.params, f.name)}
        for name in ("profile", "period"):
            if getattr(job, name) != getattr(shown, name):
                out[name] = (getattr(job, name), getattr(shown, name))
        if (job.source, job.axis) != (shown.source, shown.axis):
            out["blade"] = (job.source, shown.source)
        return out

    # -- plan ------------------------------------------------------------------------------------
    def set_plan(self, data: PlanData) -> None:
        old = self.plan
        t_old = None
        if old is not None and old.has_schedule:
            t_old = float(old.timeline.t[self.cursor])
        self.plan = data
        self.preview = None
        # the cursor on the new plan's time column before anyone hears of the plan (a shorter plan
        # must never be read at the old plan's index)
        self.cursor = (data.index_at(t_old) if t_old is not None else 0) if data.has_schedule else 0
        if old is None or old.blade is not data.blade:
            self.blade_changed.emit(data.blade)
        self.plan_changed.emit(data)
        self.regions_changed.emit(data)
        self.set_stale(data.job != self.job())
        if data.has_schedule:
            self.cursor_changed.emit(self.cursor)

    def set_regions_preview(self, data: PlanData) -> None:
        """New paths / regions of the plan being computed (the timeline stays the shown plan's)."""
        self.preview = data
        self.regions_changed.emit(data)

    def clear_preview(self) -> None:
        """Back to the shown plan's paths and regions (after a failed or cancelled job)."""
        if self.preview is not None:
            self.preview = None
            if self.plan is not None:
                self.regions_changed.emit(self.plan)

    def set_busy(self, busy: bool) -> None:
        if busy != self.busy:
            self.busy = busy
            self.busy_changed.emit(busy)

    def set_stale(self, stale: bool) -> None:
        if stale != self.stale:
            self.stale = stale
            self.stale_changed.emit(stale)

    # -- cursor ----------------------------------------------------------------------------------
    def set_cursor(self, index: int) -> None:
        if self.plan is None or not self.plan.has_schedule:
            return
        index = max(0, min(int(index), len(self.plan.timeline.t) - 1))
        if index != self.cursor:
            self.cursor = index
            self.cursor_changed.emit(index)

    def set_cursor_time(self, t_ms: float) -> None:
        if self.plan is not None and self.plan.has_schedule:
            self.set_cursor(self.plan.index_at(t_ms))

    @property
    def cursor_time(self) -> float:
        if self.plan is None or not self.plan.has_schedule:
            return 0.0
        return float(self.plan.timeline.t[self.cursor])
