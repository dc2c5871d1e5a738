"""End to end under Xvfb: the real interactor driven by Qt mouse events (issue 11).

After each interaction (orbit by left-drag, wheel zoom, plane-widget drag, isovalue slider
drag) the window must show the exact full-resolution frame within 2 s of the interaction
ending, without any test hook asking for it: the picture grabbed from the window must match
an off-screen exact render of the same camera (:func:`offscreen_screenshot`) and must not be
blocky (the preview is cast at a reduced resolution, so its pixels come in equal blocks).

The window stays open across the tests of this module (opening it and casting the first
exact frame is most of the cost); each test leaves the scene as it found it, apart from the
camera.
"""

import time

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("pyvistaqt")

from interaction import (  # noqa: E402  (tests/gui helper, on sys.path via pytest)
    StallMeter,
    agreement,
    blockiness,
    drag,
    pump,
    surface_mask,
    wheel,
)

import splineviz as sv  # noqa: E402
from splineviz.render.scene import SplineScene, offscreen_screenshot  # noqa: E402

#: requested size of the 3-D view (the docks may make it taller)
VIEW = (360, 280)
#: the exact frame is on screen this long after the interaction ended (``splineviz bench
#: gui`` reports it per action); the tests wait three times as long, which a busy machine does
#: not need and a view that never refines does
SETTLE_S = 3 * 2.0
#: an exact frame: at least this share of pixels within 2/255 of the off-screen render at
#: the same pixel or one of its 8 neighbours (the window and the off-screen plotter draw the
#: outline's lines one pixel apart in places: ~1.6 % of pixels; the surface matches exactly)
MIN_AGREEMENT = 0.99
#: ... and at least this share at the same pixel (previews: <= 0.83 and <= 0.94 shifted) ...
MIN_STRICT_AGREEMENT = 0.95
#: ... and at most this share of surface pixels equal to their left neighbour
MAX_BLOCKINESS = 0.15


@pytest.fixture(scope="module")
def window(qapp, tmp_path_factory):
    from PySide6.QtCore import QSettings

    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(tmp_path_factory.mktemp("settings")))
    w = MainWindow(size=VIEW)
    w.show()
    w.resize(w.minimumSizeHint())
    w.open_default()
    # the orientation axes and the axes grid are window decorations the off-screen
    # reference (a copy of the spline scene's props) does not draw
    w.plotter.hide_axes()
    w.scene.view.show_scale = False
    pump(0.3)
    w.wait_for_refine(120)
    yield w
    w.wait_idle()
    w.close()
    pump(0.1)


def layer_of(w):
    return w.spline_scene.layers[0]


def scene_shows_exact(w) -> bool:
    """The layer's shown frame is final and made for the current view and layer state."""
    layer = layer_of(w)
    f = w.spline_scene.shown_frame(layer)
    return (f is not None and f.final and f.state == layer.state
            and f.view.key() == w.spline_scene.view_state().key())


def window_image(w) -> np.ndarray:
    """What the window shows now (the last rendered frame; no new render)."""
    return np.asarray(w.plotter.screenshot(return_img=True))[..., :3]


def center(w):
    return w.plotter.width() / 2.0, w.plotter.height() / 2.0


def assert_exact_after(w, what, compare_image=True):
    """Process events for at most :data:`SETTLE_S`; then the window must show the exact frame."""
    t0 = time.perf_counter()
    pump(SETTLE_S, lambda: scene_shows_exact(w))
    waited = time.perf_counter() - t0
    shown = w.spline_scene.shown_frame(layer_of(w))
    img = window_image(w)
    ref = offscreen_screenshot(w.spline_scene, size=w.spline_scene.window_size())[..., :3]
    mask = surface_mask(ref, w.plotter.renderer.GetBackground())
    block = blockiness(img, mask)
    state = (f"{what}: after {waited:.2f} s the shown frame has scale {shown.scale:.3f} "
             f"({shown.path}), final={shown.final}; blockiness {block:.3f} "
             f"(exact reference {blockiness(ref, mask):.3f})")
    assert mask.mean() > 0.02, f"{what}: the reference shows almost no surface"
    assert scene_shows_exact(w), state
    assert block < MAX_BLOCKINESS, state
    if compare_image:
        strict = agreement(img, ref, tol=2)
        near = agreement(img, ref, tol=2, shift=1)
        state += (f"; {strict:.4f} of pixels agree with the exact render ({near:.4f} within "
                  f"one pixel)")
        assert strict >= MIN_STRICT_AGREEMENT and near >= MIN_AGREEMENT, state
    print(f"{what}: exact frame on screen {waited:.2f} s after the interaction ended "
          f"(blockiness {block:.3f})")


def test_orbit_by_left_drag_ends_on_the_exact_frame(window):
    w = window
    cam = w.plotter.camera
    before = np.array(cam.GetPosition())
    cx, cy = center(w)
    with StallMeter() as stall:
        drag(w.plotter, (cx - 60, cy), (cx + 60, cy + 20), n=15)
    moved = np.linalg.norm(np.array(cam.GetPosition()) - before)
    assert moved > 1e-3 * np.linalg.norm(before), "the drag did not reach the interactor"
    print(f"orbit: longest GUI-thread stall {stall.max_ms:.0f} ms over {stall.ticks} ticks")
    assert_exact_after(w, "orbit")


def test_wheel_zoom_ends_on_the_exact_frame(window):
    w = window
    cam = w.plotter.camera
    before = np.linalg.norm(np.subtract(cam.GetPosition(), cam.GetFocalPoint()))
    with StallMeter() as stall:
        wheel(w.plotter, center(w), clicks=2)
    after = np.linalg.norm(np.subtract(cam.GetPosition(), cam.GetFocalPoint()))
    assert after < 0.95 * before, "the wheel did not zoom in"
    print(f"wheel: longest GUI-thread stall {stall.max_ms:.0f} ms")
    assert_exact_after(w, "wheel zoom")
    # and back out (wheel towards the user)
    wheel(w.plotter, center(w), clicks=-2)
    far = np.linalg.norm(np.subtract(cam.GetPosition(), cam.GetFocalPoint()))
    assert far > 1.05 * after
    assert_exact_after(w, "wheel zoom out")


def display_point(renderer, world, height):
    """Widget pixel (x right, y down) of a world point."""
    renderer.SetWorldPoint(*map(float, world), 1.0)
    renderer.WorldToDisplay()
    x, y, _ = renderer.GetDisplayPoint()
    return x, height - 1 - y


def test_plane_widget_drag_ends_on_the_exact_frame(window):
    w = window
    plotter = w.plotter
    bounds = np.asarray(layer_of(w).volume.bounds, float).reshape(3, 2)
    mid = bounds.mean(axis=1)
    w.view.standard_view("isometric")  # the plane x = mid at 45 degrees, whatever came before
    w.scene.select(w.scene.volumes[0])
    node = w.clip_panel.add_plane(origin=tuple(mid), normal=(1.0, 0.0, 0.0))
    assert node.id in w.plane_widgets.widgets  # the model's plane has its widget
    try:
        w.wait_for_refine(60)
        start = node.origin
        # grab the plane away from its origin sphere and normal arrow, push it along x
        ext = bounds[:, 1] - bounds[:, 0]
        grip = mid + np.array([0.0, 0.3 * ext[1], 0.3 * ext[2]])
        h = plotter.height()
        p0 = display_point(plotter.renderer, grip, h)
        p1 = display_point(plotter.renderer, grip + np.array([0.25 * ext[0], 0, 0]), h)
        with StallMeter() as stall:
            drag(plotter, p0, p1, n=10)
        assert node.origin != start, "the drag did not move the plane widget"
        assert w.spline_scene.layers[0].clip_planes[0][0] == pytest.approx(node.origin)
        print(f"plane drag: longest GUI-thread stall {stall.max_ms:.0f} ms")
        # the widget is drawn in the window but not in the off-screen reference: compare the
        # frame state and the blockiness of the window's surface pixels, not whole images
        assert_exact_after(w, "plane widget drag", compare_image=False)
    finally:
        w.scene.remove(node)
        w.wait_for_refine(60)


def test_isovalue_slider_drag_ends_on_the_exact_frame(window):
    w = window
    hist = getattr(getattr(w, "iso_panel", None), "histogram", None)
    if hist is None or not hist.isVisible():
        pytest.skip("the isovalue histogram slider is not reachable as window.iso_panel.histogram")
    layer = layer_of(w)
    before = layer.isovalue
    lo, hi = hist.range()
    width, y = hist.width(), hist.height() / 2.0

    def x_of(v):  # the slider's plot area spans 6 .. width - 6 pixels
        return 6 + (v - lo) / (hi - lo) * (width - 12)

    x0 = x_of(before)
    x1 = x0 + 0.1 * width if x0 < width / 2 else x0 - 0.1 * width
    with StallMeter() as stall:
        drag(hist, (x0, y), (x1, y), n=8)
    assert abs(layer.isovalue - before) > 0.02 * (hi - lo), "the slider drag did not apply"
    print(f"slider drag: longest GUI-thread stall {stall.max_ms:.0f} ms")
    try:
        assert_exact_after(w, "isovalue slider drag")
    finally:
        hist.setValue(before)  # back to the default isovalue for the tests after this one
        w.wait_for_refine(60)


def test_a_cell_projected_orbit_never_blocks_and_ends_on_the_exact_frame(window):
    """Issue 32 without an OpenCL-fast path: the surface drawn by cell projection (OpenGL),
    orbited through the interactor. On software OpenGL a cell-projected frame of the default
    data takes 0.25-0.8 s: drawn in the window it held the GUI thread that long after every
    drag; now the stand-in moves and the exact frame is drawn off the GUI thread."""
    w = window
    iso = w.scene.isosurfaces[0]
    layer = layer_of(w)
    iso.renderer = "cell-projection"
    try:
        w.wait_for_refine(120)
        cx, cy = center(w)
        with StallMeter() as stall:
            drag(w.plotter, (cx - 60, cy), (cx + 60, cy - 20), n=15)
            pump(SETTLE_S, lambda: scene_shows_exact(w))
        assert_exact_after(w, "cell-projected orbit")  # (its reference is drawn here)
        shown = w.spline_scene.shown_frame(layer)
        assert shown.path == "cell-projection" and w.spline_scene.drawn_by_cells(layer)
        print(f"cell-projected orbit and its exact frame: longest GUI-thread stall "
              f"{stall.max_ms:.0f} ms over {stall.ticks} ticks; the frame took "
              f"{shown.seconds:.2f} s off the GUI thread")
        # three times the 100 ms budget (a busy machine's tick; a frame drawn in the
        # window here took 250-800 ms on software OpenGL)
        assert stall.max_ms < 300.0
    finally:
        iso.renderer = "auto"
        w.wait_for_refine(120)


def test_scene_asks_for_exact_frames_when_an_interaction_ends():
    """What the window's interactor does in a drag or a wheel step, without a window: the
    render at the end of the interaction finds the last preview made for the current view;
    it must still ask for the exact frame (it did not: the view stayed blocky)."""
    import pyvista as pv

    from splineviz.render.isosurface import IsosurfaceLayer

    x = np.linspace(-1, 1, 15)
    vol = sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2), spacing=2 / 14,
                    origin=(-1, -1, -1))
    pl = pv.Plotter(off_screen=True, window_size=(80, 60))
    scene = SplineScene(pl, progressive=True)
    layer = IsosurfaceLayer(vol, model="trilinear", isovalue=0.64)
    scene.add_layer(layer)
    pl.camera_position = [(0.3, -5, 0.4), (0, 0, 0), (0, 0, 1)]
    pl.camera_set = True
    calls = []
    scene.request_refine = lambda: calls.append(1)
    try:
        pl.render_window.Render()
        scene.apply(scene.refine())
        pl.render_window.Render()
        assert scene.shown_frame(layer).final and not scene.needs_refine()
        calls.clear()
        scene.set_interacting(True)  # StartInteractionEvent
        pl.camera.Azimuth(15)
        pl.render_window.Render()  # a drag step: a preview, no refinement yet
        assert not scene.shown_frame(layer).final and not calls
        scene.set_interacting(False)  # EndInteractionEvent, then the window renders
        pl.render_window.Render()
        assert calls, "the end of the interaction did not ask for the exact frame"
        assert scene.needs_refine() and scene.apply(scene.refine())
        calls.clear()
        pl.render_window.Render()
        assert scene.shown_frame(layer).final and not calls and not scene.needs_refine()
    finally:
        scene.close()
        pl.close()
