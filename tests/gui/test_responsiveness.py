"""The GUI thread never stalls: the longest gap between event-loop ticks while the user opens
data, splits the view (View > Split view) and drags in the new view, switches every spline
model, smooths and reverts, adds an isosurface, remeshes and cancels — and a cancel acts
within a second.

The default run uses small data (the embedded default volume, the kitten scan); ``-m slow``
runs the same script on bonsai (256^3) and the bunny (36k points), the issue's figures.
"""

import os
import time

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from interaction import (  # noqa: E402
    FRESH,
    StallMeter,
    close_window,
    drag_steps,
    in_fresh_process,
    line,
    open_window,
    pump,
    run_steps,
)

from splineviz.core.splines import MODELS  # noqa: E402
from splineviz.model import PointsNode  # noqa: E402

#: the longest the GUI thread may be away from its event loop, milliseconds
MAX_STALL_MS = 100
#: the longest a cancelled job may keep the window busy, seconds
MAX_CANCEL_S = 1.0


@pytest.fixture
def window(qapp, tmp_path):
    from splineviz.compute.to_tables import cell_classes, stencils

    # as in an installed app: install.sh prepares the truncated-octahedral tables (a second of
    # Python that would otherwise run, once, the first time that model is chosen)
    stencils(2)
    cell_classes()
    w = open_window(tmp_path)
    yield w
    close_window(w)


def _measure(w, what, action, settle, timeout_s=300.0):
    """Run ``action`` from the event loop and pump until ``settle()``; returns the longest
    stall in ms (printed, and collected for the closing table)."""
    with StallMeter() as meter:
        action()
        assert pump(timeout_s, settle), f"{what}: did not finish in {timeout_s:g} s"
    print(f"{what}: longest GUI-thread stall {meter.max_ms:.0f} ms ({meter.ticks} ticks)")
    return meter.max_ms


def _measure_again_if_slow(w, what, action, settle, undo):
    """:func:`_measure`, and once more after ``undo()`` when the stall exceeded the limit:
    on a shared 2-core machine another process can take the CPU for one tick; a stall of
    our own shows in both runs (the smaller one is returned)."""
    first = _measure(w, what, action, settle)
    if first <= MAX_STALL_MS:
        return first
    undo()
    pump(60, lambda: _idle_and_exact(w))
    return min(first, _measure(w, what + " (again)", action, settle))


def _idle_and_exact(w):
    return not w.jobs.jobs and not w.view.refining and not w.spline_scene.needs_refine()


def _split_and_exact(w):
    """Split, the second view open, and every view shows exact frames."""
    return (w.view2 is not None and not w.linked_views.opening and not w.jobs.jobs
            and all(not v.refining and not v.spline_scene.needs_refine()
                    for v in w.linked_views.views))


def _split_and_drag(w, stalls):
    """View > Split view, then an orbit dragged in the new (right) view (both measured), then
    the split off.

    Turning the split on makes a second VTK window (gui.split.OPEN_STEPS, one step per turn
    of the event loop); the first drag in it casts previews of sizes not cast before in both
    views. After them each view shows the exact frame of its own isosurface (the original's
    model on the left, the comparison copy's on the right) at the one camera. The copy is
    removed with the split, so the script goes on with the scene it had."""
    node = w.scene.isosurfaces[0]
    w.scene.select(node)
    split = w.actions_by_name["split"]

    def split_off():
        split.trigger()
        assert pump(60, lambda: w.view2 is None and w.linked_views.splitter.count() == 1
                    and _idle_and_exact(w))

    def split_on():
        split.trigger()
        assert pump(60, lambda: _split_and_exact(w))

    def unsplit_and_uncompare():  # as before the split: it compares the copy anew
        split_off()
        w.scene.remove(w.scene.isosurfaces[1])
        node.shown_in = "both"
        w.scene.select(node)
        assert pump(60, lambda: _idle_and_exact(w))

    stalls["split on"] = _measure_again_if_slow(w, "split on", split.trigger,
                                                lambda: _split_and_exact(w),
                                                unsplit_and_uncompare)
    assert split.isChecked() and w.linked_views.splitter.count() == 2
    left, right = w.scene.isosurfaces

    def drag_right():
        p = w.view2.plotter
        cx, cy = p.width() / 2.0, p.height() / 2.0
        run_steps(drag_steps(p, line((cx - 60, cy), (cx + 60, cy + 20), 12)), interval_ms=16)

    def split_on_again():  # a new second view: its first drag again
        split_off()
        split_on()

    pose = np.array(w.scene.camera.position)
    stalls["first drag after split"] = _measure_again_if_slow(
        w, "first drag in the new view", drag_right, lambda: _split_and_exact(w),
        split_on_again)
    assert np.linalg.norm(np.subtract(w.scene.camera.position, pose)) > 1e-3, \
        "the drag did not reach the interactor"
    for view, iso in ((w.view, left), (w.view2, right)):
        (layer,) = [la for la in view.spline_scene.layers if la.visible]
        frame = view.spline_scene.shown_frame(layer)
        assert (layer.model, layer.isovalue) == (iso.model, iso.isovalue)
        assert frame is not None and frame.final and frame.frame.hit.mean() > 0.01
        cam = view.plotter.renderer.GetActiveCamera()
        np.testing.assert_allclose(cam.GetPosition(), w.scene.camera.position, atol=1e-9)
    assert left.model != right.model
    split_off()
    w.scene.remove(right)
    left.shown_in = "both"
    assert pump(60, lambda: _idle_and_exact(w))


def _script(w, volume_path, cloud_path, iso):
    stalls = {}
    if volume_path is None:
        stalls["open"] = _measure_again_if_slow(w, "open default", w.open_default,
                                                lambda: _idle_and_exact(w), w.scene.clear)
    else:
        stalls["open"] = _measure(w, f"open {volume_path.name}",
                                  lambda: w.open_path(volume_path, mode="replace",
                                                      isovalue=iso),
                                  lambda: bool(w.scene.isosurfaces) and _idle_and_exact(w))
    _split_and_drag(w, stalls)
    node = w.scene.isosurfaces[0]
    w.scene.select(node)
    for model in [m for m in MODELS if MODELS[m].family is not None]:
        index = w.iso_panel.model.findData(model)
        previous = node.model
        stalls[f"model {model}"] = _measure_again_if_slow(
            w, f"switch to {model}", lambda i=index: w.iso_panel.model.setCurrentIndex(i),
            lambda: _idle_and_exact(w), lambda p=previous: setattr(node, "model", p))
        assert node.model == model
    vol = w.scene.volume_of(node)
    stalls["smooth"] = _measure_again_if_slow(
        w, "smooth sigma 1.5", lambda: (w.smooth_panel.sigma.setValue(1.5),
                                        w.smooth_panel.apply()),
        lambda: _idle_and_exact(w) and not w.smooth_panel.pending,
        lambda: setattr(vol, "sigma", 0.0))
    stalls["original"] = _measure_again_if_slow(
        w, "smoothing: Original", w.smooth_panel.reset_button.click, lambda: _idle_and_exact(w),
        lambda: setattr(vol, "sigma", 1.5))
    stalls["add isosurface"] = _measure_again_if_slow(
        w, "add isosurface", w.iso_panel.add_button.click, lambda: _idle_and_exact(w),
        lambda: w.scene.remove(w.scene.isosurfaces[-1]))
    # the reading process, its fork and its result's unpickling share the 2 cores with the GUI
    # thread: measured again, as the other steps, when a busy machine took one tick
    stalls["open points"] = _measure_again_if_slow(
        w, f"open {cloud_path.name}", lambda: w.open_path(cloud_path, mode="add"),
        lambda: not w.jobs.jobs, lambda: w.scene.remove(w.scene.of_kind(PointsNode)[-1]))
    job = {}
    # a remesh that is still running when Cancel is pressed: the compiled front meshes the
    # kitten in ~1.5 s at the default lengths, so edges of 1/150 of its diagonal (~9x the
    # triangles, ~5 s)
    cloud = np.asarray(w.remesh_panel.points.data.points)
    w.remesh_panel.mode.setCurrentIndex(1)
    w.remesh_panel.edge.setValue(float(np.linalg.norm(np.ptp(cloud, axis=0))) / 150)

    def cancel_quietly():
        w.jobs.cancel_all()
        pump(5, lambda: not w.jobs.jobs)

    stalls["remesh"] = _measure_again_if_slow(
        w, "remesh, then cancel after 2 s", lambda: job.update(j=w.remesh_panel.run()),
        lambda: time.perf_counter() - job["j"].started > 2.0, cancel_quietly)
    t0 = time.perf_counter()
    stalls["cancel"] = _measure(w, "cancel", w.cancel_button.click, lambda: not w.jobs.jobs)
    cancel_s = time.perf_counter() - t0
    print(f"cancel acted after {cancel_s:.2f} s; job state {job['j'].state}")
    assert job["j"].state == "cancelled" and cancel_s < MAX_CANCEL_S
    worst = max(stalls, key=stalls.get)
    assert stalls[worst] <= MAX_STALL_MS, (worst, stalls)
    return stalls


@pytest.mark.skipif(os.environ.get(FRESH) != "1", reason="run in a fresh process by "
                    "test_no_stall_on_the_default_data_and_kitten_alone")
def test_no_stall_on_the_default_data_and_kitten(window, shared_data):
    _script(window, None, shared_data / "points" / "kitten.xyz", None)


@pytest.mark.slow
def test_no_stall_on_bonsai_and_bunny(window, shared_data):
    _script(window, shared_data / "volumes" / "bonsai.vti", shared_data / "points" / "bunny.ply",
            40.5)


@pytest.mark.skipif(os.environ.get(FRESH) == "1", reason="this process is the fresh one")
def test_no_stall_on_the_default_data_and_kitten_alone():
    in_fresh_process("tests/gui/test_responsiveness.py::test_no_stall_on_the_default_data_and_kitten")
