"""The split view in the scene model (no Qt): which objects each side shows, the comparison
copy, and sessions that keep the split as two views."""

import json

import pytest

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.io.session import load_session
from splineviz.model import ModelError, Scene
from splineviz.model.session import load_scene, save_scene, to_session


def ml_scene(n=13, source=None) -> Scene:
    scene = Scene()
    scene.add_volume(sv.Volume.from_function(ml, (n, n, n), ml.domain), name="ML",
                     source=source)
    return scene


def test_compare_copies_the_isosurface_into_the_right_view():
    scene = ml_scene()
    iso = scene.isosurfaces[0]
    iso.update(color=(0.2, 0.4, 0.6), material="shiny")
    copy = scene.compare(iso, distance=True)
    assert scene.view.split
    assert (iso.shown_in, copy.shown_in) == ("left", "right")
    assert (iso.model, copy.model) == ("cubic-c1", "trilinear")
    assert copy.isovalue == iso.isovalue and copy.volume_id == iso.volume_id
    assert (copy.color, copy.material) == (iso.color, iso.material)
    # the left surface coloured by its distance to the right one
    assert (iso.color_by, iso.color_isosurface_id) == ("distance", copy.id)
    assert copy.color_by == "none"
    again = scene.compare(copy, isovalue=0.3)  # trilinear compares with the default model
    assert (again.model, again.isovalue) == ("cubic-c1", 0.3)
    with pytest.raises(ModelError, match="shown_in"):
        iso.shown_in = "middle"


def test_each_side_shows_its_own_objects_and_sections_follow_their_surfaces():
    scene = ml_scene()
    left = scene.isosurfaces[0]
    right = scene.compare(left)
    both = scene.add_isosurface(scene.volumes[0], isovalue=0.4)
    plane = scene.add_clip_plane()
    cut = scene.add_section(right, plane=plane)
    meet = scene.add_section(left, other=right)
    shows = {side: {n.id for n in scene if scene.shows(n, side)}
             for side in ("left", "right")}
    assert left.id in shows["left"] and left.id not in shows["right"]
    assert right.id in shows["right"] and right.id not in shows["left"]
    assert both.id in shows["left"] & shows["right"]
    assert cut.id in shows["right"] and cut.id not in shows["left"]
    assert meet.id in shows["left"] & shows["right"]  # lies on both surfaces
    scene.view.split = False  # one view: everything, the sides are kept for next time
    assert all(scene.shows(n, "left") and scene.shows(n, None) for n in scene)
    assert (left.shown_in, right.shown_in) == ("left", "right")


def test_session_keeps_the_split_as_two_views(tmp_path):
    scene = ml_scene(source="marschner-lobb")
    scene.volumes[0].data = sv.Volume.from_function(ml, (64, 64, 64), ml.domain)
    left = scene.isosurfaces[0]
    right = scene.compare(left, model="trilinear", isovalue=0.3)
    left.k = 3
    scene.frame(view="isometric")
    path = save_scene(scene, tmp_path / "split.svs")
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 4
    v1, v2 = doc["views"]
    assert v1["hidden"] == [right.id] and v2["hidden"] == [left.id]
    assert v2["layout"] == {"col": 1} and v2["camera"] == v1["camera"]

    loaded = load_scene(path)
    assert loaded.view.split
    got = {n.id: (n.shown_in, n.model, n.k, n.isovalue) for n in loaded.isosurfaces}
    assert got == {left.id: ("left", left.model, 3, left.isovalue),
                   right.id: ("right", "trilinear", 2, 0.3)}
    for key in ("position", "focal_point", "view_up"):
        assert getattr(loaded.camera, key) == pytest.approx(getattr(scene.camera, key))

    # loading a one-view session over a split scene ends the split
    scene.view.split = False
    single = to_session(scene)
    assert len(single.views) == 1 and single.views[0].hidden == []
    save_scene(scene, tmp_path / "single.svs")
    load_scene(tmp_path / "single.svs", scene=loaded)
    assert not loaded.view.split


def test_a_session_with_views_in_either_order_restores_the_sides(tmp_path):
    scene = ml_scene(source="marschner-lobb")
    scene.volumes[0].data = sv.Volume.from_function(ml, (64, 64, 64), ml.domain)
    left = scene.isosurfaces[0]
    right = scene.compare(left)
    path = save_scene(scene, tmp_path / "s.svs")
    doc = json.loads(path.read_text())
    doc["views"].reverse()  # the left view is the one in column 0, wherever it is listed
    path.write_text(json.dumps(doc))
    loaded = load_scene(path)
    assert {n.id: n.shown_in for n in loaded.isosurfaces} == {left.id: "left",
                                                               right.id: "right"}
    # hidden in both views: shown in both (its own visibility decides)
    doc["views"][0]["hidden"] = doc["views"][1]["hidden"] = [left.id]
    path.write_text(json.dumps(doc))
    assert load_session(path).views[0].hidden == [left.id]
    assert load_scene(path).get(left.id).shown_in == "both"
