"""The volume rendering layer of a live view (issue 30): its exact frame in the window is
the picture render_scene composites, synchronously and through the refine worker's path
(preview first, then the exact frame against the scene's depth)."""

import numpy as np
import pyvista as pv

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.model import Scene
from splineviz.render.scene_view import SceneView, render_scene

SIZE = (120, 96)
#: mean of the per-pixel largest channel difference allowed (the overlay holds straight
#: 8-bit colour, render_scene premultiplied floats)
MEAN_TOL = 1.0


def _scene():
    scene = Scene()
    node = scene.add_volume(sv.Volume.from_function(ml, (21, 21, 21), ml.domain), name="ML")
    scene.aspect = SIZE[0] / SIZE[1]
    scene.frame(view="isometric")
    node.update(volume_rendering=True, transfer_function="mri")
    return scene, node


def _difference(a, b) -> float:
    return float(np.abs(a[..., :3].astype(int) - b[..., :3]).max(axis=2).mean())


def test_live_layer_matches_render_scene():
    scene, node = _scene()
    expected = render_scene(scene, SIZE, device="cpu")
    pl = pv.Plotter(off_screen=True, window_size=SIZE)
    view = SceneView(scene, pl, progressive=False, device="cpu", live_volume_rendering=True)
    try:
        assert len(view.spline_scene.volume_layers) == 1
        view.render_exact()
        shown = pl.screenshot(None, return_img=True)
        assert _difference(shown, expected) < MEAN_TOL
        node.update(volume_rendering=False)
        assert not view.spline_scene.volume_layers
        view.render_exact()
        plain = pl.screenshot(None, return_img=True)
        assert _difference(plain, expected) > 10 * MEAN_TOL
    finally:
        view.close()
        pl.close()


def test_progressive_layer_is_refined_to_the_exact_frame():
    scene, node = _scene()
    expected = render_scene(scene, SIZE, device="cpu")
    pl = pv.Plotter(off_screen=True, window_size=SIZE)
    view = SceneView(scene, pl, progressive=True, device="cpu")
    ss = view.spline_scene
    asked = []
    ss.request_refine = lambda: asked.append(1)
    try:
        (layer,) = ss.volume_layers
        partial = []
        for _ in range(4):  # the isosurface's exact frame changes the depth: a second round
            pl.render_window.Render()
            if not ss.needs_refine():
                break
            assert asked
            results = ss.refine(ss.next_view_state(),
                                partial=lambda lyr, f: partial.append((lyr, f)))
            assert ss.apply(results)
        pl.render_window.Render()
        # the worker showed a preview of the volume before its exact frame
        assert any(lyr is layer and f.path == "preview" and not f.final for lyr, f in partial)
        shown = ss.shown_frame(layer)
        assert shown.final and not ss.needs_refine()
        img = pl.screenshot(None, return_img=True)
        assert _difference(img, expected) < MEAN_TOL
        # a new transfer function: the frame is of another state, refined again
        node.update(transfer_function="ct-bone")
        pl.render_window.Render()
        assert ss.needs_refine()
        assert ss.apply(ss.refine(ss.next_view_state()))
        pl.render_window.Render()
        assert not ss.needs_refine()
        other = pl.screenshot(None, return_img=True)
        assert _difference(other, img) > MEAN_TOL
        assert _difference(other, render_scene(scene, SIZE, device="cpu")) < MEAN_TOL
    finally:
        view.close()
        pl.close()
