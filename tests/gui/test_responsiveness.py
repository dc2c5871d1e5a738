"""The GUI thread never stalls: the longest gap between event-loop ticks while the user opens
data, switches every spline model, smooths and reverts, adds an isosurface, remeshes and
cancels — and a cancel acts within a second.

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
    in_fresh_process,
    open_window,
    pump,
)

from splineviz.core.splines import MODELS  # noqa: E402

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
    stalls["open points"] = _measure(w, f"open {cloud_path.name}",
                                     lambda: w.open_path(cloud_path, mode="add"),
                                     lambda: not w.jobs.jobs)
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
