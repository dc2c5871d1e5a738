"""``splineviz bench gui``: the GUI thread's longest stall per user action against the 100 ms
budget.

A script drives the main window as a user would: open data (the embedded default volume, or
a volume file), orbit, zoom with the wheel, drag the isovalue slider, split the view (View >
Split view) and drag in the new view, show the four-up layout (View > Layout) and move its
crosshair with the wheel, switch to every spline model with a kernel, smooth and revert, add
an isosurface, open a point cloud, remesh it and cancel. Each action is measured
``repeats`` times (undone between two measurements) by a :class:`~splineviz.bench.driving.
StallMeter`: the longest gap between the ticks of a 10 ms timer from the action until the
window settles (jobs done, exact frames shown). The table gives per action the median, 95th
percentile and maximum stall, the stall of the first run (what a user meets the first time:
a caster built, a kernel compiled, a view made), the budget and whether the median keeps it,
and the median time from the action's start until the window settled (the exact frames on
screen); a line after it the time a cancelled job took to stop (budget 1 s).

A stall is a property of our GUI thread only when the machine is otherwise idle: another
process can take a core for one tick. The median of several repeats is the figure the budget
applies to; the maximum shows what a busy machine adds.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizError

#: the longest the GUI thread may be away from its event loop, milliseconds
MAX_STALL_MS = 100.0
#: the longest a cancelled job may keep the window busy, seconds
MAX_CANCEL_S = 1.0
#: seconds an action may take to settle before the benchmark gives up on it
SETTLE_TIMEOUT_S = 300.0


class GuiBenchError(SplinevizError):
    """The scripted window did not do what the script asked (the benchmark cannot go on)."""


def _check(ok: bool, what: str) -> None:
    if not ok:
        raise GuiBenchError(f"bench gui: {what}")


@dataclass
class Stalls:
    """Measurements of one run of the script.

    Attributes
    ----------
    ms : dict
        Action name -> list of the longest GUI-thread stalls (ms), one per repeat, in the
        order the script ran them.
    settled_s : dict
        Action name -> list of the seconds from the action's start until the window settled.
    cancel_s : list of float
        Seconds from pressing Cancel until no job ran, one per repeat.
    """

    ms: dict[str, list[float]] = field(default_factory=dict)
    settled_s: dict[str, list[float]] = field(default_factory=dict)
    cancel_s: list[float] = field(default_factory=list)

    def rows(self, budget_ms: float = MAX_STALL_MS) -> list[dict]:
        """One dict per action: ``action, n, median_ms, p95_ms, max_ms, first_ms, budget_ms,
        ok, settled_s`` (ok: the median keeps the budget; first_ms: the first run's stall;
        settled_s: a median, or None)."""
        out = []
        for name, values in self.ms.items():
            med = statistics.median(values)
            settled = self.settled_s.get(name)
            out.append({"action": name, "n": len(values), "median_ms": med,
                        "p95_ms": float(np.percentile(values, 95)), "max_ms": max(values),
                        "first_ms": values[0], "budget_ms": budget_ms, "ok": med <= budget_ms,
                        "settled_s": statistics.median(settled) if settled else None})
        return out


def print_table(stalls: Stalls, out=print, budget_ms: float = MAX_STALL_MS) -> list[dict]:
    """Print the table of :meth:`Stalls.rows` and the cancel line; returns the rows."""
    rows = stalls.rows(budget_ms)
    out("GUI-thread stall per action (ms; ok: the median keeps the budget)")
    out(f"| {'action':32} | {'n':>2} | {'median':>7} | {'p95':>7} | {'max':>7} | "
        f"{'first':>7} | {'budget':>6} | ok  | {'settled s':>9} |")
    out("|" + "|".join("-" * w for w in (34, 4, 9, 9, 9, 9, 8, 5, 11)) + "|")
    for r in rows:
        settled = "-" if r["settled_s"] is None else f"{r['settled_s']:.2f}"
        out(f"| {r['action']:32} | {r['n']:2d} | {r['median_ms']:7.1f} | {r['p95_ms']:7.1f} | "
            f"{r['max_ms']:7.1f} | {r['first_ms']:7.1f} | {r['budget_ms']:6.0f} | "
            f"{'yes' if r['ok'] else 'NO ':3} | {settled:>9} |")
    if stalls.cancel_s:
        c = stalls.cancel_s
        out(f"cancel: the job stopped after {statistics.median(c):.2f} s (median of {len(c)}, "
            f"max {max(c):.2f} s; budget {MAX_CANCEL_S:g} s)")
    return rows


class _Script:
    """The user's actions on ``window`` (see module docstring), each measured ``repeats``
    times; with ``again_over`` (ms) an action whose every stall exceeded it is measured once
    more (a stall of our own shows in every run, a busy machine's tick in one)."""

    def __init__(self, window, repeats: int, again_over: float | None, out):
        from splineviz.bench import driving  # Qt: imported when a window is driven

        self.drive = driving
        self.w = window
        self.repeats = max(int(repeats), 1)
        self.again_over = again_over
        self.out = out
        self.stalls = Stalls()

    # -- states the window settles in ---------------------------------------------------

    def idle_and_exact(self) -> bool:
        w = self.w
        return not w.jobs.jobs and not w.view.refining and not w.spline_scene.needs_refine()

    def split_and_exact(self) -> bool:
        """Split, the second view open, and every view shows exact frames."""
        w = self.w
        return (w.view2 is not None and not w.linked_views.opening and not w.jobs.jobs
                and all(not v.refining and not v.spline_scene.needs_refine()
                        for v in w.linked_views.views))

    def settle(self, until, what: str, timeout_s: float = 60.0) -> None:
        _check(self.drive.pump(timeout_s, until), f"{what} did not finish in {timeout_s:g} s")

    # -- measuring -----------------------------------------------------------------------

    def _once(self, name, action, settle) -> tuple[float, float]:
        t0 = time.perf_counter()
        with self.drive.StallMeter() as meter:
            action()
            _check(self.drive.pump(SETTLE_TIMEOUT_S, settle),
                   f"{name}: did not finish in {SETTLE_TIMEOUT_S:g} s")
        took = time.perf_counter() - t0
        self.out(f"{name}: longest GUI-thread stall {meter.max_ms:.0f} ms "
                 f"({meter.ticks} ticks, {took:.2f} s)")
        return meter.max_ms, took

    def measure(self, name, action, settle, undo) -> list[float]:
        """Run ``action`` until ``settle()``, ``repeats`` times with ``undo()`` (back to the
        state before the action, settled) between two; returns the seconds each took."""
        values, took = [], []
        for i in range(self.repeats):
            if i:
                undo()
            ms, s = self._once(name, action, settle)
            values.append(ms)
            took.append(s)
        if self.again_over is not None and min(values) > self.again_over:
            undo()
            ms, s = self._once(f"{name} (again)", action, settle)
            values.append(ms)
            took.append(s)
        self.stalls.ms[name] = values
        self.stalls.settled_s[name] = took
        return took

    # -- the script ----------------------------------------------------------------------

    def open_data(self, volume_path, iso) -> None:
        w = self.w

        def clear():
            w.scene.clear()
            self.settle(self.idle_and_exact, "clear")

        if volume_path is None:
            self.measure("open default data", w.open_default, self.idle_and_exact, clear)
        else:
            self.measure(f"open {Path(volume_path).name}",
                         lambda: w.open_path(volume_path, mode="replace", isovalue=iso),
                         lambda: bool(w.scene.isosurfaces) and self.idle_and_exact(), clear)
        _check(bool(w.scene.isosurfaces), "the data opened without an isosurface")

    def orbit_and_zoom(self) -> None:
        w = self.w
        p = w.plotter

        def centre():
            return p.width() / 2.0, p.height() / 2.0

        def orbit():
            cx, cy = centre()
            self.drive.drag(p, (cx - 60, cy), (cx + 60, cy + 20), n=15)

        pose = np.array(w.scene.camera.position)
        self.measure("orbit (left drag)", orbit, self.idle_and_exact, lambda: None)
        _check(np.linalg.norm(np.subtract(w.scene.camera.position, pose)) > 1e-6,
               "the orbit drag did not reach the interactor")

        def zoom_out():
            self.drive.wheel(p, centre(), clicks=-2)
            self.settle(self.idle_and_exact, "zoom out")

        def distance():
            cam = w.scene.camera
            return float(np.linalg.norm(np.subtract(cam.position, cam.focal_point)))

        far = distance()
        self.measure("wheel zoom (2 notches)", lambda: self.drive.wheel(p, centre(), clicks=2),
                     self.idle_and_exact, zoom_out)
        _check(distance() < 0.95 * far, "the wheel did not zoom in")
        zoom_out()

    def slider_drag(self) -> None:
        w = self.w
        node = w.scene.isosurfaces[0]
        w.scene.select(node)
        hist = w.iso_panel.histogram
        before = node.isovalue
        lo, hi = hist.range()
        width, y = hist.width(), hist.height() / 2.0
        x0 = 6 + (before - lo) / (hi - lo) * (width - 12)  # plot area: 6 .. width - 6 px
        x1 = x0 + 0.1 * width if x0 < width / 2 else x0 - 0.1 * width

        def back():
            hist.setValue(before)
            self.settle(self.idle_and_exact, "isovalue reset")

        self.measure("isovalue slider drag", lambda: self.drive.drag(hist, (x0, y), (x1, y), n=8),
                     self.idle_and_exact, back)
        _check(abs(node.isovalue - before) > 0.02 * (hi - lo),
               "the slider drag did not change the isovalue")
        back()

    def split_and_drag(self) -> None:
        """View > Split view, then an orbit dragged in the new (right) view, then the split
        off again. Turning the split on makes a second VTK window (gui.split.OPEN_STEPS); the
        first drag in it casts previews of sizes not cast before in both views."""
        w = self.w
        node = w.scene.isosurfaces[0]
        w.scene.select(node)
        split = w.actions_by_name["split"]

        def split_off():
            split.trigger()
            self.settle(lambda: w.view2 is None and w.linked_views.splitter.count() == 1
                        and self.idle_and_exact(), "split off")

        def split_on():
            split.trigger()
            self.settle(self.split_and_exact, "split on")

        def unsplit_and_uncompare():  # as before the split: it compares the copy anew
            split_off()
            w.scene.remove(w.scene.isosurfaces[1])
            node.shown_in = "both"
            w.scene.select(node)
            self.settle(self.idle_and_exact, "unsplit")

        self.measure("split on", split.trigger, self.split_and_exact, unsplit_and_uncompare)
        _check(split.isChecked() and w.linked_views.splitter.count() == 2,
               "View > Split view did not split the view")
        left, right = w.scene.isosurfaces

        def drag_right():
            p = w.view2.plotter
            cx, cy = p.width() / 2.0, p.height() / 2.0
            path = self.drive.line((cx - 60, cy), (cx + 60, cy + 20), 12)
            self.drive.run_steps(self.drive.drag_steps(p, path), interval_ms=16)

        def split_on_again():  # a new second view: its first drag again
            split_off()
            split_on()

        pose = np.array(w.scene.camera.position)
        self.measure("first drag after split", drag_right, self.split_and_exact,
                     split_on_again)
        _check(np.linalg.norm(np.subtract(w.scene.camera.position, pose)) > 1e-3,
               "the drag in the new view did not reach the interactor")
        for view, iso in ((w.view, left), (w.view2, right)):
            (layer,) = [la for la in view.spline_scene.layers if la.visible]
            frame = view.spline_scene.shown_frame(layer)
            _check((layer.model, layer.isovalue) == (iso.model, iso.isovalue)
                   and frame is not None and frame.final and frame.frame.hit.mean() > 0.01,
                   f"the {view.side} view does not show the exact frame of its isosurface")
        _check(left.model != right.model, "the split compares a model with itself")
        split_off()
        w.scene.remove(right)
        left.shown_in = "both"
        self.settle(self.idle_and_exact, "unsplit")

    def models_and_smoothing(self) -> None:
        from splineviz.core.splines import MODELS

        w = self.w
        node = w.scene.isosurfaces[0]
        w.scene.select(node)
        for model in [m for m in MODELS if MODELS[m].family is not None]:
            index = w.iso_panel.model.findData(model)
            previous = node.model

            def undo(p=previous):
                node.model = p
                self.settle(self.idle_and_exact, "model switch back")

            self.measure(f"switch to {model}",
                         lambda i=index: w.iso_panel.model.setCurrentIndex(i),
                         self.idle_and_exact, undo)
            _check(node.model == model, f"the model list did not switch to {model}")
        vol = w.scene.volume_of(node)

        def sigma(value):
            vol.sigma = value
            self.settle(lambda: self.idle_and_exact() and not w.smooth_panel.pending,
                        "smoothing")

        self.measure("smooth sigma 1.5",
                     lambda: (w.smooth_panel.sigma.setValue(1.5), w.smooth_panel.apply()),
                     lambda: self.idle_and_exact() and not w.smooth_panel.pending,
                     lambda: sigma(0.0))
        self.measure("smoothing: Original", w.smooth_panel.reset_button.click,
                     self.idle_and_exact, lambda: sigma(1.5))

        count = len(w.scene.isosurfaces)

        def remove_added():  # and the original selected again: Add needs a selection
            w.scene.remove(w.scene.isosurfaces[-1])
            w.scene.select(node)
            self.settle(self.idle_and_exact, "remove isosurface")

        self.measure("add isosurface", w.iso_panel.add_button.click,
                     lambda: len(w.scene.isosurfaces) == count + 1 and self.idle_and_exact(),
                     remove_added)

    def slices_settled(self) -> bool:
        """The layout's slice views all made, computed and rendered."""
        w = self.w
        slices = w.view_layout.slices
        return (w.view_layout.ready and not slices.rendering and not slices.worker.busy
                and self.idle_and_exact())

    def four_up(self) -> None:
        """View > Layout > Four-up (its slice views are made the first time), the wheel
        turned over the axial slice, and back to the 3-D view alone."""
        w = self.w
        layout = w.view_layout
        four_up = layout.actions[("four-up", None)]
        three_d = layout.actions[("3d", None)]

        def back():
            three_d.trigger()
            self.settle(lambda: layout.state.layout == "3d" and self.idle_and_exact(),
                        "3-D only")

        self.measure("four-up layout", four_up.trigger, self.slices_settled, back)
        _check(layout.state.layout == "four-up" and set(layout.views) ==
               {"axial", "coronal", "sagittal"}, "View > Layout > Four-up showed no slices")
        axial = layout.views["axial"].widget
        before = layout.state.position("axial")
        self.measure("slice wheel (2 notches)",
                     lambda: self.drive.wheel(axial, (axial.width() / 2, axial.height() / 2),
                                              clicks=2),
                     self.slices_settled, lambda: None)
        _check(layout.state.position("axial") != before,
               "the wheel over the axial slice did not move it")
        back()

    def points_remesh_cancel(self, cloud_path) -> None:
        from splineviz.model import PointsNode

        w = self.w

        def remove_points():
            w.scene.remove(w.scene.of_kind(PointsNode)[-1])
            self.settle(lambda: not w.jobs.jobs, "remove points")

        # the reading process, its fork and its result's unpickling share the cores with the
        # GUI thread
        self.measure(f"open {Path(cloud_path).name}", lambda: w.open_path(cloud_path, mode="add"),
                     lambda: not w.jobs.jobs, remove_points)
        # a remesh still running when Cancel is pressed: the compiled front meshes the kitten
        # in ~1.5 s at the default lengths, so edges of 1/150 of its diagonal (~9x the
        # triangles, ~5 s)
        cloud = np.asarray(w.remesh_panel.points.data.points)
        w.remesh_panel.mode.setCurrentIndex(1)
        w.remesh_panel.edge.setValue(float(np.linalg.norm(np.ptp(cloud, axis=0))) / 150)
        job = {}

        def start():
            job["j"] = w.remesh_panel.run()

        def running_2s():
            return time.perf_counter() - job["j"].started > 2.0

        def cancel_quietly():
            w.jobs.cancel_all()
            self.settle(lambda: not w.jobs.jobs, "cancel", 10)

        def restart():
            start()
            self.settle(running_2s, "remesh start")

        self.measure("remesh (first 2 s)", start, running_2s, cancel_quietly)
        self.stalls.cancel_s = self.measure("cancel", w.cancel_button.click,
                                            lambda: not w.jobs.jobs, restart)
        _check(job["j"].state == "cancelled", f"the remesh job ended {job['j'].state}, "
                                              f"not cancelled")

    def run(self, volume_path, cloud_path, iso) -> Stalls:
        self.open_data(volume_path, iso)
        self.orbit_and_zoom()
        self.slider_drag()
        self.split_and_drag()
        self.four_up()  # with the first model (the slices of a plugin's are NumPy's)
        self.models_and_smoothing()
        self.points_remesh_cancel(cloud_path)
        return self.stalls


def run_script(window, volume_path=None, cloud_path=None, iso=None, repeats: int = 1,
               again_over: float | None = None, out=print) -> Stalls:
    """Drive ``window`` (a shown :class:`~splineviz.gui.main_window.MainWindow`) through
    the script of the module docstring.

    Parameters
    ----------
    window : MainWindow
    volume_path : path-like, optional
        Volume to open (default: the embedded default data).
    cloud_path : path-like
        Point cloud to open, remesh and cancel.
    iso : float, optional
        Isovalue of ``volume_path``.
    repeats : int
        Measurements per action.
    again_over : float, optional
        Measure an action once more when all its stalls exceeded this (ms).
    out : callable
        Receives one line per measurement.

    Returns
    -------
    Stalls
    """
    return _Script(window, repeats, again_over, out).run(volume_path, cloud_path, iso)


def prepare() -> None:
    """What ``install.sh`` prepares for an installed app: the truncated-octahedral tables
    (a second of Python the first time that model is chosen)."""
    from splineviz.compute.to_tables import cell_classes, stencils

    stencils(2)
    cell_classes()


def run_gui_bench(data_dir=None, volume=None, points: str = "kitten.xyz", iso=None,
                  repeats: int = 5, out=print) -> list[dict]:
    """Open the main window, run the script and print the table; returns its rows.

    Parameters
    ----------
    data_dir : path-like, optional
        Folder with ``volumes/`` and ``points/`` (default ``../shared/data``).
    volume : str, optional
        File in ``volumes/`` (default: the embedded default data).
    points : str
        File in ``points/``.
    iso : float, optional
        Isovalue of ``volume``.
    repeats : int
        Measurements per action.
    """
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise GuiBenchError("bench gui opens the main window and needs a display "
                            "(without one: xvfb-run -a splineviz bench gui)")
    from PySide6.QtWidgets import QApplication

    from splineviz.bench.driving import close_window, open_window

    root = Path(data_dir) if data_dir else Path.cwd() / ".." / "shared" / "data"
    cloud = root / "points" / points
    if not cloud.is_file():
        raise GuiBenchError(f"bench gui: point cloud {cloud} not found (--data-dir)")
    vol = None
    if volume:
        vol = root / "volumes" / volume
        if not vol.exists():
            raise GuiBenchError(f"bench gui: volume {vol} not found (--data-dir)")
    app = QApplication.instance() or QApplication(["splineviz-bench"])
    app.setApplicationName("splineviz-bench")
    prepare()
    with tempfile.TemporaryDirectory(prefix="splineviz-bench-gui-") as settings:
        w = open_window(settings)
        try:
            stalls = run_script(w, vol, cloud, iso, repeats=repeats, out=out)
        finally:
            close_window(w)
            w.join_workers()
    return print_table(stalls, out)
