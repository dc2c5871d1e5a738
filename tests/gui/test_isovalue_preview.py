"""Dragging the isovalue slider: every step shows a picture of the new isovalue within
100 ms (a reduced-resolution preview), the last one becomes the exact frame, and a frame of
an older isovalue is never shown after one of a newer isovalue.

The default suite drags across the default data against a guard of :data:`PREVIEW_GUARD_S`
(three times the budget: a busy machine's tick does not reach it, a render in the GUI thread
does); ``-m slow`` asserts the 100 ms budget on the same data and drags across bonsai (256^3)
with the cubic C1 model, the issue's case.
"""

import os
import time

import pytest

pytest.importorskip("pytestqt")

from interaction import (  # noqa: E402
    FRESH,
    LEFT,
    NO_BUTTON,
    close_window,
    in_fresh_process,
    mouse,
    open_window,
    pump,
)
from PySide6.QtCore import QEvent  # noqa: E402

#: a picture of the new isovalue must be on screen this soon after a slider step
PREVIEW_S = 0.100
#: the default suite's limit on it
PREVIEW_GUARD_S = 0.300
#: the exact frame must follow the release within this time
EXACT_S = 30.0


@pytest.fixture
def window(qapp, tmp_path):
    w = open_window(tmp_path)
    yield w
    close_window(w)


def _drag_across(w, steps=12):
    iso = w.scene.isosurfaces[0]
    w.scene.select(iso)
    layer = w.view.scene_view.layers[iso.id]
    scene = w.spline_scene
    shown_versions = []
    original = scene._show

    def spy(lyr, rf):  # every frame that reaches the screen, in order
        shown_versions.append(rf.state[0])
        return original(lyr, rf)

    scene._show = spy
    hist = w.iso_panel.histogram
    lo, hi = hist.range()
    width, y = hist.width(), hist.height() / 2.0

    def x_of(v):  # the slider's plot area spans 6 .. width - 6 pixels
        return 6 + (v - lo) / (hi - lo) * (width - 12)

    xs = [x_of(lo + (hi - lo) * f) for f in [0.15 + 0.7 * i / (steps - 1) for i in range(steps)]]
    latencies, values = [], []
    try:
        mouse(hist, QEvent.Type.MouseButtonPress, (xs[0], y), LEFT, LEFT)
        for x in xs[1:]:
            mouse(hist, QEvent.Type.MouseMove, (x, y), NO_BUTTON, LEFT)
            t0 = time.perf_counter()
            state = layer.state
            ok = pump(2.0, lambda s=state: (scene.shown_frame(layer) is not None
                                            and scene.shown_frame(layer).state == s))
            latencies.append(time.perf_counter() - t0 if ok else float("inf"))
            values.append(iso.isovalue)
        mouse(hist, QEvent.Type.MouseButtonRelease, (xs[-1], y), LEFT, NO_BUTTON)
        t0 = time.perf_counter()
        assert pump(EXACT_S, lambda: (scene.shown_frame(layer).final
                                      and scene.shown_frame(layer).state == layer.state
                                      and not w.view.refining))
        exact_s = time.perf_counter() - t0
    finally:
        scene._show = original
    print(f"{len(latencies)} slider steps over {values[0]:.4g} .. {values[-1]:.4g}: picture of "
          f"the new isovalue after {1000 * max(latencies):.0f} ms at worst "
          f"(median {1000 * sorted(latencies)[len(latencies) // 2]:.0f} ms); exact frame "
          f"{exact_s:.2f} s after the release")
    assert len(set(values)) == len(values), "every step changed the isovalue"
    assert shown_versions == sorted(shown_versions), "an older frame came after a newer one"
    return latencies


def _drag_across_twice_if_slow(w, limit_s=PREVIEW_S):
    """:func:`_drag_across`, and once more when a step missed ``limit_s``: on this shared
    2-core machine another process can take the CPU for a step; a delay of our own shows in
    both drags."""
    latencies = _drag_across(w)
    if max(latencies) > limit_s:
        latencies = _drag_across(w)
    assert max(latencies) <= limit_s, latencies


@pytest.mark.skipif(os.environ.get(FRESH) != "1", reason="run in a fresh process by "
                    "test_slider_drag_on_the_default_data_previews_every_step_alone")
def test_slider_drag_on_the_default_data_previews_every_step(window):
    window.open_default()
    window.wait_for_refine()
    _drag_across_twice_if_slow(window, PREVIEW_GUARD_S)


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get(FRESH) != "1", reason="run in a fresh process by "
                    "test_slider_drag_on_the_default_data_keeps_the_budget_alone")
def test_slider_drag_on_the_default_data_keeps_the_budget(window):
    window.open_default()
    window.wait_for_refine()
    _drag_across_twice_if_slow(window, PREVIEW_S)


@pytest.mark.slow
def test_slider_drag_across_bonsai_with_cubic_c1(window, shared_data):
    window.open_path(shared_data / "volumes" / "bonsai.vti", mode="replace", isovalue=40.5,
                     model="cubic-c1")
    window.wait_idle(300)
    window.wait_for_refine(300)
    _drag_across_twice_if_slow(window)


@pytest.mark.skipif(os.environ.get(FRESH) == "1", reason="this process is the fresh one")
def test_slider_drag_on_the_default_data_previews_every_step_alone():
    in_fresh_process("tests/gui/test_isovalue_preview.py::test_slider_drag_on_the_default_data_previews_every_step")


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get(FRESH) == "1", reason="this process is the fresh one")
def test_slider_drag_on_the_default_data_keeps_the_budget_alone():
    in_fresh_process("tests/gui/test_isovalue_preview.py::"
                     "test_slider_drag_on_the_default_data_keeps_the_budget", marks="slow")
