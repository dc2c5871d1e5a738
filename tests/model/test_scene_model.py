"""The scene model (no Qt): ids, events, validation, dependants, framing, and sessions as a
complete round trip of every property of every kind of object."""

import subprocess
import sys

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.model import (
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    ModelError,
    PointsNode,
    Scene,
    VolumeNode,
)
from splineviz.model.scene import first_isovalue
from splineviz.model.session import load_scene, save_scene, to_session


def ml_volume(n=13):
    return sv.Volume.from_function(ml, (n, n, n), ml.domain)


def test_model_imports_no_qt_or_vtk():
    code = ("import sys, splineviz.model, splineviz.model.session, splineviz.model.opening;"
            "bad=[m for m in sys.modules if m.split('.')[0] in "
            "('PySide6','vtk','vtkmodules','pyvista','pyopencl','pyvistaqt','superqt')];"
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_ids_events_and_validation():
    scene = Scene()
    seen = []
    scene.inserted.connect(lambda n: seen.append(("+", n.id)))
    scene.removed.connect(lambda n: seen.append(("-", n.id)))
    vol = scene.add_volume(ml_volume(), "ml")
    iso = scene.isosurfaces[0]
    assert (vol.id, iso.id) == ("volume1", "isosurface1") and iso.volume_id == vol.id
    # the first isovalue comes from the data's histogram (core/default_isovalue.py)
    assert iso.isovalue == pytest.approx(first_isovalue(vol.data))
    fields = []
    iso.events.isovalue.connect(fields.append)
    iso.isovalue = 0.25
    assert fields == [0.25] and scene.modified
    for field, bad in (("isovalue", float("nan")), ("opacity", 0.0), ("model", "nope"),
                       ("material", "velvet"), ("color", (2, 0, 0))):
        before = getattr(iso, field)
        with pytest.raises(ModelError, match=field):
            setattr(iso, field, bad)
        assert getattr(iso, field) == before
    with pytest.raises(ModelError, match="not in the scene"):
        scene.add(IsosurfaceNode(volume_id="volume99"))
    second = scene.add_isosurface(vol)
    assert second.color != iso.color and second.isovalue != iso.isovalue
    plane = scene.add_clip_plane(volume=vol)
    everywhere = scene.add_clip_plane(normal=(0, 1, 0))
    assert scene.planes_for(vol) == [plane.as_pair(), everywhere.as_pair()]
    scene.select(iso)
    scene.remove(vol)  # its isosurfaces and planes go with it; scene-wide planes stay
    assert [n.id for n in scene] == [everywhere.id] and scene.selected is None
    assert ("-", iso.id) in seen and ("-", plane.id) in seen


def test_camera_moves_do_not_mark_the_scene_modified():
    scene = Scene()
    scene.add_volume(ml_volume(), "ml")
    scene.mark_saved()
    changes = []
    scene.changed.connect(lambda: changes.append(1))
    scene.camera.position = (5.0, 5.0, 5.0)
    assert changes and not scene.modified


@pytest.mark.parametrize("aspect", [0.4, 1.0, 2.5])
@pytest.mark.parametrize("view", ["+X", "-Z", "isometric"])
def test_frame_shows_every_corner(aspect, view):
    scene = Scene()
    scene.add_volume(sv.Volume(np.zeros((4, 5, 6)), spacing=(1, 2, 3), origin=(-5, 0, 7)), "v")
    scene.aspect = aspect
    scene.frame(view=view)
    cam = sv.Camera(scene.camera.position, scene.camera.focal_point, scene.camera.view_up,
                    scene.camera.view_angle)
    right, up, forward = cam.basis()
    t = np.tan(np.radians(cam.view_angle) / 2)
    for corner in np.array(np.meshgrid(*scene.bounds(), indexing="ij")).reshape(3, -1).T:
        d = corner - np.asarray(cam.position)
        depth = d @ forward
        assert depth > 0
        assert abs(d @ up) / depth <= t and abs(d @ right) / depth <= t * aspect


def _all_corners_in_view(scene):
    cam = sv.Camera(scene.camera.position, scene.camera.focal_point, scene.camera.view_up,
                    scene.camera.view_angle)
    right, up, forward = cam.basis()
    t = np.tan(np.radians(cam.view_angle) / 2)
    corners = np.array(np.meshgrid(*scene.bounds(), indexing="ij")).reshape(3, -1).T
    d = corners - np.asarray(cam.position)
    depth = d @ forward
    return bool(np.all(np.abs(d @ up) <= t * depth)
                and np.all(np.abs(d @ right) <= t * scene.aspect * depth))


def test_a_framed_view_that_changes_shape_is_framed_again():
    """Opened from the command line, the data were framed for a square view; the window's
    portrait 3-D view then cut a CAD scan at its sides. A camera the user has moved stays."""
    scene = Scene()
    scene.add_volume(sv.Volume(np.zeros((20, 8, 6))), "v")
    scene.frame(view="isometric")
    scene.aspect = 0.45
    assert _all_corners_in_view(scene)
    direction = np.subtract(scene.camera.position, scene.camera.focal_point)
    scene.aspect = 2.0  # wider: closer again, the same direction
    assert _all_corners_in_view(scene)
    moved = np.subtract(scene.camera.position, scene.camera.focal_point)
    assert np.linalg.norm(moved) < np.linalg.norm(direction)
    np.testing.assert_allclose(moved / np.linalg.norm(moved),
                               direction / np.linalg.norm(direction))
    scene.camera.position = (40.0, 30.0, 20.0)  # the user orbits or zooms
    pose = scene.camera.pose()
    scene.aspect = 0.45
    assert scene.camera.pose() == pose


def _every_kind(tmp_path):
    """A scene with every kind of object and every property away from its default."""
    from splineviz.plugins import ensure_loaded

    ensure_loaded()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    sv.write_volume(tmp_path / "a" / "ct.npy", ml_volume(11))
    sv.write_volume(tmp_path / "b" / "ct.npy", ml_volume(9).data[::-1].copy())
    rng = np.random.default_rng(3)
    p = rng.normal(size=(400, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    sv.write_mesh(tmp_path / "cloud.ply", (p, np.zeros((0, 3), dtype=np.int64)))

    scene = Scene()
    va = scene.add_volume(sv.read_volume(tmp_path / "a" / "ct.npy"), "ct.npy",
                          path=tmp_path / "a" / "ct.npy", isosurface=False)
    vb = scene.add_volume(sv.read_volume(tmp_path / "b" / "ct.npy"), "ct.npy",
                          path=tmp_path / "b" / "ct.npy", isosurface=False)
    mem = scene.add_volume(ml_volume(7), "in memory", isosurface=False)  # no file: written
    va.update(sigma=1.25, show_outline=False)
    vb.visible = False
    skin = scene.add_isosurface(va, isovalue=0.4, model="to-quadratic", k=3,
                                color=(0.1, 0.2, 0.3), opacity=0.6, material="shiny",
                                name="skin")
    # colour by another volume (schema 4) and by curvature with a manual range
    skin.update(color_by="volume", color_volume_id=vb.id, color_map="coolwarm",
                color_range="symmetric")
    scene.add_isosurface(vb, isovalue=0.55, model="tricubic-bspline", material="metal",
                         visible=False, color_by="distance", color_isosurface_id=skin.id)
    scene.add_isosurface(mem, isovalue=0.5, model="super-quadratic", material="matte",
                         color_by="mean", color_map="magma", color_range="manual",
                         color_min=-3.0, color_max=2.5)
    pts = scene.add_points(sv.read_points(tmp_path / "cloud.ply"), "cloud",
                           path=tmp_path / "cloud.ply", color=(0.9, 0.1, 0.1), point_size=7.0,
                           opacity=0.5)
    tri = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
           np.array([[0, 1, 2], [0, 1, 3]]))
    scene.add_mesh(*tri, name="remeshed", normals=np.tile([0, 0, 1.0], (4, 1)),
                   points_id=pts.id, rho=0.5, sharp_creases=False, color=(0.2, 0.9, 0.2),
                   opacity=0.7, show_edges=False, visible=False)
    scene.add_clip_plane((0.1, 0.2, 0.3), (0, 0, -1), volume=va, show_widget=False,
                         name="cut a")
    scene.add_clip_plane((0, 0, 0), (1, 1, 0), enabled=False)
    scene.camera.update(position=(3.0, -4.0, 2.0), focal_point=(0.1, 0.0, -0.1),
                        view_up=(0.0, 0.0, 1.0), view_angle=25.0)
    scene.view.update(background=(0.3, 0.3, 0.3), show_axes=False, show_scale=False)
    return scene


def _state(scene):
    out = {}
    for n in scene:
        state = dict(n.state(), name=n.name, type=type(n).__name__)
        state.pop("path", None)  # absolute paths: compared separately
        if isinstance(n, VolumeNode):
            state["data"] = n.data.data.tobytes()
        elif isinstance(n, PointsNode):
            state["data"] = np.asarray(n.data.points).round(6).tobytes()
        elif isinstance(n, MeshNode):
            state["data"] = (n.vertices.tobytes(), n.faces.tobytes(),
                             np.asarray(n.normals, np.float32).tobytes())
        out[n.id] = state
    out["camera"] = scene.camera.pose()
    out["view"] = scene.view.state()
    return out


def test_session_round_trip_of_every_property_and_the_picture(tmp_path):
    from splineviz.render.scene_view import render_scene

    scene = _every_kind(tmp_path)
    path = save_scene(scene, tmp_path / "all")  # .svs appended
    assert path.name == "all.svs" and (tmp_path / "all_data").is_dir()
    # data without a file was written beside the session, nodes now point at it
    assert scene.get("volume3").path.endswith("volume3.vti")
    assert scene.get("mesh1").path.endswith("mesh1.ply")
    back = load_scene(path)
    assert _state(back) == _state(scene)
    # the two ct.npy are told apart by their folders, never by name
    assert back.get("volume1").path != back.get("volume2").path
    assert back.get("isosurface2").volume_id == "volume2"
    assert not back.modified
    # saving the loaded scene again writes the same document
    assert to_session(back).to_document(tmp_path) == to_session(scene).to_document(tmp_path)
    for s in (scene, back):  # the plugin model renders on the NumPy path: hide it
        s.get("isosurface2").visible = False
    a = render_scene(scene, (96, 72))
    b = render_scene(back, (96, 72))
    assert np.array_equal(a, b)
    assert np.any(a != a[0, 0]), "the picture shows something"


def test_schema_2_sessions_still_load(tmp_path):
    import json

    np.save(tmp_path / "v.npy", ml_volume(9).data)
    doc = {"format": "splineviz-session", "schema_version": 2, "objects": [
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
        {"id": "i", "type": "Isosurface", "inputs": ["v"],
         "properties": {"isovalue": 0.5, "model": "cubic-c1"}},
        {"id": "c", "type": "ClipPlane", "inputs": ["i"],
         "properties": {"normal": [0, 0, 1]}}]}
    (tmp_path / "old.svs").write_text(json.dumps(doc))
    scene = load_scene(tmp_path / "old.svs")
    plane = scene.get("c")
    assert isinstance(plane, ClipPlaneNode) and plane.volume_id == "v"
    assert scene.get("i").model == "cubic-c1"
    assert scene.get("i").color_by == "none"  # schema 4's colour by: off in old sessions


def test_colour_by_a_non_volume_is_refused(tmp_path):
    import json

    from splineviz.io.errors import SessionError

    np.save(tmp_path / "v.npy", ml_volume(9).data)
    doc = {"format": "splineviz-session", "schema_version": 4, "objects": [
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
        {"id": "i", "type": "Isosurface", "inputs": ["v"],
         "properties": {"isovalue": 0.5, "color_by": "volume", "color_volume": "i"}}]}
    (tmp_path / "s.svs").write_text(json.dumps(doc))
    with pytest.raises(SessionError, match="not a volume"):
        load_scene(tmp_path / "s.svs")
    doc["objects"][1]["properties"] = {"isovalue": 0.5, "color_map": "jet"}
    (tmp_path / "s.svs").write_text(json.dumps(doc))
    with pytest.raises(SessionError):
        load_scene(tmp_path / "s.svs")


def test_unknown_model_in_a_session_is_an_error_not_trilinear(tmp_path):
    import json

    from splineviz.core.errors import SplinevizError

    np.save(tmp_path / "v.npy", ml_volume(9).data)
    doc = {"format": "splineviz-session", "schema_version": 3, "objects": [
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
        {"id": "i", "type": "Isosurface", "inputs": ["v"],
         "properties": {"isovalue": 0.5, "model": "no-such-model"}}]}
    (tmp_path / "s.svs").write_text(json.dumps(doc))
    with pytest.raises(SplinevizError, match="no-such-model"):
        load_scene(tmp_path / "s.svs")
