"""Both halves of a split view colour one surface over one range unless unlinked
(issue 26, part 4)."""

import pyvista as pv

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.model import Scene
from splineviz.render.scene_view import SceneView, colour_range_link


def _two_views(scene, sizes=((120, 90), (120, 170))):
    """Two views of other sizes: their frames hold other pixels of the surface (as a
    preview of one beside an exact frame of the other)."""
    views = []
    for side, size in zip(("left", "right"), sizes, strict=True):
        pl = pv.Plotter(off_screen=True, window_size=size)
        views.append((pl, SceneView(scene, pl, side=side)))
    return views


def _range(view, node):
    return view.spline_scene.color_range(view.layers[node.id])


def _own(view, node):
    """The range the view's own frame needs (2-98 % of its values)."""
    layer = view.layers[node.id]
    rf = view.spline_scene.shown_frame(layer)
    return layer.color_range_of(rf.scalars[rf.frame.hit])


def test_the_halves_of_a_split_share_the_range_of_a_surface_unless_unlinked():
    scene = Scene()
    vol = scene.add_volume(sv.Volume.from_function(ml, (17, 17, 17), ml.domain), "ML",
                           isovalue=0.5, model="trilinear")
    iso = scene.isosurfaces_of(vol)[0]
    iso.color_by = "mean"
    scene.aspect = 1.0
    scene.frame(view="isometric")
    scene.view.split = True
    views = _two_views(scene)
    link = colour_range_link(scene)
    heard = []
    link.listeners.append(lambda key, value: heard.append((key, value)))
    try:
        (pl_a, a), (pl_b, b) = views
        a.render_exact()
        b.render_exact()
        own_a, own_b = _own(a, iso), _own(b, iso)
        # the frames differ, so do their percentiles; both views use the span
        assert own_a != own_b
        span = (min(own_a[0], own_b[0]), max(own_a[1], own_b[1]))
        assert _range(a, iso) == _range(b, iso) == link.range_of(iso.id) == span
        assert heard and heard[-1] == (iso.id, span)
        link.set_enabled(False)  # each view colours again by its own frame (no new cast)
        assert _range(a, iso) == own_a and _range(b, iso) == own_b
        link.set_enabled(True)
        assert _range(a, iso) == _range(b, iso) == span
    finally:
        link.set_enabled(True)
        for pl, view in views:
            view.close()
            pl.close()
    assert link.range_of(iso.id) is None  # closed views leave nothing behind



def test_an_exported_picture_has_the_colours_of_the_view(monkeypatch):
    from splineviz.render.scene import SplineScene, offscreen_screenshot

    scene = Scene()
    vol = scene.add_volume(sv.Volume.from_function(ml, (17, 17, 17), ml.domain), "ML",
                           isovalue=0.5, model="trilinear")
    iso = scene.isosurfaces_of(vol)[0]
    iso.color_by = "mean"
    scene.frame(view="isometric")
    pl = pv.Plotter(off_screen=True, window_size=(120, 90))
    view = SceneView(scene, pl)
    seen = []
    close = SplineScene.close

    def recording_close(self):
        seen.extend(self.color_range(layer) for layer in self.layers)
        close(self)

    monkeypatch.setattr(SplineScene, "close", recording_close)
    try:
        view.render_exact()
        shown = _range(view, iso)
        offscreen_screenshot(view.spline_scene, size=(300, 260))
        # the copy's own frame (another size) needs another range; it used the view's
        assert seen == [shown]
    finally:
        monkeypatch.undo()
        view.close()
        pl.close()
