"""Animations: interpolation, presets, applying frames to a scene, sessions with one."""

import json

import numpy as np
import pytest

import splineviz as sv
from splineviz.core import testfunctions as tf
from splineviz.io.errors import SessionError
from splineviz.model import Scene
from splineviz.model.animation import (
    Animation,
    AnimationError,
    Keyframe,
    Track,
    clip_sweep,
    isovalue_sweep,
    orbit,
    slerp_unit,
)
from splineviz.model.session import load_scene, save_scene


def _scene():
    scene = Scene()
    vol = scene.add_volume(sv.Volume.from_function(tf.ml, (9, 9, 9), tf.ml.domain),
                           name="ML", isovalue=0.5)
    scene.frame(view="isometric")
    return scene, vol


def test_orbit_stays_on_its_circle_at_any_elevation():
    scene = Scene()
    scene.camera.update(position=(1.0, -3.0, 2.5), focal_point=(1.0, 0.0, 0.5),
                        view_up=(0.0, 0.0, 1.0))
    anim = orbit(scene, degrees=360, frames=10)
    focal = np.array([1.0, 0.0, 0.5])
    radii, heights, angles = [], [], []
    for k in range(anim.frames):
        anim.apply(scene, k)
        p = np.array(scene.camera.position) - focal
        radii.append(np.hypot(p[0], p[1]))
        heights.append(p[2])
        angles.append(np.degrees(np.arctan2(p[1], p[0])))
    assert np.allclose(radii, 3.0) and np.allclose(heights, 2.0)
    steps = np.diff(np.unwrap(np.radians(angles)))
    assert np.allclose(np.degrees(steps), 36.0)  # one speed, a loop without a repeat


def test_open_orbit_ends_at_its_angle():
    scene = Scene()
    scene.camera.update(position=(0.0, -2.0, 0.0), focal_point=(0.0, 0.0, 0.0),
                        view_up=(0.0, 0.0, 1.0))
    anim = orbit(scene, degrees=90, frames=5)
    anim.apply(scene, 4)
    assert np.allclose(scene.camera.position, (2.0, 0.0, 0.0), atol=1e-12)


def test_scalar_tracks_linear_and_smooth():
    lin = Track(target="iso", property="isovalue",
                keys=[Keyframe(frame=0, value=(1.0,)), Keyframe(frame=10, value=(3.0,))])
    assert lin.value_at(5) == (2.0,) and lin.value_at(-1) == (1.0,) and lin.value_at(20) == (3.0,)
    smooth = lin.model_copy(update={"interpolation": "smooth"})
    assert smooth.value_at(5) == (2.0,)
    assert smooth.value_at(1)[0] < lin.value_at(1)[0]  # eases in


def test_normal_turns_on_the_sphere():
    v = slerp_unit((1.0, 0.0, 0.0), (0.0, 2.0, 0.0), 0.5)
    assert np.allclose(v, (np.sqrt(0.5), np.sqrt(0.5), 0.0))
    half = slerp_unit((0.0, 0.0, 1.0), (0.0, 0.0, -1.0), 0.5)
    assert np.isclose(np.linalg.norm(half), 1.0) and abs(half[2]) < 1e-12


def test_bad_tracks_are_refused_in_one_sentence():
    with pytest.raises(AnimationError, match="increasing frame order"):
        Animation.make(tracks=[{"target": "camera", "property": "camera", "keys": [
            {"frame": 3, "value": [0] * 10}, {"frame": 1, "value": [0] * 10}]}])
    with pytest.raises(AnimationError, match="unknown animated property"):
        Animation.make(tracks=[{"target": "x", "property": "spin", "keys": [
            {"frame": 0, "value": [0]}]}])
    with pytest.raises(AnimationError, match="10 number"):
        Animation.make(tracks=[{"target": "camera", "property": "camera", "keys": [
            {"frame": 0, "value": [0, 1]}]}])
    scene, _ = _scene()
    anim = Animation.make(tracks=[{"target": "nothing", "property": "isovalue",
                                   "keys": [{"frame": 0, "value": [1]}]}])
    with pytest.raises(AnimationError, match="not in the scene"):
        anim.apply(scene, 0)


def test_presets_apply_to_the_scene_and_combine():
    scene, vol = _scene()
    iso = scene.isosurfaces[0]
    sweep = isovalue_sweep(scene, 0.2, 0.8, frames=7)
    sweep.apply(scene, 3)
    assert iso.isovalue == pytest.approx(0.5)
    sweep.apply(scene, 6)
    assert iso.isovalue == pytest.approx(0.8)
    clip = clip_sweep(scene, "z", frames=5)
    plane = scene.clip_planes[0]
    (x0, x1), (y0, y1), (z0, z1) = vol.bounds
    clip.apply(scene, 0)
    assert plane.origin[2] == pytest.approx(z0)
    clip.apply(scene, 4)
    assert plane.origin[2] == pytest.approx(z1)
    both = orbit(scene, 180, frames=9) + sweep
    assert both.frames == 9 and {t.property for t in both.tracks} == {"camera", "isovalue"}
    before = scene.camera.position
    both.apply(scene, 8)
    assert iso.isovalue == pytest.approx(0.8) and scene.camera.position != before


def test_add_key_from_the_view():
    scene, _ = _scene()
    anim = Animation(frames=20)
    anim = anim.add_key(scene, 0)
    scene.camera.position = tuple(np.array(scene.camera.position) * 2.0)
    anim = anim.add_key(scene, 19)
    far = scene.camera.position
    anim.apply(scene, 0)
    assert scene.camera.position != far
    anim.apply(scene, 19)
    assert np.allclose(scene.camera.position, far)
    iso = scene.isosurfaces[0]
    anim = anim.add_key(scene, 5, iso.id, "isovalue")
    assert anim.track(iso.id, "isovalue").keys[0].value == (iso.isovalue,)


def test_session_round_trip_with_an_animation(tmp_path):
    scene, _ = _scene()
    anim = orbit(scene, 360, frames=24, fps=12) + clip_sweep(scene, "x", frames=24)
    scene.animation = anim
    path = save_scene(scene, tmp_path / "anim.svs")
    doc = json.loads(path.read_text())
    assert doc["animation"]["frames"] == 24
    loaded = load_scene(path)
    assert loaded.animation == anim
    loaded.animation.apply(loaded, 10)
    anim.apply(scene, 10)
    assert loaded.camera.pose() == scene.camera.pose()
    assert loaded.clip_planes[0].origin == scene.clip_planes[0].origin
    again = save_scene(loaded, tmp_path / "again.svs")
    assert json.loads(again.read_text())["animation"] == doc["animation"]


def test_session_animation_naming_a_missing_object_changes_nothing(tmp_path):
    scene, _ = _scene()
    scene.animation = isovalue_sweep(scene, 0.1, 0.9, frames=4)
    path = save_scene(scene, tmp_path / "a.svs")
    doc = json.loads(path.read_text())
    doc["animation"]["tracks"][0]["target"] = "ghost"
    path.write_text(json.dumps(doc))
    target, _ = _scene()
    with pytest.raises(SessionError, match="ghost"):
        load_scene(path, scene=target)
    assert len(target.isosurfaces) == 1


def test_opacity_colour_range_and_normal_tracks():
    scene, vol = _scene()
    iso = scene.isosurfaces[0]
    plane = scene.add_clip_plane(normal=(1.0, 0.0, 0.0))
    anim = Animation.make(frames=3, tracks=[
        {"target": iso.id, "property": "opacity",
         "keys": [{"frame": 0, "value": [1.0]}, {"frame": 2, "value": [0.2]}]},
        {"target": iso.id, "property": "color_range",
         "keys": [{"frame": 0, "value": [0.0, 1.0]}, {"frame": 2, "value": [0.4, 0.6]}]},
        {"target": plane.id, "property": "normal",
         "keys": [{"frame": 0, "value": [1, 0, 0]}, {"frame": 2, "value": [0, 1, 0]}]}])
    saved = anim.state_of(scene)
    anim.apply(scene, 1)
    assert iso.opacity == pytest.approx(0.6)
    assert (iso.color_range, iso.color_min, iso.color_max) == ("manual", pytest.approx(0.2),
                                                               pytest.approx(0.8))
    assert np.allclose(plane.normal, (np.sqrt(0.5), np.sqrt(0.5), 0.0))
    anim.restore(scene, saved)
    assert iso.opacity == 1.0 and iso.color_range == "auto" and plane.normal == (1.0, 0.0, 0.0)
    with pytest.raises(AnimationError, match="cannot animate"):
        Animation.make(tracks=[{"target": plane.id, "property": "isovalue",
                                "keys": [{"frame": 0, "value": [1]}]}]).apply(scene, 0)


def test_removing_an_object_removes_its_tracks():
    scene, vol = _scene()
    iso = scene.isosurfaces[0]
    scene.animation = orbit(scene, 90, frames=4) + isovalue_sweep(scene, 0.2, 0.8, frames=4)
    scene.remove(iso)
    assert [t.target for t in scene.animation.tracks] == ["camera"]
    scene.clear()
    assert scene.animation is None
