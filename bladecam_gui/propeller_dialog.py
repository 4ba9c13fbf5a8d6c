"""The dialog that asks which blade of a whole propeller to open (a mesh or CAD file of the whole
propeller): it shows the blades found outside the hub cut (core.blade.propeller.listing, as
``bladecam blade info`` does), the blade's number (default 1), and the hub cut: found from the geometry
by default, or a radius the operator gives."""

from __future__ import annotations

from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import (
    QCheckBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QLabel,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from core.blade.propeller import Propeller, listing


class PropellerDialog(QDialog):
    """Which blade of ``propeller`` (read from the file named ``name``) to open, and where to cut its hub."""

    def __init__(self, propeller: Propeller, name: str, parent: QWidget | None = None):
        super().__init__(parent)
        n = len(propeller.blades)
        self.setWindowTitle("Whole propeller")
        layout = QVBoxLayout(self)
        self.count = QLabel(f"{name} is a whole propeller of {n} blades. Which blade is to be machined?")
        layout.addWidget(self.count)
        table = QLabel("\n".join(listing({**propeller.summary(), "picked": None}, False)))
        table.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        layout.addWidget(table)
        form = QFormLayout()
        self.blade = QSpinBox()
        self.blade.setRange(1, n)
        form.addRow("Blade", self.blade)
        self.found = QCheckBox("Cut the hub where it is found from the geometry")
        self.found.setChecked(not propeller.r_min_given)
        self.r_min = QDoubleSpinBox()
        self.r_min.setDecimals(3)
        self.r_min.setRange(0.0, max(b.r_to for b in propeller.blades))
        self.r_min.setSuffix(" mm")
        self.r_min.setValue(propeller.r_min)
        self.r_min.setEnabled(propeller.r_min_given)
        self.found.toggled.connect(lambda on: self.r_min.setEnabled(not on))
        form.addRow(self.found)
        form.addRow("Hub cut r_min", self.r_min)
        layout.addLayout(form)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout.addWidget(buttons)

    def choice(self) -> tuple[int, float | None]:
        """(the blade's number from 1, the hub cut in mm or None: found from the geometry)."""
        return self.blade.value(), None if self.found.isChecked() else float(self.r_min.value())
