"""Colour by curvature, gradient magnitude or another volume: values at the ray hits from the
spline, colour maps by name, ranges, the scalar bar and the picked value."""

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
from splineviz.core.colour_by import ColourByError, hit_scalars, scalar_range  # noqa: E402
from splineviz.render.colormaps import ColormapError, colorize, lut  # noqa: E402
from splineviz.render.isosurface import IsosurfaceLayer, LayerError, ViewState  # noqa: E402
from splineviz.render.scene import SplineScene  # noqa: E402

W, H = 96, 72
CAMERA = sv.Camera((0.3, -5, 0.4), (0, 0, 0), view_up=(0, 0, 1))


def grid(n, lo=-1.0, hi=1.0):
    return sv.Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (n,) * 3,
                                   ((lo, hi),) * 3)


@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_colour_by_another_volume_is_its_value_at_each_hit(model):
    # the second volume: a linear field on another grid, reproduced exactly by every model
    other = sv.Volume.from_function(lambda x, y, z: 2 * x - 3 * y + 0.5 * z, (17, 19, 23),
                                    ((-1.2, 1.1), (-1.1, 1.3), (-1.0, 1.2)))
    layer = IsosurfaceLayer(grid(21), model=model, isovalue=0.64)
    layer.set_color_by("volume", other)
    rf = layer.compute(ViewState(CAMERA, (W, H)))
    hit = rf.frame.hit
    assert hit.sum() > 500
    p = rf.frame.position[hit]
    exact = 2 * p[:, 0] - 3 * p[:, 1] + 0.5 * p[:, 2]
    lo, hi = other.finite_range
    assert np.abs(rf.scalars[hit] - exact).max() < 1e-6 * (hi - lo)
    assert np.isnan(rf.scalars[~hit]).all()


def test_curvature_at_hits_of_a_sphere():
    # distance field: the level set r = 0.6 has k1 = k2 = -1 / 0.6 (values increase outwards)
    vol = sv.Volume.from_function(lambda x, y, z: np.sqrt(x * x + y * y + z * z), (41,) * 3,
                                  ((-1, 1),) * 3)
    layer = IsosurfaceLayer(vol, model="cubic-c1", isovalue=0.6)
    layer.set_color_by("mean")
    rf = layer.compute(ViewState(CAMERA, (W, H)))
    mean = rf.scalars[rf.frame.hit]
    assert np.median(np.abs(mean + 1 / 0.6)) < 0.02 / 0.6
    s = sv.build_spline(vol, "cubic-c1")
    pts = rf.frame.position[rf.frame.hit][:50]
    g = hit_scalars(s, pts, "gaussian")
    assert np.median(np.abs(g - 1 / 0.36)) < 0.05 / 0.36
    si = hit_scalars(s, pts, "shape-index")
    assert np.all(si < -0.9)  # a cup seen from the side of lower values
    np.testing.assert_allclose(hit_scalars(s, pts, "gradient-magnitude"), 1.0, atol=0.02)


def test_distance_to_another_isovalue_of_an_exact_sphere():
    # cubic-c1 of x^2 + y^2 + z^2 is exact up to + 3 h^2 / 4: radii 0.6 and 0.7 exactly
    vol = grid(31, -1.5, 1.5)
    c = 0.75 * 0.1**2
    layer = IsosurfaceLayer(vol, model="cubic-c1", isovalue=0.36 + c)
    layer.set_color_by("distance", reference=(vol, "cubic-c1", {}, 0.49 + c))
    rf = layer.compute(ViewState(CAMERA, (W, H)))
    d = rf.scalars[rf.frame.hit]
    assert rf.frame.hit.sum() > 300
    np.testing.assert_allclose(d, -0.1, atol=1e-6)  # inside the larger sphere: negative


def test_ranges_and_maps():
    v = np.r_[np.linspace(-1, 3, 1001), np.nan]
    lo, hi = scalar_range(v, "auto")
    assert -1 < lo < -0.9 and 2.9 < hi < 3
    assert scalar_range(v, "symmetric") == (-hi, hi)
    assert scalar_range(v, "manual", 0.5, 2.0) == (0.5, 2.0)
    assert scalar_range(np.full(5, 2.0), "auto")[0] < 2.0 < scalar_range(np.full(5, 2.0))[1]
    with pytest.raises(ColourByError):
        scalar_range(v, "log")
    rgb = colorize(np.array([-5.0, 0.0, 1.0, 9.0, np.nan]), "viridis", 0.0, 1.0)
    table = lut("viridis")
    assert rgb[0].tolist() == table[0].tolist() == rgb[1].tolist()
    assert rgb[2].tolist() == table[-1].tolist() == rgb[3].tolist()
    assert rgb[4].tolist() == [128, 128, 128]
    with pytest.raises(ColormapError):
        lut("no-such-map")
    layer = IsosurfaceLayer(grid(9), model="trilinear", isovalue=0.5)
    with pytest.raises(LayerError):
        layer.set_color_by("temperature")
    with pytest.raises(LayerError):
        layer.set_color_map("no-such-map")
    with pytest.raises(LayerError):
        layer.set_color_map(limits=(1.0, 1.0))


def test_scene_colours_the_surface_and_shows_a_scalar_bar():
    pl = pv.Plotter(off_screen=True, window_size=(W * 2, H * 2))
    pl.set_background("black")
    scene = SplineScene(pl)
    layer = IsosurfaceLayer(grid(21), model="trilinear", isovalue=0.64, color=(0.9, 0.9, 0.9))
    scene.add_layer(layer)
    pl.camera_position = [(0.3, -5, 0.4), (0, 0, 0), (0, 0, 1)]
    pl.camera_set = True
    other = sv.Volume.from_function(lambda x, y, z: x + 0 * y, (9, 9, 9), ((-1, 1),) * 3)
    layer.set_color_by("volume", other)
    layer.set_color_map("coolwarm", "symmetric")
    scene.render_exact()
    img = np.asarray(pl.screenshot(return_img=True)).astype(int)
    lo, hi = scene.color_range(layer)
    assert lo == -hi and 0.65 < hi <= 0.8  # the 98th percentile of x on a radius-0.8 sphere
    bar = scene._views[id(layer)].scalar_bar
    assert bar.GetVisibility() and bar.GetTitle().endswith("volume")
    # coolwarm: the -x side (image left) bluish, the +x side reddish
    row = img[H - 8]
    left, right = row[: W - 20], row[W + 20:]
    lit = lambda part: part[part.sum(axis=1) > 60]  # noqa: E731
    assert (lit(left)[:, 2] > lit(left)[:, 0]).mean() > 0.8
    assert (lit(right)[:, 0] > lit(right)[:, 2]).mean() > 0.8
    # picked value: the window centre sees x ~ 0.3 / 5 * ... close to 0
    value = scene.picked_value(layer, W, H)
    assert value is not None and abs(value) < 0.2
    layer.set_color_by("none")
    scene.render_exact()
    assert scene.color_range(layer) is None and not bar.GetVisibility()
    pl.close()
