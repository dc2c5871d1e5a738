"""``scene.widget()``: an ipywidgets view whose image is render_scene of the scene as its
controls leave it (no browser: the controls are set as a notebook front end sets them)."""

import io

import numpy as np
import pytest

pytest.importorskip("ipywidgets")

from splineviz.model.opening import default_scene  # noqa: E402
from splineviz.render.scene_view import render_scene  # noqa: E402
from splineviz.widget import SceneWidget  # noqa: E402

SIZE = (160, 120)


def _image(widget) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(widget.image.value)))


def test_widget_controls_change_the_scene_and_its_exact_picture():
    import ipywidgets

    scene = default_scene()
    widget = scene.widget(size=SIZE)
    try:
        assert isinstance(widget, SceneWidget) and isinstance(widget, ipywidgets.Box)
        first = _image(widget)
        assert np.array_equal(first, render_scene(scene, SIZE))

        iso = scene.isosurfaces[0]
        lo, hi = widget.isovalue.min, widget.isovalue.max
        widget.isovalue.value = lo + 0.8 * (hi - lo)
        assert iso.isovalue == pytest.approx(widget.isovalue.value)
        moved = _image(widget)
        assert np.array_equal(moved, render_scene(scene, SIZE))
        assert not np.array_equal(moved, first)

        widget.clip.value = True
        assert any(p.enabled for p in scene.clip_planes)
        assert np.array_equal(_image(widget), render_scene(scene, SIZE))

        widget.color_by.value = "mean"
        widget.model.value = "trilinear"
        assert (iso.color_by, iso.model) == ("mean", "trilinear")
        assert np.array_equal(_image(widget), render_scene(scene, SIZE))

        pose = scene.camera.pose()
        widget.children[-1].children[1].click()  # orbit right
        assert scene.camera.pose()["position"] != pose["position"]
        assert np.array_equal(_image(widget), render_scene(scene, SIZE))
    finally:
        widget.close()


def test_widget_without_ipywidgets_is_one_clear_error(monkeypatch):
    import sys

    from splineviz.core.pictures import PictureError

    monkeypatch.setitem(sys.modules, "ipywidgets", None)
    monkeypatch.delitem(sys.modules, "splineviz.widget", raising=False)
    with pytest.raises(PictureError, match="needs ipywidgets"):
        default_scene().widget()
