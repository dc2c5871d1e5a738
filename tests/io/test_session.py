"""Session documents: round trip, migration, relative and re-pointed paths."""

import json
import shutil
from pathlib import Path

import pytest

import splineviz as sv
from splineviz.io import errors
from splineviz.io.session import SCHEMA_VERSION, load_session, migrate, save_session

HEAD = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "volumes"
BUNNY = HEAD.parent / "points" / "bunny_res2.ply"


def scene_doc(vol="data/head.mhd", pts="data/bunny.ply"):
    """Two isosurfaces, a clip plane and a point cloud (the issue's round-trip scene)."""
    return {
        "format": "splineviz-session", "schema_version": SCHEMA_VERSION, "app_version": "0.1.0",
        "objects": [
            {"id": "vol1", "type": "VolumeFile", "name": "head", "properties": {"path": vol}},
            {"id": "iso1", "type": "Isosurface", "inputs": ["vol1"],
             "properties": {"isovalue": 40.0, "model": "cubic-c1", "color": [1.0, 0.5, 0.0]}},
            {"id": "iso2", "type": "Isosurface", "inputs": ["vol1"],
             "properties": {"isovalue": 90.0, "opacity": 0.4}},
            {"id": "pc1", "type": "PointsFile", "properties": {"path": pts, "point_size": 2.0}},
            {"id": "clip1", "type": "ClipPlane", "inputs": ["iso1", "iso2", "pc1"],
             "properties": {"origin": [90.0, 120.0, 80.0], "normal": [0.0, 1.0, 0.0]}},
        ],
        "views": [{"id": "view1", "type": "RenderView",
                   "camera": {"position": [300.0, -200.0, 150.0],
                              "focal_point": [94.0, 122.0, 82.0], "view_up": [0.0, 0.0, 1.0]},
                   "background": [1.0, 1.0, 1.0],
                   "lights": [{"type": "scene", "position": [0.0, 0.0, 500.0],
                               "intensity": 0.8}]}],
    }


@pytest.fixture
def project(tmp_path):
    """A session folder with its data beside it."""
    (tmp_path / "data").mkdir()
    for suffix in (".mhd", ".raw"):
        shutil.copy(HEAD / f"HeadMRVolume{suffix}", tmp_path / "data" / f"HeadMRVolume{suffix}")
    (tmp_path / "data" / "head.mhd").write_text(
        (HEAD / "HeadMRVolume.mhd").read_text())
    shutil.copy(BUNNY, tmp_path / "data" / "bunny.ply")
    return tmp_path


def write(path, doc):
    path.write_text(json.dumps(doc, indent=1))
    return path


def test_round_trip_is_stable(project):
    src = write(project / "scene.svs", scene_doc())
    s = load_session(src)
    assert Path(s.object("vol1").properties.path) == project / "data" / "head.mhd"
    save_session(s, project / "a.svs")
    first = (project / "a.svs").read_text()
    assert json.loads(first) == scene_doc()  # nothing lost, nothing default added
    save_session(load_session(project / "a.svs"), project / "b.svs")
    assert (project / "b.svs").read_text() == first


def test_defaults_are_omitted_and_types_always_written(project):
    doc = scene_doc()
    doc["objects"][1]["properties"]["opacity"] = 1.0  # the default
    s = load_session(write(project / "s.svs", doc))
    out = s.to_document(base_dir=project)
    assert "opacity" not in out["objects"][1]["properties"]
    assert [o["type"] for o in out["objects"]] == ["VolumeFile", "Isosurface", "Isosurface",
                                                   "PointsFile", "ClipPlane"]


def test_paths_stay_relative_when_saved_elsewhere(project):
    s = load_session(write(project / "scene.svs", scene_doc()))
    (project / "sub").mkdir()
    save_session(s, project / "sub" / "moved.svs")
    doc = json.loads((project / "sub" / "moved.svs").read_text())
    assert doc["objects"][0]["properties"]["path"] == "../data/head.mhd"
    # data outside the session's folder is read only when the caller allows it
    with pytest.raises(errors.SessionOutsideFolderError, match="head.mhd"):
        load_session(project / "sub" / "moved.svs")
    again = load_session(project / "sub" / "moved.svs", allow_outside=True)
    assert Path(again.object("vol1").properties.path).resolve() == \
        (project / "data" / "head.mhd").resolve()


def test_missing_file_is_repointed(project):
    doc = scene_doc(vol="data/gone.mhd")
    asked = []

    def repoint(obj_id, path):
        asked.append((obj_id, path.name))
        return project / "data" / "head.mhd"

    s = load_session(write(project / "s.svs", doc), repoint=repoint)
    assert asked == [("vol1", "gone.mhd")]
    assert sv.read_volume(s.object("vol1").properties.path).shape == (48, 62, 42)
    with pytest.raises(errors.SessionPathError, match="gone.mhd.*does not exist"):
        load_session(project / "s.svs")
    with pytest.raises(errors.SessionPathError, match="not re-pointed"):
        load_session(project / "s.svs", repoint=lambda i, p: None)
    assert load_session(project / "s.svs", check_data=False).missing_files()[0][0] == "vol1"


def test_old_schema_is_migrated(project):
    v1 = {"format": "splineviz-session", "schema_version": 1,
          "objects": [{"id": "vol1", "type": "VolumeFile", "properties": {
                           "path": "data/head.mhd"}},
                      {"id": "iso1", "type": "Isosurface", "input": "vol1",
                       "properties": {"iso": 40, "colour": "#ff8000"}}],
          "view": {"camera": {"position": [1, 2, 3]}, "background": "#ffffff"}}
    before = json.dumps(v1)
    s = load_session(write(project / "old.svs", v1))
    assert json.dumps(v1) == before  # migrate() never edits its input
    iso = s.object("iso1")
    assert iso.inputs == ["vol1"] and iso.properties.isovalue == 40
    assert iso.properties.color == pytest.approx((1.0, 128 / 255, 0.0), abs=1e-6)
    assert s.views[0].background == (1.0, 1.0, 1.0)
    assert s.views[0].camera.position == (1, 2, 3)
    assert migrate(v1)["schema_version"] == SCHEMA_VERSION


def test_sources_come_from_plugins(project):
    doc = {"format": "splineviz-session", "schema_version": 2,
           "objects": [{"id": "ml", "type": "Source",
                        "properties": {"source": "marschner-lobb", "shape": [20, 20, 20]}},
                       {"id": "iso", "type": "Isosurface", "inputs": ["ml"],
                        "properties": {"isovalue": 0.5}}]}
    s = load_session(write(project / "ml.svs", doc))
    assert s.object("ml").properties.shape == (20, 20, 20)


def test_saving_leaves_no_partial_file_on_error(project):
    s = load_session(write(project / "scene.svs", scene_doc()))
    save_session(s, project / "out.svs")
    before = (project / "out.svs").read_bytes()
    s.object("iso1").properties.__dict__["opacity"] = float("nan")  # bypass validation
    with pytest.raises((errors.SessionError, ValueError)):
        save_session(s, project / "out.svs")
    assert (project / "out.svs").read_bytes() == before
    assert sorted(p.name for p in project.iterdir() if p.name.startswith(".")) == []


def test_absolute_path_inside_the_folder_is_stored_relative(project):
    doc = scene_doc(vol=str(project / "data" / "head.mhd"))
    s = load_session(write(project / "abs.svs", doc))
    save_session(s, project / "rel.svs")
    saved = json.loads((project / "rel.svs").read_text())
    assert saved["objects"][0]["properties"]["path"] == "data/head.mhd"


def test_scene_access_for_renderers(project):
    s = load_session(write(project / "scene.svs", scene_doc()))
    assert [o.id for o in s.visible()] == ["iso1", "iso2", "pc1"]
    assert s.clip_planes_for("iso2") == [((90.0, 120.0, 80.0), (0.0, 1.0, 0.0))]
    assert s.clip_planes_for("vol1") == []
    assert s.load_volume("iso1").spacing == (4.0, 4.0, 4.0)
    cam = s.views[0].camera.to_camera()
    assert cam.position == (300.0, -200.0, 150.0) and cam.view_up == (0.0, 0.0, 1.0)


def test_building_a_session_in_code_and_saving_it(project):
    from splineviz.io.session import Session

    s = Session()
    vol = s.add("VolumeFile", {"path": str(project / "data" / "head.mhd")}, name="head")
    iso = s.add("Isosurface", {"isovalue": 50.0, "model": "cubic-c1"}, inputs=[vol.id])
    s.add("ClipPlane", {"normal": [0, 0, 1]}, inputs=[iso.id])
    assert [o.id for o in s.objects] == ["volumefile1", "isosurface1", "clipplane1"]
    with pytest.raises(errors.SessionError, match="cannot take"):
        s.add("Isosurface", {"isovalue": 1.0}, inputs=["clipplane1"])
    with pytest.raises(errors.SessionError, match="isovalue"):
        s.add("Isosurface", {"isovalue": float("inf")}, inputs=[vol.id])
    with pytest.raises(errors.SessionError, match="input of"):
        s.remove(vol.id)
    save_session(s, project / "built.svs")
    again = load_session(project / "built.svs")
    assert again.object("isosurface1").properties.model == "cubic-c1"
    assert again.object("volumefile1").name == "head"
    s.remove("clipplane1")
    assert [o.id for o in s.objects] == ["volumefile1", "isosurface1"]


def test_open_path_dispatches_on_content(project):
    from splineviz.io.opening import open_path

    write(project / "scene.svs", scene_doc())
    assert open_path(project / "scene.svs").kind == "session"
    assert open_path(project / "data" / "head.mhd").kind == "volume"
    assert open_path(project / "data" / "bunny.ply").kind == "points"
    (project / "junk.bin2").write_bytes(b"\x00\x01junk")
    with pytest.raises(errors.UnknownFormatError, match="svs sessions"):
        open_path(project / "junk.bin2")


def test_relative_paths_set_in_memory_are_relative_to_the_working_directory(project,
                                                                          monkeypatch):
    from splineviz.io.session import Session

    monkeypatch.chdir(project / "data")
    s = Session()
    s.add("VolumeFile", {"path": "head.mhd"})
    (project / "sessions").mkdir()
    save_session(s, project / "sessions" / "s.svs")
    doc = json.loads((project / "sessions" / "s.svs").read_text())
    assert doc["objects"][0]["properties"]["path"] == "../data/head.mhd"
    monkeypatch.chdir(project)
    again = load_session(project / "sessions" / "s.svs", allow_outside=True)
    assert Path(again.object("volumefile1").properties.path) == project / "data" / "head.mhd"
