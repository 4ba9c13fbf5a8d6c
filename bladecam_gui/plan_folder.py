"""A written plan folder opened read-only, for review: the tables as written, both machines at the cursor
(their axis rows and their cutters' rows), and ``bladecam verify``'s findings.

What an operator checks before sending the tables to the machines. The folder is read with verify's
own readers (core.verify.read) and never written; nothing is planned again. To change the plan, the
blade and tool the folder carries (blade.stl, tool.toml) open in the workbench, which plans them anew.
"""

from __future__ import annotations

import json
import logging
import mmap
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PySide6.QtCore import QAbstractTableModel, QObject, Qt, QThread, Signal, Slot
from PySide6.QtWidgets import (
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QListWidget,
    QMainWindow,
    QSlider,
    QSplitter,
    QTableView,
    QTableWidget,
    QTableWidgetItem,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from core.errors import BladecamError, OutputError
from core.machine.model import SIDES
from core.paths.regions import REGION_NAMES
from core.schedule.safety import tip_spacing
from core.verify.read import read_axes, read_cl

log = logging.getLogger(__name__)

#: the axis columns shown per machine at the cursor (mm)
AXIS_VALUES = ("x_mm", "y_mm", "z_mm", "d1_mm", "d2_mm", "d3_mm")


@dataclass(frozen=True)
class PlanFolder:
    """A plan folder as written: plan.json's summary, both CL tables (core.verify.read.read_cl) and,
    when written, both axis tables (read_axes: (n, 13))."""

    path: Path
    summary: dict
    cl: dict
    axes: dict | None

    @classmethod
    def read(cls, folder: str | Path) -> PlanFolder:
        """Read ``folder`` (OutputError naming what is missing or unreadable)."""
        path = Path(folder)
        if not path.is_dir():
            raise OutputError(f"{path}: no such folder")
        try:
            summary = json.loads((path / "plan.json").read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise OutputError(f"{path} is not a plan folder: it has no plan.json (bladecam plan --out writes "
                              "one)") from None
        except (OSError, ValueError, RecursionError) as exc:
            raise OutputError(f"{path / 'plan.json'}: cannot read it ({exc})") from None
        if not isinstance(summary, dict):
            raise OutputError(f"{path / 'plan.json'}: not a plan summary (a JSON object)")
        names = [f"{side}_cl.csv" for side in SIDES]
        missing = [n for n in names if not (path / n).is_file()]
        if missing:
            raise OutputError(f"{path}: {' and '.join(missing)} missing: a paths-only plan (--paths-only) has no "
                              "tables to review")
        cl = {side: read_cl(path / f"{side}_cl.csv") for side in SIDES}
        if len(cl["left"]["t"]) != len(cl["right"]["t"]) or not np.array_equal(cl["left"]["t"], cl["right"]["t"]):
            raise OutputError(f"{path}: the two CL tables do not share one time column")
        axes = None
        if all((path / f"{side}_axes.csv").is_file() for side in SIDES):
            axes = {side: read_axes(path / f"{side}_axes.csv") for side in SIDES}
            if any(len(a) != len(cl["left"]["t"]) for a in axes.values()):
                raise OutputError(f"{path}: the axis tables do not have the CL tables' rows")
        return cls(path, summary, cl, axes)

    @property
    def t(self) -> np.ndarray:
        return self.cl["left"]["t"]

    def spacing(self) -> np.ndarray:
        """(n,) mm: the safety rule's tip spacing at every row (core.schedule.safety.tip_spacing)."""
        return tip_spacing(self.cl["left"]["p"], self.cl["right"]["p"])[0]

    def inputs(self) -> dict:
        inp = self.summary.get("inputs")
        return inp if isinstance(inp, dict) else {}

    def what_is_possible(self) -> str:
        """One paragraph: what this window shows and how to plan the folder's blade again."""
        here = [n for n in ("blade.stl", "tool.toml", "machine.toml") if (self.path / n).is_file()]
        carried = ", ".join(here) if here else "no blade or tool file"
        return (f"Read-only review of the tables as written: nothing here is planned again or written. To change "
                f"the plan, open the folder's blade in the workbench (File > Open blade…: blade.stl) with its "
                f"tool (File > Tool file…: tool.toml) and the parameters of plan.json's inputs; the folder "
                f"carries {carried}.")


class TextTable(QAbstractTableModel):
    """A CSV table shown exactly as the file holds it: the file mapped into memory (read-only, not
    loaded) and each row's text cut out when it is drawn."""

    def __init__(self, path: Path):
        super().__init__()
        with open(path, "rb") as f:
            self.map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        ends = np.flatnonzero(np.frombuffer(self.map, np.uint8) == 10)
        if len(ends) == 0 or ends[-1] != len(self.map) - 1:
            ends = np.append(ends, len(self.map))
        self.ends = ends
        self.columns = self.map[:ends[0]].decode("utf-8", "replace").strip().split(",")

    def line(self, i: int) -> list[str]:
        """Data row ``i`` (after the header) as the file writes it, split into its fields."""
        return self.map[self.ends[i] + 1:self.ends[i + 1]].decode("utf-8", "replace").rstrip("\r").split(",")

    def rowCount(self, parent=None) -> int:  # noqa: N802 (Qt name)
        return 0 if parent is not None and parent.isValid() else len(self.ends) - 1

    def columnCount(self, parent=None) -> int:  # noqa: N802 (Qt name)
        return 0 if parent is not None and parent.isValid() else len(self.columns)

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if role != Qt.ItemDataRole.DisplayRole or not index.isValid():
            return None
        fields = self.line(index.row())
        return fields[index.column()] if index.column() < len(fields) else ""

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802 (Qt name)
        if role != Qt.ItemDataRole.DisplayRole:
            return None
        return self.columns[section] if orientation == Qt.Orientation.Horizontal else str(section)

    def close(self) -> None:
        self.map.close()


class _Verifier(QObject):
    """bladecam verify on the folder, in a thread of its own (seconds to minutes)."""

    done = Signal(object)  # a core.verify.report.Report, or the error's text

    def __init__(self, folder: Path):
        super().__init__()
        self.folder = folder

    @Slot()
    def run(self) -> None:
        from core.verify.check import verify

        try:
            report = verify(self.folder, workers=1)  # (no forked helpers from a Qt process)
        except BladecamError as exc:
            report = str(exc)
        except Exception as exc:  # (a thread's slot never raises)
            log.exception("verifying %s failed", self.folder)
            report = f"verify failed: {type(exc).__name__}: {exc}"
        self.done.emit(report)


class PlanFolderWindow(QMainWindow):
    """The review window of one plan folder (see the module docstring). ``cursor`` is the row shown;
    ``findings`` fills when verify has run (``verified`` is emitted with its report or error text)."""

    verified = Signal(object)

    def __init__(self, folder: PlanFolder, parent: QWidget | None = None):
        super().__init__(parent)
        self.folder = folder
        self.cursor = 0
        self.report = None
        inp = folder.inputs()
        name = folder.summary.get("blade", {}).get("name") if isinstance(folder.summary.get("blade"), dict) else None
        self.setWindowTitle(f"{folder.path.name} · plan folder (read-only) · bladecam")
        self.resize(1300, 820)
        central = QWidget()
        layout = QVBoxLayout(central)
        head = QLabel(f"<b>Plan folder {folder.path}</b> (read-only){f' · blade {name}' if name else ''}"
                      f" · {len(folder.t):,} rows every {folder.summary.get('period_ms', '?')} ms"
                      f" · mode {inp.get('mode', '?')}<br>{folder.what_is_possible()}")
        head.setWordWrap(True)
        head.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        layout.addWidget(head)
        self.header = head
        cursor_row = QHBoxLayout()
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, len(folder.t) - 1)
        self.slider.valueChanged.connect(self.set_cursor)
        self.cursor_label = QLabel()
        cursor_row.addWidget(QLabel("cursor"))
        cursor_row.addWidget(self.slider, 1)
        cursor_row.addWidget(self.cursor_label)
        layout.addLayout(cursor_row)
        self.machines = QTableWidget(2, 0)
        self.machines.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        layout.addWidget(QLabel("<b>The machines at the cursor</b> (the rows of the tables as written)"))
        layout.addWidget(self.machines)
        split = QSplitter(Qt.Orientation.Horizontal)
        self.tables = QTabWidget()
        self.views: dict[str, QTableView] = {}
        names = [f"{side}_cl.csv" for side in SIDES]
        if folder.axes is not None:
            names += [f"{side}_axes.csv" for side in SIDES]
        for name in names:
            self._add_table(name, TextTable(folder.path / name))
        split.addWidget(self.tables)
        box = QWidget()
        box_layout = QVBoxLayout(box)
        box_layout.setContentsMargins(0, 0, 0, 0)
        self.verify_label = QLabel("<b>verify</b>: checking the folder…")
        self.verify_label.setWordWrap(True)
        self.findings = QListWidget()
        box_layout.addWidget(self.verify_label)
        box_layout.addWidget(self.findings, 1)
        split.addWidget(box)
        split.setSizes([800, 500])
        layout.addWidget(split, 1)
        self.setCentralWidget(central)
        self._spacing = folder.spacing()
        self.set_cursor(0)
        self._start_verify()

    def _add_table(self, name: str, model: TextTable) -> None:
        view = QTableView()
        view.setModel(model)
        view.verticalHeader().setDefaultSectionSize(20)
        view.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        view.clicked.connect(lambda index: self.slider.setValue(index.row()))
        self.tables.addTab(view, name)
        self.views[name] = view

    # -- the cursor ------------------------------------------------------------------------------
    def machine_rows(self, i: int) -> tuple[list[str], list[list[str]]]:
        """(column names, one row per side) of what the machines' tables hold at row ``i``."""
        cols = ["step", "region", "path", "cutting", "tip x", "tip y", "tip z", "axis i", "axis j", "axis k"]
        if self.folder.axes is not None:
            cols = [*AXIS_VALUES, *cols]
        out = []
        for side in SIDES:
            cl = self.folder.cl[side]
            row = [str(int(cl["step"][i])), REGION_NAMES[int(cl["region"][i])], str(int(cl["path"][i])),
                   "yes" if cl["cutting"][i] else "no", *(f"{v:.4f}" for v in cl["p"][i]),
                   *(f"{v:.6f}" for v in cl["w"][i])]
            if self.folder.axes is not None:
                a = self.folder.axes[side][i]
                row = [*(f"{a[1 + k]:.4f}" for k in range(len(AXIS_VALUES))), *row]
            out.append(row)
        return cols, out

    @Slot(int)
    def set_cursor(self, i: int) -> None:
        i = max(0, min(int(i), len(self.folder.t) - 1))
        self.cursor = i
        if self.slider.value() != i:
            self.slider.setValue(i)
        cols, rows = self.machine_rows(i)
        self.machines.setColumnCount(len(cols))
        self.machines.setHorizontalHeaderLabels(cols)
        self.machines.setVerticalHeaderLabels([f"{side} machine" for side in SIDES])
        for r, row in enumerate(rows):
            for c, text in enumerate(row):
                self.machines.setItem(r, c, QTableWidgetItem(text))
        self.machines.resizeColumnsToContents()
        self.machines.setFixedHeight(self.machines.horizontalHeader().height()
                                     + sum(self.machines.rowHeight(r) for r in range(2)) + 4)
        self.cursor_label.setText(f"row {i:,} · t = {self.folder.t[i]:.3f} ms · tip spacing "
                                  f"{self._spacing[i]:.4f} mm")
        for view in self.views.values():
            view.selectRow(i)

    # -- verify ----------------------------------------------------------------------------------
    def _start_verify(self) -> None:
        self._thread = QThread(self)
        self._verifier = _Verifier(self.folder.path)
        self._verifier.moveToThread(self._thread)
        self._thread.started.connect(self._verifier.run)
        self._verifier.done.connect(self._on_verified)
        self._verifier.done.connect(self._thread.quit)
        self._thread.start()

    @Slot(object)
    def _on_verified(self, report) -> None:
        self.report = report
        self.findings.clear()
        if isinstance(report, str):
            self.verify_label.setText(f"<b>verify</b>: could not check the folder: {report}")
        else:
            self.verify_label.setText(f"<b>verify</b>: {report.summary()}"
                                      + (f"<br><i>{report.trusted}</i>" if report.trusted else ""))
            for kind, line in zip(report.kinds, report.findings, strict=True):
                self.findings.addItem(f"{kind}: {line}")
            if not report.findings:
                self.findings.addItem("no findings: the tables keep every rule verify checks")
        self.verified.emit(report)

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        try:
            if self._thread.isRunning():  # (verify runs to its end: it cannot be interrupted)
                self._thread.quit()
                self._thread.wait()
            for view in self.views.values():
                view.model().close()
        finally:
            super().closeEvent(event)
