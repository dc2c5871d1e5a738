"""The Quantities dock: area and enclosed volume of the isosurfaces, length and enclosed area
of their cross sections, over time.

*Measure* tabulates every isosurface and section at every time step (one step for a scene
that does not vary) from the spline surface itself
(:func:`splineviz.model.quantities.quantities_over_time`, in a job: the GUI thread measures
nothing), plots area and volume against time with matplotlib (one line per object) and
*Export CSV...* writes the table.
"""

from __future__ import annotations

import math

from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from PySide6.QtWidgets import (
    QFileDialog,
    QHBoxLayout,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from splineviz.model.quantities import QuantityTable, quantities_over_time


class QuantitiesPanel(QWidget):
    """Table and plot of area and enclosed volume per isosurface and time step.

    Attributes
    ----------
    table : QuantityTable or None
        The last measured table.
    """

    def __init__(self, scene, jobs, parent=None):
        super().__init__(parent)
        self.scene = scene
        self.jobs = jobs
        self.table: QuantityTable | None = None
        self._job = None
        self.measure_button = QPushButton("Measure")
        self.measure_button.setToolTip("Area and enclosed volume of every isosurface at every "
                                       "time step, from the spline surface")
        self.export_button = QPushButton("Export CSV...")
        self.export_button.setEnabled(False)
        self.export_button.setToolTip("Write the table as a CSV file")
        self.grid = QTableWidget(0, 6)
        self.grid.setHorizontalHeaderLabels(["step", "time", "object", "area", "volume",
                                             "length"])
        self.grid.setToolTip("Per time step: area and enclosed volume of each isosurface "
                             "(empty where it leaves the data box), length and enclosed area "
                             "of each cross section")
        self.figure = Figure(figsize=(3.0, 3.0), layout="constrained")
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.canvas.setMinimumHeight(180)
        lay = QVBoxLayout(self)
        row = QHBoxLayout()
        row.addWidget(self.measure_button)
        row.addWidget(self.export_button)
        row.addStretch(1)
        lay.addLayout(row)
        lay.addWidget(self.canvas, 2)
        lay.addWidget(self.grid, 1)
        self.measure_button.clicked.connect(self.measure)
        self.export_button.clicked.connect(self._export_clicked)

    def measure(self) -> None:
        """Measure in a job; the table and plot follow when it is done."""
        if self._job is not None or not self.scene.isosurfaces:
            return
        self.measure_button.setEnabled(False)
        self._job = self.jobs.run("measuring isosurfaces", self._measure, on_done=self._done,
                                  on_error=self._failed)

    def _measure(self, job=None) -> QuantityTable:
        # cancelled (Esc): the steps measured so far
        return quantities_over_time(
            self.scene, cancelled=None if job is None else lambda: job.cancelled)

    def _done(self, table: QuantityTable) -> None:
        self._job = None
        self.measure_button.setEnabled(True)
        self.show_table(table)

    def _failed(self, exc) -> None:
        from splineviz.gui.jobs import error_message

        self._job = None
        self.measure_button.setEnabled(True)
        self.jobs.error.emit(f"measuring failed: {error_message(exc)}")

    def show_table(self, table: QuantityTable) -> None:
        """Fill the grid and draw area and volume against time."""
        self.table = table
        self.export_button.setEnabled(bool(table.rows))
        self.grid.setRowCount(len(table.rows))
        for r, row in enumerate(table.rows):
            for c, value in enumerate(row):
                if isinstance(value, float):  # no volume of an open surface: left empty
                    text = "" if math.isnan(value) else f"{value:.8g}"
                else:
                    text = str(value)
                self.grid.setItem(r, c, QTableWidgetItem(text))
        self.figure.clear()
        area_ax, vol_ax = self.figure.subplots(2, 1, sharex=True)
        lu, tu = table.length_unit, table.time_unit
        for name in dict.fromkeys(table.column("object")):
            t = table.column("time", name)
            area_ax.plot(t, table.column("area", name), marker="o", label=name)
            vols = table.column("volume", name)
            if not all(math.isnan(v) for v in vols):
                vol_ax.plot(t, vols, marker="o", label=name)
        area_ax.set_ylabel(f"area [{lu}²]" if lu else "area")
        vol_ax.set_ylabel(f"volume [{lu}³]" if lu else "volume")
        vol_ax.set_xlabel(f"time [{tu}]" if tu else "time step")
        area_ax.legend(fontsize="small")
        self.canvas.draw_idle()

    def export_csv(self, path) -> None:
        """Write the last table to ``path``."""
        if self.table is not None:
            self.table.to_csv(path)

    def _export_clicked(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Export quantities", "quantities.csv",
                                              "CSV (*.csv)")
        if path:
            self.export_csv(path)
