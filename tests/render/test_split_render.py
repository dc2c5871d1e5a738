"""render_scene of a split scene: its two views side by side, each the picture of its own
objects."""

import numpy as np

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.model import Scene
from splineviz.render.scene_view import render_scene


def test_render_scene_draws_the_split_as_two_half_pictures():
    scene = Scene()
    scene.add_volume(sv.Volume.from_function(ml, (25, 25, 25), ml.domain), name="ML")
    left = scene.isosurfaces[0]
    scene.aspect = 1.0
    scene.frame(view="isometric")
    scene.compare(left, model="trilinear")
    img = render_scene(scene, (240, 120))
    assert img.shape == (120, 240, 3)
    # the right half is the picture of the right view alone (its own model, the linked
    # camera at half the width); the left half is another model's picture
    scene.view.split = False
    left.visible = False
    only_right = render_scene(scene, (120, 120))
    np.testing.assert_array_equal(img[:, 120:], only_right)
    differ = np.abs(img[:, :120].astype(int) - only_right).max(axis=2) > 10
    assert differ.mean() > 0.02  # cubic C1 and trilinear surfaces look different


def test_narrow_views_get_scalar_bars_whose_labels_fit():
    import pyvista as pv

    from splineviz.render.isosurface import IsosurfaceLayer
    from splineviz.render.scene import NARROW_BAR_PX, SplineScene

    vol = sv.Volume.from_function(ml, (9, 9, 9), ml.domain)
    for width, labels in ((NARROW_BAR_PX - 1, 3), (NARROW_BAR_PX, 5)):
        pl = pv.Plotter(off_screen=True, window_size=(width, 200))
        scene = SplineScene(pl)
        layer = IsosurfaceLayer(vol, model="trilinear", isovalue=0.5)
        scene.add_layer(layer)
        scene._fit_scalar_bars()
        bar = scene._views[id(layer)].scalar_bar
        x, _ = bar.GetPosition()
        assert bar.GetNumberOfLabels() == labels
        assert 0.0 <= x and x + bar.GetWidth() <= 1.0  # inside the view
        scene.close()
        pl.close()
