"""Undoable scene edits (splineviz.model.commands) without Qt: every edit a user makes,
undone and redone, compared through the scene model (ids, order, every saved property,
the data objects themselves and the selection)."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.model import MeshNode, ModelError, Scene
from splineviz.model.commands import ChangeObjects, SetProperties, remove_objects


def sphere(n=11):
    x = np.linspace(-1, 1, n)
    return sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2), spacing=2 / (n - 1),
                     origin=(-1, -1, -1))


def state(scene: Scene) -> list:
    """What the scene holds, node by node: id, kind, saved properties (references and
    per-view fields included), the identity of its data, and the selection."""
    rows = []
    for n in scene:
        data = [id(getattr(n, k)) for k in ("data", "vertices", "faces")
                if getattr(n, k, None) is not None]
        rows.append((n.id, n.kind, n.model_dump(mode="json", by_alias=True), data))
    rows.append(("selected", None if scene.selected is None else scene.selected.id))
    return rows


@pytest.fixture
def scene():
    s = Scene()
    vol = s.add_volume(sphere(), "sphere", isovalue=0.5, model="trilinear")
    iso = s.isosurfaces[0]
    s.add_isosurface(vol, isovalue=0.8, name="outer")
    plane = s.add_clip_plane(volume=vol)
    s.add_section(iso, plane=plane)
    pts = s.add_points(sv.PointCloud(np.random.default_rng(0).normal(size=(50, 3))), "cloud")
    s.add_mesh(np.eye(3), [[0, 1, 2]], "mesh", points_id=pts.id)
    s.select(iso)
    return s


def round_trip(scene, command):
    """Do, undo, redo, undo: the states after undo equal the state before, after redo the
    state after do; returns the state after do."""
    before = state(scene)
    command.do()
    after = state(scene)
    assert after != before, "the command changed nothing"
    command.undo()
    assert state(scene) == before
    command.do()
    assert state(scene) == after
    command.undo()
    assert state(scene) == before
    return after


@pytest.mark.parametrize("values", [
    {"isovalue": 0.3}, {"model": "cubic-c1"}, {"color": (0.2, 0.4, 0.6)},
    {"opacity": 0.4}, {"material": "shiny"},
    {"color_by": "mean", "color_map": "plasma", "color_range": "manual", "color_min": -2.0,
     "color_max": 3.0},
    {"color_by": "distance", "color_isosurface_id": "isosurface2"},
    {"visible": False}, {"shown_in": "left"},
])
def test_isosurface_properties_round_trip(scene, values):
    iso = scene.get("isosurface1")
    round_trip(scene, SetProperties(scene, iso, values))


def test_smoothing_plane_moves_and_point_size_round_trip(scene):
    round_trip(scene, SetProperties(scene, scene.get("volume1"), {"sigma": 1.5}))
    plane = scene.clip_planes[0]
    round_trip(scene, SetProperties(scene, plane, {"origin": (0.1, 0.2, 0.3),
                                                   "normal": (0.0, 0.0, 1.0)}))
    round_trip(scene, SetProperties(scene, plane, {"enabled": False, "show_widget": False}))
    round_trip(scene, SetProperties(scene, scene.get("points1"), {"point_size": 7.0}))


def test_a_bad_value_changes_nothing_and_an_unknown_property_is_refused(scene):
    iso = scene.get("isosurface1")
    before = state(scene)
    with pytest.raises(ModelError):
        SetProperties(scene, iso, {"opacity": 2.0}).do()
    assert state(scene) == before
    with pytest.raises(ModelError, match="no property"):
        SetProperties(scene, iso, {"colour": (1, 0, 0)})


def test_merged_drag_keeps_the_first_old_and_the_last_new_value(scene):
    iso = scene.get("isosurface1")
    first = SetProperties(scene, iso, {"isovalue": 0.55})
    first.do()
    for v in (0.6, 0.65, 0.7):
        step = SetProperties(scene, iso, {"isovalue": v})
        step.do()
        assert step.merge_key == first.merge_key and first.merge(step)
    assert iso.isovalue == 0.7 and not first.obsolete
    first.undo()
    assert iso.isovalue == 0.5
    back = SetProperties(scene, iso, {"isovalue": 0.5})
    assert first.merge(back) and first.obsolete  # a drag back to where it started
    assert not first.merge(SetProperties(scene, iso, {"opacity": 0.5}))


@pytest.mark.parametrize("make", [
    lambda s: s.add_isosurface(s.get("volume1"), isovalue=0.2),
    lambda s: s.add_clip_plane(normal=(0, 1, 0)),
    lambda s: s.add_section(s.get("isosurface2"), plane=s.get("clipplane1")),
    lambda s: s.add_volume(sphere(7), "small"),             # a file opened beside the others
    lambda s: s.add_mesh(np.eye(3), [[0, 1, 2]], "mesh of cloud", points_id="points1",
                         rho=0.3),                            # a remesh result
])
def test_adding_objects_round_trips_with_the_same_nodes(scene, make):
    command = ChangeObjects(scene, "Add", lambda: make(scene))
    after = round_trip(scene, command)
    command.do()
    assert state(scene) == after and command.result.id in scene
    assert scene.get(command.result.id) is command.result  # the same node, not a copy


@pytest.mark.parametrize("node_id,gone", [
    ("volume1", {"volume1", "isosurface1", "isosurface2", "clipplane1", "section1"}),
    ("isosurface1", {"isosurface1", "section1"}),
    ("clipplane1", {"clipplane1", "section1"}),
    ("points1", {"points1"}),
    ("mesh1", {"mesh1"}),
])
def test_removing_restores_ids_data_dependants_and_order(scene, node_id, gone):
    ids = [n.id for n in scene]
    nodes = {n.id: n for n in scene}
    command = remove_objects(scene, scene.get(node_id))
    round_trip(scene, command)
    command.do()
    assert {n.id for n in scene} == set(ids) - gone
    command.undo()
    assert [n.id for n in scene] == ids
    assert all(scene.get(i) is nodes[i] for i in ids)  # with their data, not copies


def test_removal_side_effects_on_kept_objects_are_undone(scene):
    outer = scene.get("isosurface2")
    outer.update(color_by="distance", color_isosurface_id="isosurface1")
    mesh = scene.get("mesh1")
    round_trip(scene, remove_objects(scene, scene.get("isosurface1")))
    command = remove_objects(scene, scene.get("points1"))
    command.do()
    assert mesh.points_id is None
    command.undo()
    assert mesh.points_id == "points1"


def test_an_edit_of_a_node_no_longer_in_the_scene_is_refused(scene):
    iso = scene.get("isosurface2")
    command = SetProperties(scene, iso, {"isovalue": 0.7})
    command.do()
    scene.remove(iso)
    with pytest.raises(ModelError, match="no longer in the scene"):
        command.undo()
    with pytest.raises(ModelError):
        remove_objects(scene, iso)


def test_mesh_node_comes_back_with_its_arrays(scene):
    mesh = scene.get("mesh1")
    v = mesh.vertices
    command = remove_objects(scene, mesh)
    command.do()
    command.undo()
    assert isinstance(scene.get("mesh1"), MeshNode) and scene.get("mesh1").vertices is v
