"""Soak: many isovalue changes, camera moves and model switches, and many open/close cycles
of a real volume, with the process's memory and the OpenCL buffers flat.

Driven in process through the panels and the scene model (as the other GUI tests), each
change waited for until its exact frame is shown. Memory: the resident set size (psutil).
OpenCL buffers: the live ``pyopencl`` memory objects reachable from Python objects (the
ray casters keep theirs as attributes and ``pyopencl.array.Array`` bases), counted through
the garbage collector, with their bytes. Each figure is taken in the same state (first
model, objects in the scene as at the start) so that they compare.

The full runs (1,000 changes, 100 cycles of bonsai) are ``-m slow``; the default run does
a short version of each.
"""

import gc
import time

import numpy as np
import pytest

pytest.importorskip("pytestqt")
psutil = pytest.importorskip("psutil")
cl = pytest.importorskip("pyopencl")

from interaction import close_window, open_window  # noqa: E402

#: models the soak switches between (all with an OpenCL kernel); the short run takes the
#: first two (each model's kernel is compiled once per process: seconds for the others)
MODELS = ("cubic-c1", "trilinear", "super-quadratic", "to-quadratic")


def rss_mb() -> float:
    return psutil.Process().memory_info().rss / 2**20


def live_buffers() -> tuple[int, float]:
    """``(count, MiB)`` of the OpenCL memory objects reachable from Python objects."""
    gc.collect()
    found = {}
    for obj in gc.get_objects():
        if isinstance(obj, cl.MemoryObjectHolder):
            found[id(obj)] = obj
        for ref in gc.get_referents(obj):
            if isinstance(ref, cl.MemoryObjectHolder):
                found[id(ref)] = ref
    return len(found), sum(b.size for b in found.values()) / 2**20


def _figures(label: str) -> dict:
    n, mib = live_buffers()
    return {"at": label, "rss_mb": round(rss_mb(), 1), "buffers": n,
            "buffer_mb": round(mib, 2)}


@pytest.fixture
def window(qtbot, tmp_path):
    w = open_window(tmp_path / "settings", size=(120, 90))
    w.resize(400, 300)  # the view shrinks to its minimum size: a fast loop
    yield w
    close_window(w)


def _check_flat(rows, what: str) -> None:
    """The second half adds < 50 MB and < 5 % of RSS; the buffers are the same."""
    first, half, end = rows[0], rows[len(rows) // 2], rows[-1]
    grew = end["rss_mb"] - half["rss_mb"]
    print(f"{what}: " + "; ".join(f"{r['at']}: RSS {r['rss_mb']} MB, {r['buffers']} "
                                   f"buffers {r['buffer_mb']} MiB" for r in rows))
    assert grew < 50 and grew < 0.05 * half["rss_mb"], f"RSS grew {grew:.1f} MB: {rows}"
    assert end["buffers"] == half["buffers"] == first["buffers"], rows
    assert end["buffer_mb"] == pytest.approx(half["buffer_mb"], rel=1e-6), rows


@pytest.mark.parametrize("changes", [30, pytest.param(1000, marks=pytest.mark.slow)])
def test_isovalue_camera_and_model_soak_keeps_memory_and_buffers_flat(window, changes):
    vol = window.open_default()
    iso = window.scene.isosurfaces_of(vol)[0]
    window.scene.select(iso)
    spin, box = window.iso_panel.spin, window.iso_panel.model
    index = {box.itemData(i): i for i in range(box.count())}
    lo, hi = vol.data.finite_range
    cam = window.scene.camera
    centre = np.asarray(cam.focal_point)
    radius = float(np.linalg.norm(np.subtract(cam.position, centre)))

    def checkpoint(label):
        box.setCurrentIndex(index[MODELS[0]])
        window.wait_for_refine()
        return _figures(label)

    models = MODELS if changes >= 100 else MODELS[:2]
    rows = []
    switch_every = max(changes // 20, 1)
    t0 = time.perf_counter()
    for step in range(changes):
        if step in (changes // 10, changes // 2):
            rows.append(checkpoint(f"change {step}"))
        spin.setValue(float(lo + (hi - lo) * (0.25 + 0.5 * ((step * 0.618) % 1.0))))
        if step % 3 == 0:  # orbit
            a = np.radians(7.0 * step)
            cam.update(position=tuple(map(float, centre + radius * np.array(
                [np.cos(a), np.sin(a), 0.5]) / np.linalg.norm([1, 1, 0.5]) * 1.2)))
        if step % switch_every == 0:
            box.setCurrentIndex(index[models[(step // switch_every) % len(models)]])
        window.wait_for_refine()
        assert window.last_error is None, window.last_error
    rows.append(checkpoint(f"change {changes}"))
    took = time.perf_counter() - t0
    print(f"{changes} isovalue changes ({took:.1f} s, {1000 * took / changes:.0f} ms each)")
    frame = window.spline_scene.shown_frame(window.view.scene_view.layers[iso.id])
    assert frame.final and frame.frame.hit.any()
    _check_flat(rows, f"{changes} isovalue changes")


@pytest.mark.parametrize("cycles", [3, pytest.param(100, marks=pytest.mark.slow)])
def test_bonsai_open_close_cycles_keep_memory_and_buffers_flat(window, shared_data, cycles):
    from splineviz.io.volumes import read_volume

    bonsai = read_volume(shared_data / "volumes" / "bonsai.vti")  # read once: cached
    rows = []
    window.wait_for_refine()
    t0 = time.perf_counter()
    for cycle in range(cycles + 1):
        if cycle in (max(cycles // 10, 1), cycles // 2 + 1, cycles):
            rows.append(_figures(f"cycle {cycle}"))
        if cycle == cycles:
            break
        node = window.scene.add_volume(bonsai, "bonsai.vti", isovalue=40.0)
        window.scene.frame(node.bounds, view="isometric")
        window.wait_for_refine(300)
        iso = window.scene.isosurfaces_of(node)[0]
        frame = window.spline_scene.shown_frame(window.view.scene_view.layers[iso.id])
        assert frame.final and frame.frame.hit.mean() > 0.02
        window.scene.remove(node)
        window.wait_for_refine()
        assert not len(window.scene) and window.last_error is None
    took = time.perf_counter() - t0
    print(f"{cycles} open/close cycles of bonsai ({took:.1f} s, {took / cycles:.2f} s each)")
    _check_flat(rows, f"{cycles} bonsai cycles")
