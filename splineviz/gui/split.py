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
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QSplitter

from splineviz.gui.panels import PlaneWidgets
from splineviz.gui.view import View3D
from splineviz.model import IsosurfaceNode, VolumeNode


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
        window.view.interacting.connect(self._first_interacting)
        window.view.activated.connect(lambda: self._activated("left"))
        self.scene.view.events.split.connect(self._split_changed)
        if self.scene.view.split:
            self._open_second()

    @property
    def views(self) -> list[View3D]:
        """The views shown now, left to right."""
        return [self.window.view] + ([self.second] if self.second is not None else [])

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
        sizes = self.splitter.sizes()
        # the splitter lays out a removed view's room later: the first view gets it all
        after = self._first_aspect(sizes[0] if self.second is not None
                                   else self.splitter.width())
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
        if on and self.second is None:
            self._open_second()
        elif not on and self.second is not None:
            self._close_second()

    def _open_second(self) -> None:
        w = self.window
        view = View3D(self.scene, w, device=w.device, side="right")
        self.second = view
        self.splitter.addWidget(view.plotter)
        # half each: the two pictures are compared at one size
        total = sum(self.splitter.sizes()) or self.splitter.width()
        self.splitter.setSizes([total // 2, total - total // 2])
        view.readout.connect(w.readout_label.setText)
        view.busy.connect(w._view_busy)
        view._refiner.error.connect(w.show_error)
        view.interacting.connect(self._second_interacting)
        view.activated.connect(lambda: self._activated("right"))
        self._second_planes = PlaneWidgets(self.scene, view.plotter, view.request_render)
        view.request_render()

    def _close_second(self) -> None:
        view, self.second = self.second, None
        if self._second_planes is not None:
            self._second_planes.close()
            self._second_planes = None
        view.close()
        view.plotter.hide()
        view.plotter.setParent(None)
        # kept while a frame it was ray casting may still run (joined at exit: pocl aborts
        # a process that exits while one of its threads is inside OpenCL); earlier ones
        # whose workers ended are let go
        for old in [v for v in self._retired if v.join(0.0)]:
            self._retired.remove(old)
            old.plotter.deleteLater()
            old.deleteLater()
        self._retired.append(view)
        self.window.view.request_render()

    # -- linking -------------------------------------------------------------------------

    def _first_interacting(self, on: bool) -> None:
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
        if self.second is not None:
            view, self.second = self.second, None
            if self._second_planes is not None:
                self._second_planes.close()
                self._second_planes = None
            view.close()
            self._retired.append(view)

    def join(self, timeout_s: float) -> bool:
        """After :meth:`close`: wait for frames the second views were still casting."""
        import time

        end = time.perf_counter() + timeout_s
        ok = True
        for view in self._retired:
            ok = view.join(max(end - time.perf_counter(), 0.0)) and ok
        return ok
