"""Two linked side-by-side views of one scene (ParaView's split view with "Link Camera",
3D Slicer's linked views).

The split is a property of the scene model (:attr:`splineviz.model.ViewNode.split`), so a
session restores it and the View menu, a script or :meth:`splineviz.model.Scene.compare`
turn it on alike. :class:`LinkedViews` follows that property: it puts a second
:class:`~splineviz.gui.view.View3D` (side ``"right"``) beside the window's view in a splitter
when the split turns on and closes it when it turns off. Each view leaves out the objects
whose ``shown_in`` names the other side, so each can show its own isosurface (another spline
model, another isovalue) of the same volume.

Both views draw the one camera of the model: a drag in either moves VTK's camera there, the
view writes it into the model after the frame and the other view follows (one preview frame
later). While one view is dragged the other shows previews too, and both refine to exact
frames in their own workers once the drag ends.

The second view opens in steps, one per turn of the event loop (:data:`OPEN_STEPS`): made at
once, its widget, its scene, the first paint of a new OpenGL context (the blit shader of
software GL), the first frame of its props (their shaders) and the first view's repaint at
half the width held the GUI thread 380-550 ms in one piece; each step alone stays well under
the project's 100 ms. The view counts as open (:attr:`LinkedViews.second`) after the last.
"""

from __future__ import annotations

import time

import numpy as np
from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QColor, QPalette
from PySide6.QtWidgets import QSplitter, QWidget

from splineviz.gui.panels import PlaneWidgets
from splineviz.gui.view import View3D
from splineviz.model import IsosurfaceNode, VolumeNode

#: the steps that open the second view, each in its own turn of the event loop (see the
#: module docstring); methods of :class:`LinkedViews`
OPEN_STEPS = ("_make_room", "_make_view", "_first_paint", "_attach_scene", "_first_frame",
              "_add_grid", "_grid_frame", "_finish_opening")
#: milliseconds between two steps of opening
OPEN_STEP_GAP_MS = 16
#: a step whose timer fired this much later than due (other work held the GUI thread just
#: before: a render, a refined frame) waits another gap, at most :data:`OPEN_STEP_WAITS` times
OPEN_STEP_LATE_MS = 8
OPEN_STEP_WAITS = 4


class LinkedViews:
    """The window's central splitter with its first view, and the second view while the
    scene is split (see module docstring).

    Parameters
    ----------
    window : splineviz.gui.main_window.MainWindow
        Owner of the scene, the first view, the status labels and the error display.
    """

    def __init__(self, window):
        self.window = window
        self.scene = window.scene
        self.splitter = QSplitter(Qt.Orientation.Horizontal, window)
        self.splitter.setObjectName("views")
        self.splitter.setChildrenCollapsible(False)
        self.splitter.addWidget(window.view.plotter)
        #: the right-hand view while the scene is split, else None
        self.second: View3D | None = None
        self._second_planes: PlaneWidgets | None = None
        #: closed second views whose workers may still be finishing a frame (joined on exit)
        self._retired: list[View3D] = []
        self._closed = False
        #: while the second view opens: the steps still to run, the view being made and the
        #: pane that holds its place in the splitter until its widget is shown
        self._steps: list[str] | None = None
        self._opening: View3D | None = None
        self._stand_in: QWidget | None = None
        self._first_dragging = False
        #: hidden second views to close on the next turn, with their plane widgets
        self._closing: list = []
        self._step_timer = QTimer(self.splitter)
        self._step_timer.setSingleShot(True)
        # a frame's time between steps: the paints and renders a step asks for, and the
        # user's input, run before the next step, not in one piece with it
        self._step_timer.setInterval(OPEN_STEP_GAP_MS)
        self._step_timer.timeout.connect(self._next_step)
        self._step_due = 0.0
        self._step_waits = 0
        window.view.interacting.connect(self._first_interacting)
        window.view.activated.connect(lambda: self._activated("left"))
        self.scene.view.events.split.connect(self._split_changed)
        if self.scene.view.split:
            self._open_second()

    @property
    def views(self) -> list[View3D]:
        """The views shown now, left to right."""
        return [self.window.view] + ([self.second] if self.second is not None else [])

    @property
    def opening(self) -> bool:
        """Whether the second view is being opened (steps still to run)."""
        return self._steps is not None

    # -- the model's split ---------------------------------------------------------------

    def set_split(self, on: bool) -> None:
        """Split the view (the View menu's toggle). When nothing is assigned to a side yet,
        the current isosurface (or the first) is compared with a copy in another model
        (:meth:`~splineviz.model.Scene.compare`): the two views then differ at once.

        The camera keeps what it showed across: a view half as wide moves it back so that
        the same width of the scene fits (and forward again when the split ends)."""
        before = self._first_aspect()
        try:
            self._set_split(on)
        finally:
            self._keep_width(before)

    def _first_aspect(self, width: int | None = None) -> float:
        p = self.window.view.plotter
        w = p.width() if width is None else width
        return w / p.height() if self.splitter.isVisible() and p.height() > 0 else 0.0

    def _keep_width(self, before: float) -> None:
        """Move the camera along its line of sight so that the first view, now of another
        aspect ratio, shows the scene as wide as before (a perspective view shows a width
        of ``2 d tan(angle / 2) aspect`` at distance ``d``)."""
        # the first view gets half the width once the second view opens (in steps: the
        # splitter has not made room yet) and all of it when it closes (laid out later)
        total = self.splitter.width()
        split = self.second is not None or self.opening
        after = self._first_aspect(total // 2 if split else total)
        if before <= 0.0 or after <= 0.0 or abs(after / before - 1.0) < 0.02:
            return
        cam = self.scene.camera
        focal = np.asarray(cam.focal_point, dtype=float)
        offset = np.asarray(cam.position, dtype=float) - focal
        cam.position = tuple(map(float, focal + offset * (before / after)))

    def _set_split(self, on: bool) -> None:
        if on and not self.scene.view.split and not any(
                getattr(n, "shown_in", "both") != "both" for n in self.scene):
            iso = self.scene.selected
            if not isinstance(iso, IsosurfaceNode):
                isos = self.scene.isosurfaces
                iso = isos[0] if isos else None
            if iso is not None:
                copy = self.scene.compare(iso)
                self.window.show_warning(
                    f"left: {iso.name}, right: {copy.name}; select either (or click its "
                    "view) to set its model and isovalue")
                return
        self.scene.view.split = bool(on)

    def _split_changed(self, on: bool) -> None:
        if self._closed:
            return
        # a session or a script may split the scene too: the menu's check mark follows
        action = getattr(self.window, "actions_by_name", {}).get("split")
        if action is not None and action.isChecked() != on:
            action.setChecked(on)
        if on and self.second is None and not self.opening:
            self._open_second()
        elif not on and (self.second is not None or self.opening):
            self._close_second()

    # -- opening the second view in steps (OPEN_STEPS) -----------------------------------

    def _open_second(self) -> None:
        self._steps = list(OPEN_STEPS)
        self._arm_step()

    def _arm_step(self) -> None:
        self._step_due = time.perf_counter() + OPEN_STEP_GAP_MS / 1000.0
        self._step_timer.start()

    def _next_step(self) -> None:
        if self._steps is None or self._closed:
            return
        # run after other work, not right behind it in one piece
        late_ms = 1000.0 * (time.perf_counter() - self._step_due)
        if late_ms > OPEN_STEP_LATE_MS and self._step_waits < OPEN_STEP_WAITS:
            self._step_waits += 1
            self._arm_step()
            return
        self._step_waits = 0
        getattr(self, self._steps.pop(0))()
        if self._steps:
            self._arm_step()
        else:
            self._steps = None

    def _make_room(self) -> None:
        """A plain pane of the background colour takes the right half: the first view is
        repainted at its new width now, not in the same turn as the new view's first paint."""
        pane = QWidget()
        palette = pane.palette()
        palette.setColor(QPalette.ColorRole.Window, QColor.fromRgbF(
            *self.window.view.plotter.renderer.GetBackground()))
        pane.setPalette(palette)
        pane.setAutoFillBackground(True)
        self._stand_in = pane
        # added hidden, then shown and laid out at once: the first view is resized (and
        # repainted: a QOpenGLWidget paints in its resize event) once, not twice
        pane.hide()
        self.splitter.addWidget(pane)
        # half each: the two pictures are compared at one size
        total = sum(self.splitter.sizes()) or self.splitter.width()
        self.splitter.setSizes([total // 2, total - total // 2])
        pane.show()
        self.splitter.refresh()

    def _make_view(self) -> None:
        """The second view's widget, not shown yet and without the scene."""
        w = self.window
        self._opening = View3D(self.scene, w, device=w.device, side="right", attach=False)
        self._opening.hold_refine(True)  # its exact frames once it is open

    def _first_paint(self) -> None:
        """The widget replaces the pane: its OpenGL context is made and painted once with
        the background only."""
        pane, self._stand_in = self._stand_in, None
        self.splitter.replaceWidget(self.splitter.indexOf(pane), self._opening.plotter)
        pane.deleteLater()

    def _attach_scene(self) -> None:
        """The scene's objects become the view's props (drawn in the next step); the
        view's signals and the clip planes' widgets are connected."""
        w, view = self.window, self._opening
        view.attach(grid=False)
        view.readout.connect(w.readout_label.setText)
        view.busy.connect(w._view_busy)
        view._refiner.error.connect(w.show_error)
        view.interacting.connect(self._second_interacting)
        view.activated.connect(lambda: self._activated("right"))
        self._second_planes = PlaneWidgets(self.scene, view.plotter, view.request_render)

    def _first_frame(self) -> None:
        """The first frame of the scene's props; the isosurfaces follow as exact frames
        from the view's worker (their ray casters are made there)."""
        self._opening._render_now()

    def _add_grid(self) -> None:
        """The axes grid, when the scene shows it (drawn in the next step)."""
        self._opening.add_grid()

    def _grid_frame(self) -> None:
        """The grid's first frame (its labels' first frame in this context)."""
        self._opening._render_now()

    def _finish_opening(self) -> None:
        """The orientation axes (their own first frame), and the view is open."""
        view, self._opening = self._opening, None
        view.add_axes()
        self.second = view
        self.window.view_layout.slices.add_view3d(view)
        view.request_render()
        view.hold_refine(False)
        # a drag that began in the first view while this one opened: follow it
        if self._first_dragging:
            view.follow_interaction(True)

    def _abandon_opening(self) -> View3D | None:
        """Stop opening; the view made so far (None if none) is returned to be closed."""
        self._steps = None
        self._step_timer.stop()
        if self._stand_in is not None:
            self._stand_in.hide()
            self._stand_in.setParent(None)
            self._stand_in.deleteLater()
            self._stand_in = None
        view, self._opening = self._opening, None
        return view

    def _close_second(self) -> None:
        opening = self._abandon_opening()
        view, self.second = self.second or opening, None
        if view is None:
            self.window.view.request_render()
            return
        planes, self._second_planes = self._second_planes, None
        self.window.view_layout.slices.remove_view3d(view)
        # in two turns of the event loop: it stops following the scene and is hidden now (the
        # first view takes the width and is repainted), its widget and OpenGL context are
        # closed in the next: in one piece the two held the GUI thread 120-260 ms
        view.close(widget=False)
        view.plotter.hide()
        self._closing.append((view, planes))
        QTimer.singleShot(OPEN_STEP_GAP_MS, self._finish_closing)
        self.window.view.request_render()

    def _finish_closing(self) -> None:
        while self._closing:
            view, planes = self._closing.pop(0)
            if planes is not None:
                planes.close()
            view.close()  # the widget: the rest was closed with the split
            view.plotter.setParent(None)
            # kept while a frame it was ray casting may still run (joined at exit: pocl
            # aborts a process that exits while one of its threads is inside OpenCL);
            # earlier ones whose workers ended are let go
            for old in [v for v in self._retired if v.join(0.0)]:
                self._retired.remove(old)
                old.plotter.deleteLater()
                old.deleteLater()
            self._retired.append(view)

    # -- linking -------------------------------------------------------------------------

    def _first_interacting(self, on: bool) -> None:
        self._first_dragging = on
        if self.second is not None:
            self.second.follow_interaction(on)

    def _second_interacting(self, on: bool) -> None:
        self.window.view.follow_interaction(on)

    def _activated(self, side: str) -> None:
        """A click in one of the split views: the panels turn to that view's isosurface
        when the current one is not shown there (a selected volume counts as its first
        isosurface; a selected plane, mesh or cloud stays selected: the click may be a
        drag of its widget)."""
        if not self.scene.view.split:
            return
        sel = self.scene.selected
        if isinstance(sel, VolumeNode):
            isos = self.scene.isosurfaces_of(sel)
            sel = isos[0] if isos else None
        if sel is not None and not isinstance(sel, IsosurfaceNode):
            return
        if sel is not None and sel.shown_in in ("both", side):
            return
        own = [n for n in self.scene.isosurfaces if n.shown_in == side]
        if own:
            self.scene.select(own[0])

    # -- closing -------------------------------------------------------------------------

    def close(self) -> None:
        """The window is closing: close the second view (the first is the window's)."""
        self._closed = True
        self.scene.view.events.split.disconnect(self._split_changed)
        self._finish_closing()
        opening = self._abandon_opening()
        if self.second is not None or opening is not None:
            view, self.second = self.second or opening, None
            if self._second_planes is not None:
                self._second_planes.close()
                self._second_planes = None
            view.close()
            self._retired.append(view)

    def join(self, timeout_s: float) -> bool:
        """After :meth:`close`: wait for frames the second views were still casting."""
        end = time.perf_counter() + timeout_s
        ok = True
        for view in self._retired:
            ok = view.join(max(end - time.perf_counter(), 0.0)) and ok
        return ok
