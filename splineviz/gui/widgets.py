"""Small Qt widgets: the isovalue slider over the data histogram, a colour button."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QPainter, QPainterPath, QPen
from PySide6.QtWidgets import QColorDialog, QPushButton, QSizePolicy, QWidget

from splineviz.model.summaries import HISTOGRAM_BINS, log_histogram


class HistogramSlider(QWidget):
    """A horizontal value slider drawn over the log histogram of the data.

    Click or drag to set the value; arrow keys step by one bin (Page Up/Down by ten).
    Emits :attr:`pressed` when a drag starts, :attr:`valueChanged` (float) while dragging
    and :attr:`released` when the mouse is released.
    """

    valueChanged = Signal(float)
    pressed = Signal()
    released = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMinimumHeight(60)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self._counts = np.zeros(HISTOGRAM_BINS)
        self._edges = np.linspace(0.0, 1.0, HISTOGRAM_BINS + 1)
        self._value = 0.5
        self.setToolTip("Isovalue: drag over the histogram of the data (log counts)")

    # -- data ----------------------------------------------------------------------------

    def set_data(self, data: np.ndarray) -> None:
        self.set_histogram(*log_histogram(data))

    def set_histogram(self, counts: np.ndarray, edges: np.ndarray) -> None:
        """Show ``(bins,)`` log counts over ``(bins + 1,)`` edges (see :func:`log_histogram`;
        computed in a worker for big volumes)."""
        self._counts, self._edges = np.asarray(counts), np.asarray(edges)
        self.update()

    def range(self) -> tuple[float, float]:
        return float(self._edges[0]), float(self._edges[-1])

    def value(self) -> float:
        return self._value

    def setValue(self, value: float) -> None:  # noqa: N802 (Qt naming)
        lo, hi = self.range()
        v = float(np.clip(value, lo, hi))
        if v != self._value:
            self._value = v
            self.update()
            self.valueChanged.emit(v)

    # -- geometry ------------------------------------------------------------------------

    def _plot_rect(self) -> QRectF:
        return QRectF(6, 4, max(self.width() - 12, 1), max(self.height() - 8, 1))

    def _x_of(self, v: float) -> float:
        r = self._plot_rect()
        lo, hi = self.range()
        return r.left() + (v - lo) / (hi - lo) * r.width()

    def _v_of(self, x: float) -> float:
        r = self._plot_rect()
        lo, hi = self.range()
        return lo + (x - r.left()) / r.width() * (hi - lo)

    # -- Qt events -----------------------------------------------------------------------

    def paintEvent(self, _event):  # noqa: N802
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        r = self._plot_rect()
        p.fillRect(r, QColor(40, 40, 48))
        top = self._counts.max() if self._counts.max() > 0 else 1.0
        path = QPainterPath(QPointF(r.left(), r.bottom()))
        n = len(self._counts)
        for i, c in enumerate(self._counts):
            y = r.bottom() - c / top * r.height()
            path.lineTo(r.left() + i / n * r.width(), y)
            path.lineTo(r.left() + (i + 1) / n * r.width(), y)
        path.lineTo(r.right(), r.bottom())
        path.closeSubpath()
        p.fillPath(path, QColor(120, 140, 170))
        x = self._x_of(self._value)
        p.setPen(QPen(QColor(255, 200, 80), 2))
        p.drawLine(QPointF(x, r.top()), QPointF(x, r.bottom()))
        p.setBrush(QColor(255, 200, 80))
        p.drawEllipse(QPointF(x, r.bottom() - 4), 5, 5)
        p.end()

    def mousePressEvent(self, event):  # noqa: N802
        self.pressed.emit()
        self.setValue(self._v_of(event.position().x()))

    def mouseMoveEvent(self, event):  # noqa: N802
        if event.buttons() & Qt.MouseButton.LeftButton:
            self.setValue(self._v_of(event.position().x()))

    def mouseReleaseEvent(self, _event):  # noqa: N802
        self.released.emit()

    def keyPressEvent(self, event):  # noqa: N802
        step = (self._edges[1] - self._edges[0])
        key = event.key()
        factor = {Qt.Key.Key_Left: -1, Qt.Key.Key_Right: 1, Qt.Key.Key_PageDown: -10,
                  Qt.Key.Key_PageUp: 10}.get(key)
        if factor is None:
            super().keyPressEvent(event)
            return
        self.setValue(self._value + factor * step)
        self.released.emit()


class ColorButton(QPushButton):
    """A button showing a colour; clicking opens a colour dialog. Emits RGB in [0, 1]."""

    colorChanged = Signal(tuple)

    def __init__(self, color=(1.0, 1.0, 1.0), parent=None):
        super().__init__(parent)
        self.setFixedWidth(48)
        self._color = tuple(color)
        self._paint()
        self.clicked.connect(self._pick)

    def color(self) -> tuple:
        return self._color

    def setColor(self, color) -> None:  # noqa: N802
        self._color = tuple(float(c) for c in color)
        self._paint()

    def _paint(self):
        c = QColor.fromRgbF(*self._color)
        self.setStyleSheet(f"background-color: {c.name()}; border: 1px solid #555;")

    def _pick(self):
        c = QColorDialog.getColor(QColor.fromRgbF(*self._color), self, "Surface colour")
        if c.isValid():
            self.setColor((c.redF(), c.greenF(), c.blueF()))
            self.colorChanged.emit(self._color)
