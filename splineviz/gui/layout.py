"""The window's view layouts (View > Layout): the 3-D view alone, the 3-D view with the
axial, coronal and sagittal slices (3D Slicer's "four-up"), or one slice alone.

The layout is :attr:`splineviz.model.slices.SliceViewNode.layout` (kept in sessions
through the scene's view, :mod:`splineviz.gui.slice_views`); :class:`ViewLayout` follows
it. The central widget is a vertical splitter of two rows: the top row holds the 3-D views
(:class:`~splineviz.gui.split.LinkedViews`' splitter) and the axial slice, the bottom row
the coronal and sagittal slices. A layout hides the panes it does not use (the
3-D view keeps its widget and OpenGL context). The slice views are made when a layout
first shows them: black panes take their places at once (the 3-D view is resized once),
then each view is made in one turn of the event loop and replaces its pane in the next
(a new OpenGL context and its first paint), so that no step holds the GUI thread long.
"""

from __future__ import annotations

from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QAction, QActionGroup, QColor, QPalette
from PySide6.QtWidgets import QSplitter, QWidget

from splineviz.gui.slice_views import SliceViews
from splineviz.model.slices import SLICE_COLORMAPS

#: (layout, single slice, menu text, tooltip) of View > Layout
LAYOUT_CHOICES = (
    ("3d", None, "&3-D only", "The 3-D view alone"),
    ("four-up", None, "&Four-up: 3-D and three slices",
     "The 3-D view with the axial, coronal and sagittal slices (3D Slicer's four-up)"),
    ("one-slice", "axial", "&Axial slice", "The axial slice (normal to z) alone"),
    ("one-slice", "coronal", "&Coronal slice", "The coronal slice (normal to y) alone"),
    ("one-slice", "sagittal", "&Sagittal slice", "The sagittal slice (normal to x) alone"),
)
#: where each slice view sits: (row, column) of the two rows
SLOTS = {"axial": (0, 1), "coronal": (1, 0), "sagittal": (1, 1)}


class ViewLayout:
    """The central widget and the slice views of a main window (see module docstring).

    Parameters
    ----------
    window : splineviz.gui.main_window.MainWindow
        Owner of the scene, the 3-D view (``view``), its split (``linked_views``), the
        readout label and the error display.
    """

    def __init__(self, window):
        self.window = window
        self.slices = SliceViews(window.scene, window.view, window)
        self.state = self.slices.state
        self.widget = QSplitter(Qt.Orientation.Vertical, window)
        self.widget.setObjectName("layout")
        self.widget.setChildrenCollapsible(False)
        self.rows = [QSplitter(Qt.Orientation.Horizontal), QSplitter(Qt.Orientation.Horizontal)]
        for row in self.rows:
            row.setChildrenCollapsible(False)
            self.widget.addWidget(row)
        self.rows[0].addWidget(window.linked_views.splitter)
        self.rows[1].hide()
        #: slice views still to make (in steps), and the panes holding their places
        self._to_make: list[str] = []
        self._stand_ins: dict[str, QWidget] = {}
        self._sized = False
        self._make_timer = QTimer(self.widget)
        self._make_timer.setSingleShot(True)
        self._make_timer.setInterval(16)
        self._make_timer.timeout.connect(self._make_next)
        self.slices.readout.connect(window.readout_label.setText)
        self.slices.error.connect(window.show_error)
        self.state.events.layout.connect(self._apply)
        self.state.events.single.connect(self._apply)
        self.actions: dict[tuple, QAction] = {}
        if self.state.shown:  # the scene's view asks for slices (a session's layout)
            QTimer.singleShot(0, self.widget, self._apply)

    @property
    def views(self) -> dict:
        """The slice views made so far, by name."""
        return self.slices.views

    def set_layout(self, layout: str, single: str | None = None) -> None:
        """Switch to a layout (see :data:`LAYOUT_CHOICES`)."""
        if single is not None:
            self.state.update(layout=layout, single=single)
        else:
            self.state.layout = layout

    @property
    def ready(self) -> bool:
        """Whether every slice of the layout has its view in place."""
        return not self._to_make and all(name in self.views for name in self.state.shown)

    def _apply(self, *_):
        missing = [n for n in self.state.shown if n not in self.views
                   and n not in self._stand_ins]
        for name in missing:
            self._make_room(name)
            self._to_make.append(name)
        if self._to_make and not self._make_timer.isActive():
            self._make_timer.start()
        self._show_panes()
        key = (self.state.layout, self.state.single if self.state.layout == "one-slice"
               else None)
        action = self.actions.get(key)
        if action is not None and not action.isChecked():
            action.setChecked(True)

    def _make_room(self, name: str) -> None:
        """A plain black pane holds the slot of a view not made yet: the layout (and the 3-D
        view's size) changes once, not again as each view arrives."""
        pane = QWidget()
        palette = pane.palette()
        palette.setColor(QPalette.ColorRole.Window, QColor(0, 0, 0))
        pane.setPalette(palette)
        pane.setAutoFillBackground(True)
        pane.setMinimumSize(120, 120)
        row, col = SLOTS[name]
        # the slot's place: the axial view right of the 3-D view, the others in order
        self.rows[row].insertWidget(min(col, self.rows[row].count()), pane)
        self._stand_ins[name] = pane

    def _make_next(self) -> None:
        """One step of making the slice views: a view's widget (hidden; 50-110 ms on a busy
        machine), then in the next turn it takes its pane's place (its first paint)."""
        if not self._to_make:
            return
        name = self._to_make[0]
        row = self.rows[SLOTS[name][0]]
        if name not in self.views:
            # made inside its row: a widget made without a parent is a window of its own,
            # whose native window kept the mouse events after it moved into the row
            view = self.slices.make_view(name, row)
            view.widget.hide()
        else:
            self._to_make.pop(0)
            pane = self._stand_ins.pop(name)
            view = self.views[name]
            # the view is already the row's (QSplitter takes its child widgets, at the end):
            # moved to the pane's place with the pane's size, the pane dropped
            share = dict(zip((row.widget(i) for i in range(row.count())), row.sizes(),
                             strict=True))
            row.insertWidget(row.indexOf(pane), view.widget)
            pane.hide()
            pane.setParent(None)
            pane.deleteLater()
            share[view.widget] = share.get(pane, 0)
            row.setSizes([share.get(row.widget(i), 0) for i in range(row.count())])
            self._show_panes()
        if self._to_make:
            self._make_timer.start()

    def _show_panes(self) -> None:
        shown = self.state.shown
        self.window.linked_views.splitter.setVisible(self.state.layout != "one-slice")
        for name, pane in self._stand_ins.items():
            pane.setVisible(name in shown)
        for name, view in self.views.items():
            if name not in self._stand_ins:
                view.widget.setVisible(name in shown)
        for row in self.rows:
            row.setVisible(any(not row.widget(i).isHidden() for i in range(row.count())))
        if self.state.layout == "four-up" and not self._sized:
            # halves when the layout is first shown and again once its views are in their
            # places (a view replacing its pane takes its own share; the splitter has laid
            # it out in the next turn); later, the user's splitter drags stay
            self._halve()
            if not self._to_make:
                self._sized = True
                QTimer.singleShot(0, self._halve)

    def _halve(self) -> None:
        """The four panes of the four-up layout the same size."""
        if self.state.layout != "four-up":
            return
        for splitter in (*self.rows, self.widget):
            n = splitter.count()
            total = sum(splitter.sizes()) or (splitter.height() if splitter is self.widget
                                              else splitter.width())
            splitter.setSizes([total // n] * (n - 1) + [total - (n - 1) * (total // n)])

    def add_menu(self, menu_bar) -> None:
        """View > Layout (in ``menu_bar``'s View menu): the choices of
        :data:`LAYOUT_CHOICES`, one checked."""
        view_menu = next(a.menu() for a in menu_bar.actions()
                         if a.menu() is not None and a.text().replace("&", "") == "View")
        menu = view_menu.addMenu("&Layout")
        group = QActionGroup(menu)
        group.setExclusive(True)
        for layout, single, text, tip in LAYOUT_CHOICES:
            action = QAction(text, menu)
            action.setCheckable(True)
            action.setToolTip(tip)
            action.setStatusTip(tip)
            action.triggered.connect(lambda _=False, la=layout, s=single:
                                     self.set_layout(la, s))
            group.addAction(action)
            menu.addAction(action)
            self.actions[(layout, single)] = action
        self.actions[("3d", None)].setChecked(True)
        menu.addSeparator()
        maps = menu.addMenu("Slice &colour map")
        maps_group = QActionGroup(maps)
        for name in SLICE_COLORMAPS:
            action = QAction(name, maps)
            action.setCheckable(True)
            action.setChecked(name == self.state.color_map)
            action.triggered.connect(lambda _=False, n=name: setattr(self.state, "color_map", n))
            maps_group.addAction(action)
            maps.addAction(action)
            self.actions[("color_map", name)] = action
        self.state.events.color_map.connect(
            lambda name: self.actions[("color_map", name)].setChecked(True))
        reset = QAction("&Reset slice window / level", menu)
        tip = "Window / level of the slices from the data (2-98 % of the samples)"
        reset.setToolTip(tip)
        reset.setStatusTip(tip)
        reset.triggered.connect(self.slices.reset_window)
        menu.addAction(reset)
        self.actions[("reset_window", None)] = reset
        self.menu = menu

    def close(self) -> None:
        self._make_timer.stop()
        self._to_make.clear()
        self.slices.close()
