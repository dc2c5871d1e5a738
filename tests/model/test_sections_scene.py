"""Cross sections as scene objects: computed from the splines, drawn as lines, following their
inputs, saved in sessions and exported with lengths and areas."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.model import ModelError, Scene, SectionNode
from splineviz.model.analysis import section_curves
from splineviz.model.session import load_scene, save_scene

R = 10.0


def sphere_scene():
    scene = Scene()
    vol = sv.Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (32, 32, 32),
                                  ((-15.5, 15.5),) * 3)
    vnode = scene.add_volume(vol, "sphere", isosurface=False)
    iso = scene.add_isosurface(vnode, isovalue=R * R + 0.75, model="cubic-c1")
    plane = scene.add_clip_plane((0, 0, 3.0), (0, 0, 1), volume=vnode)
    return scene, vnode, iso, plane


def test_section_follows_the_plane_and_saves(tmp_path):
    scene, vnode, iso, plane = sphere_scene()
    sec = scene.add_section(iso, plane=plane, line_width=2.0)
    (c,) = section_curves(scene, sec)
    assert abs(c.length / (2 * np.pi * np.sqrt(R * R - 9.0)) - 1) < 1e-6
    # saved with its inputs, the curves recomputed on load
    lin = scene.add_volume(sv.Volume.from_function(lambda x, y, z: x + 0 * y, (9, 9, 9),
                                                   ((-16, 16),) * 3), "x", isosurface=False)
    other = scene.add_isosurface(lin, isovalue=2.0, model="cubic-c1")
    sec2 = scene.add_section(iso, other=other, color=(0.1, 0.9, 0.1))
    path = save_scene(scene, tmp_path / "s")
    back = load_scene(path)
    s1, s2 = back.get(sec.id), back.get(sec2.id)
    assert (s1.plane_id, s1.line_width) == (plane.id, 2.0)
    assert (s2.other_id, s2.color) == (other.id, (0.1, 0.9, 0.1))
    (c2,) = section_curves(back, s2)
    assert abs(c2.area / (np.pi * (R * R - 4.0)) - 1) < 1e-6
    # removing an input removes the section
    back.remove(back.get(plane.id))
    assert sec.id not in back and sec2.id in back


def test_bad_sections_are_refused():
    scene, vnode, iso, plane = sphere_scene()
    with pytest.raises(ModelError):
        scene.add(SectionNode(isosurface_id=iso.id))
    with pytest.raises(ModelError):
        scene.add(SectionNode(isosurface_id=iso.id, other_id=iso.id))
    with pytest.raises(ModelError):
        scene.add(SectionNode(isosurface_id=plane.id, plane_id=plane.id))


def test_view_draws_the_curves_and_redraws_them_when_the_plane_moves():
    pv = pytest.importorskip("pyvista")
    from splineviz.render.scene_view import SceneView

    scene, vnode, iso, plane = sphere_scene()
    sec = scene.add_section(iso, plane=plane)
    pl = pv.Plotter(off_screen=True, window_size=(120, 90))
    view = SceneView(scene, pl)
    rec = view.spline_scene.props[f"section:{sec.id}"]
    pts = np.asarray(rec.dataset.points)
    np.testing.assert_allclose(pts[:, 2], 3.0, atol=1e-9)
    plane.origin = (0.0, 0.0, -5.0)
    rec = view.spline_scene.props[f"section:{sec.id}"]
    np.testing.assert_allclose(np.asarray(rec.dataset.points)[:, 2], -5.0, atol=1e-9)
    iso.isovalue = 0.5  # no surface crosses the plane any more: the lines go away
    assert f"section:{sec.id}" not in view.spline_scene.props
    view.close()
    pl.close()
