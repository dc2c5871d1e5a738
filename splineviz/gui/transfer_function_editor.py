"""The transfer function editor of the volume rendering panel, as in ParaView's colour-map
editor and Slicer's volume property: the data's histogram (log counts) behind the opacity
curve, the colour map in a bar below.

Opacity (the curve over the histogram): drag a point to move it (it stays between its
neighbours, so the points stay in value order), click empty space to add one there, right-click
a point or select it and press Delete to remove it (two always stay). Colour (the markers on
the bar): drag a marker along the bar, double-click it to choose its colour, double-click the
bar between markers to add one there (its colour the map's there), right-click or Delete to
remove one (two always stay).

The widget holds the points being edited; it tells of edits through signals and never writes
the model itself (:class:`~splineviz.gui.panels.volume_rendering.VolumeRenderingPanel` does,
coalesced while a drag lasts).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QLinearGradient, QPainter, QPainterPath, QPen, QPolygonF
from PySide6.QtWidgets import QColorDialog, QSizePolicy, QWidget

#: pixels around a point that pick it
PICK_PX = 7.0
#: height of the colour bar in pixels
BAR_PX = 18.0
#: margin around the plot and the bar in pixels
MARGIN_PX = 6.0
#: points of each kind that removal leaves at least
MIN_POINTS = 2


class TransferFunctionEditor(QWidget):
    """Opacity points over a histogram and colour points on a bar (see module docstring).

    Signals
    -------
    pressed()
        A drag of a point starts (an added opacity point is dragged from its click).
    edited()
        The points changed by the user (on every step of a drag).
    released()
        The drag ended.
    """

    pressed = Signal()
    edited = Signal()
    released = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMinimumHeight(150)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.setToolTip("Opacity over the data's histogram: drag points, click to add, "
                        "right-click or Delete to remove.\nColour bar: double-click a marker "
                        "to choose its colour, double-click the bar to add one")
        self._counts = np.zeros(1)
        self._range = (0.0, 1.0)
        self._rgb = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]])
        self._opacity = np.array([[0.0, 0.0], [1.0, 1.0]])
        #: the point dragged: ("opacity" | "rgb", index), or None
        self._drag: tuple | None = None
        #: the point Delete removes: ("opacity" | "rgb", index), or None
        self.selected: tuple | None = None

    # -- data ----------------------------------------------------------------------------

    def set_histogram(self, counts: np.ndarray, edges: np.ndarray) -> None:
        """Show ``(bins,)`` log counts over ``(bins + 1,)`` edges behind the curve (see
        :func:`~splineviz.model.summaries.log_histogram`); the edges are the value range
        shown."""
        self._counts = np.asarray(counts, np.float64)
        edges = np.asarray(edges, np.float64)
        self._range = (float(edges[0]), float(edges[-1]) if edges[-1] > edges[0]
                       else float(edges[0]) + 1.0)
        self.update()

    def set_points(self, rgb_points: np.ndarray, opacity_points: np.ndarray) -> None:
        """Show ``(n, 4)`` (value, r, g, b) and ``(m, 2)`` (value, opacity) points (no
        :attr:`edited` signal); a drag under way is given up."""
        shapes = (self._rgb.shape, self._opacity.shape)
        self._rgb = np.array(rgb_points, np.float64).reshape(-1, 4)
        self._opacity = np.array(opacity_points, np.float64).reshape(-1, 2)
        if self._drag is not None:
            self._drag = None
            self.released.emit()
        if shapes != (self._rgb.shape, self._opacity.shape):
            self.selected = None  # (the same points moved or recoloured keep it)
        self.update()

    @property
    def dragging(self) -> bool:
        return self._drag is not None

    def rgb_points(self) -> np.ndarray:
        """``(n, 4)`` (value, r, g, b), values non-decreasing."""
        return self._rgb.copy()

    def opacity_points(self) -> np.ndarray:
        """``(m, 2)`` (value, opacity), values non-decreasing."""
        return self._opacity.copy()

    def value_range(self) -> tuple[float, float]:
        """The values across the widget: the histogram's, widened to every point."""
        lo = min(self._range[0], self._rgb[0, 0], self._opacity[0, 0])
        hi = max(self._range[1], self._rgb[-1, 0], self._opacity[-1, 0])
        return float(lo), float(hi) if hi > lo else float(lo) + 1.0

    # -- geometry ------------------------------------------------------------------------

    def plot_rect(self) -> QRectF:
        """Where the histogram and the opacity curve are drawn."""
        h = max(self.height() - 3 * MARGIN_PX - BAR_PX, 1.0)
        return QRectF(MARGIN_PX, MARGIN_PX, max(self.width() - 2 * MARGIN_PX, 1.0), h)

    def bar_rect(self) -> QRectF:
        """Where the colour bar is drawn."""
        r = self.plot_rect()
        return QRectF(r.left(), r.bottom() + MARGIN_PX, r.width(), BAR_PX)

    def _x_of(self, v: float) -> float:
        r = self.plot_rect()
        lo, hi = self.value_range()
        return r.left() + (v - lo) / (hi - lo) * r.width()

    def _v_of(self, x: float) -> float:
        r = self.plot_rect()
        lo, hi = self.value_range()
        return lo + (x - r.left()) / r.width() * (hi - lo)

    def _y_of(self, a: float) -> float:
        r = self.plot_rect()
        return r.bottom() - a * r.height()

    def _a_of(self, y: float) -> float:
        r = self.plot_rect()
        return float(np.clip((r.bottom() - y) / r.height(), 0.0, 1.0))

    def point_position(self, kind: str, index: int) -> QPointF:
        """Where point ``index`` of ``kind`` ("opacity" or "rgb") is drawn, in pixels."""
        if kind == "opacity":
            v, a = self._opacity[index]
            return QPointF(self._x_of(v), self._y_of(a))
        return QPointF(self._x_of(self._rgb[index, 0]), self.bar_rect().center().y())

    def _hit(self, pos: QPointF) -> tuple | None:
        """The point under ``pos`` (the nearest within :data:`PICK_PX`), or None."""
        kind = "rgb" if self._on_bar(pos) else "opacity"
        best, best_d = None, PICK_PX
        for i in range(len(self._rgb if kind == "rgb" else self._opacity)):
            q = self.point_position(kind, i)
            d = abs(q.x() - pos.x()) if kind == "rgb" else float(np.hypot(
                q.x() - pos.x(), q.y() - pos.y()))
            if d <= best_d:
                best, best_d = (kind, i), d
        return best

    def _on_bar(self, pos: QPointF) -> bool:
        """Whether ``pos`` is below the plot: on the colour bar or its markers."""
        return pos.y() > self.plot_rect().bottom() + MARGIN_PX / 2

    # -- edits ---------------------------------------------------------------------------

    def _move(self, target: tuple, pos: QPointF) -> None:
        """Move the point ``target`` to ``pos``: its value between its neighbours' (and
        within the range shown), an opacity point's opacity to the height."""
        kind, i = target
        pts = self._opacity if kind == "opacity" else self._rgb
        lo, hi = self.value_range()
        left = pts[i - 1, 0] if i > 0 else lo
        right = pts[i + 1, 0] if i + 1 < len(pts) else hi
        pts[i, 0] = float(np.clip(self._v_of(pos.x()), left, right))
        if kind == "opacity":
            pts[i, 1] = self._a_of(pos.y())

    def _insert(self, kind: str, row) -> int:
        pts = self._opacity if kind == "opacity" else self._rgb
        i = int(np.searchsorted(pts[:, 0], row[0], side="right"))
        pts = np.insert(pts, i, row, axis=0)
        if kind == "opacity":
            self._opacity = pts
        else:
            self._rgb = pts
        return i

    def add_opacity_point(self, value: float, opacity: float) -> int:
        """Insert an opacity point in value order; its index."""
        i = self._insert("opacity", [float(value), float(np.clip(opacity, 0.0, 1.0))])
        self.selected = ("opacity", i)
        self.update()
        self.edited.emit()
        return i

    def add_rgb_point(self, value: float) -> int:
        """Insert a colour point with the map's colour at ``value``; its index."""
        rgb = [float(np.interp(value, self._rgb[:, 0], self._rgb[:, c])) for c in (1, 2, 3)]
        i = self._insert("rgb", [float(value), *rgb])
        self.selected = ("rgb", i)
        self.update()
        self.edited.emit()
        return i

    def remove_point(self, kind: str, index: int) -> bool:
        """Remove a point unless only :data:`MIN_POINTS` of its kind are left."""
        pts = self._opacity if kind == "opacity" else self._rgb
        if len(pts) <= MIN_POINTS:
            return False
        pts = np.delete(pts, index, axis=0)
        if kind == "opacity":
            self._opacity = pts
        else:
            self._rgb = pts
        self.selected = None
        self.update()
        self.edited.emit()
        return True

    def set_point_color(self, index: int, color) -> None:
        """Colour point ``index`` becomes ``color`` (RGB in [0, 1])."""
        self._rgb[index, 1:] = np.clip(np.asarray(color, np.float64), 0.0, 1.0)
        self.update()
        self.edited.emit()

    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour (None: cancelled)."""
        c = QColorDialog.getColor(initial, self, "Colour of the transfer function point")
        return c if c.isValid() else None

    # -- Qt events -----------------------------------------------------------------------

    def paintEvent(self, _event):  # noqa: N802
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        r = self.plot_rect()
        p.fillRect(r, QColor(36, 36, 44))
        self._paint_histogram(p, r)
        self._paint_curve(p, r)
        self._paint_bar(p)
        p.end()

    def _paint_histogram(self, p: QPainter, r: QRectF) -> None:
        top = float(self._counts.max()) if self._counts.size and self._counts.max() > 0 else 1.0
        x0, x1 = self._x_of(self._range[0]), self._x_of(self._range[1])
        n = len(self._counts)
        path = QPainterPath(QPointF(x0, r.bottom()))
        for i, c in enumerate(self._counts):
            y = r.bottom() - c / top * r.height()
            path.lineTo(x0 + i / n * (x1 - x0), y)
            path.lineTo(x0 + (i + 1) / n * (x1 - x0), y)
        path.lineTo(x1, r.bottom())
        path.closeSubpath()
        p.fillPath(path, QColor(90, 100, 120))

    def _paint_curve(self, p: QPainter, r: QRectF) -> None:
        # constant beyond the end points, as the renderers' table is
        pts = [QPointF(r.left(), self._y_of(self._opacity[0, 1]))]
        pts += [QPointF(self._x_of(v), self._y_of(a)) for v, a in self._opacity]
        pts.append(QPointF(r.right(), self._y_of(self._opacity[-1, 1])))
        area = QPolygonF([QPointF(r.left(), r.bottom()), *pts, QPointF(r.right(), r.bottom())])
        p.setPen(Qt.PenStyle.NoPen)
        p.setBrush(QColor(255, 255, 255, 40))
        p.drawPolygon(area)
        p.setPen(QPen(QColor(240, 240, 240), 1.5))
        p.drawPolyline(QPolygonF(pts))
        for i in range(len(self._opacity)):
            chosen = self.selected == ("opacity", i)
            p.setBrush(QColor(255, 200, 80) if chosen else QColor(250, 250, 250))
            p.setPen(QPen(QColor(20, 20, 20), 1))
            p.drawEllipse(self.point_position("opacity", i), 4.5, 4.5)

    def _paint_bar(self, p: QPainter) -> None:
        b = self.bar_rect()
        grad = QLinearGradient(b.left(), 0.0, b.right(), 0.0)
        for v, cr, cg, cb in self._rgb:
            t = (self._x_of(v) - b.left()) / b.width()
            grad.setColorAt(float(np.clip(t, 0.0, 1.0)), QColor.fromRgbF(cr, cg, cb))
        p.setPen(Qt.PenStyle.NoPen)
        p.setBrush(grad)
        p.drawRect(b)
        for i, (_v, cr, cg, cb) in enumerate(self._rgb):
            q = self.point_position("rgb", i)
            chosen = self.selected == ("rgb", i)
            p.setPen(QPen(QColor(255, 200, 80) if chosen else QColor(250, 250, 250), 2))
            p.setBrush(QColor.fromRgbF(cr, cg, cb))
            p.drawRect(QRectF(q.x() - 4, b.top() - 3, 8, b.height() + 6))

    def mousePressEvent(self, event):  # noqa: N802
        pos = event.position()
        hit = self._hit(pos)
        if event.button() == Qt.MouseButton.RightButton:
            if hit is not None:
                self.remove_point(*hit)
            return
        if event.button() != Qt.MouseButton.LeftButton:
            return
        if hit is None and not self._on_bar(pos):
            hit = ("opacity", self._insert("opacity", [self._v_of(pos.x()),
                                                       self._a_of(pos.y())]))
            added = True
        else:
            added = False
        self.selected = hit
        self.update()
        if hit is not None:
            self._drag = hit
            self.pressed.emit()
            if added:
                self.edited.emit()

    def mouseMoveEvent(self, event):  # noqa: N802
        if self._drag is None or not event.buttons() & Qt.MouseButton.LeftButton:
            return
        self._move(self._drag, event.position())
        self.update()
        self.edited.emit()

    def mouseReleaseEvent(self, event):  # noqa: N802
        if self._drag is not None and event.button() == Qt.MouseButton.LeftButton:
            self._drag = None
            self.released.emit()

    def mouseDoubleClickEvent(self, event):  # noqa: N802
        pos = event.position()
        if event.button() != Qt.MouseButton.LeftButton or not self._on_bar(pos):
            return
        hit = self._hit(pos)
        if hit is None:
            self.add_rgb_point(self._v_of(pos.x()))
            return
        i = hit[1]
        color = self.choose_color(QColor.fromRgbF(*self._rgb[i, 1:]))
        if color is not None:
            self.set_point_color(i, (color.redF(), color.greenF(), color.blueF()))

    def keyPressEvent(self, event):  # noqa: N802
        if event.key() in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace) and \
                self.selected is not None:
            self.remove_point(*self.selected)
            return
        super().keyPressEvent(event)
