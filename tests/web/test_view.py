"""The web view's frames without a browser: previews while the camera moves, exact frames
equal to render_scene at the camera the view reports."""

import numpy as np
import pytest

from splineviz.model.opening import default_scene
from splineviz.notebook import place_camera
from splineviz.render.scene_view import render_scene
from splineviz.web.view import RemoteView, WebViewError

SIZE = (160, 120)


def surface_share(image) -> float:
    """Share of pixels of the warm surface colour (the background and outline are grey)."""
    image = image.astype(int)
    return float(((image[..., 0] - image[..., 2]) > 40).mean())


@pytest.fixture
def view():
    v = RemoteView(default_scene(), SIZE)
    yield v
    v.close()


def test_orbit_previews_then_exact_frame_is_render_scene(view):
    first = view.exact()
    assert first.exact and np.array_equal(first.image, render_scene(default_scene(), SIZE))
    view.orbit(8, -3)
    preview = view.preview()
    assert not preview.exact
    # a preview shows the surface (blocks of a reduced resolution), never the outline alone
    assert surface_share(preview.image) > 0.3 * surface_share(first.image) > 0
    assert preview.state["camera"] != first.state["camera"]
    exact = view.exact()
    reference = default_scene()
    place_camera(reference, exact.state["camera"])
    assert np.array_equal(exact.image, render_scene(reference, SIZE))
    assert not np.array_equal(exact.image, first.image)


def test_first_preview_and_a_new_model_show_the_surface(view):
    assert surface_share(view.preview().image) > 0.02
    view.set("model", "trilinear")
    assert surface_share(view.preview().image) > 0.02


def test_controls_change_the_scene(view):
    iso = view.isosurface
    lo, hi = view.controls()["isovalue_range"]
    view.set("isovalue", lo + 0.2 * (hi - lo))
    assert iso.isovalue == pytest.approx(lo + 0.2 * (hi - lo))
    view.set("model", "trilinear")
    assert iso.model == "trilinear"
    view.set("clip", True)
    assert view.state()["clip"] and len(view.scene.clip_planes) == 1
    view.set("clip", False)
    assert not view.state()["clip"]
    view.set("color_by", "mean")
    assert iso.color_by == "mean"
    with pytest.raises(WebViewError, match="unknown control"):
        view.set("opacity", 0.5)
    with pytest.raises(WebViewError, match="finite"):
        view.set("isovalue", float("nan"))


def test_a_cell_projected_surface_previews_by_its_tets():
    scene = default_scene()
    scene.isosurfaces[0].renderer = "cell-projection"
    v = RemoteView(scene, SIZE)
    try:
        shot = v.preview()
        assert surface_share(shot.image) > 0.02
        layer = v._view.layers[scene.isosurfaces[0].id]
        assert layer.cells_current() and v._view.spline_scene.shown_frame(layer) is None
        exact = v.exact()
        assert exact.exact and np.array_equal(exact.image, render_scene(scene, SIZE))
    finally:
        v.close()
