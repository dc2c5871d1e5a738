"""Time playback in animations (issues 27 and 28): a track of the scene's current time, the
``time_playback`` preset, ``splineviz movie --all-times`` and ``sv.movie(all_times=True)``;
each frame is the still ``render_scene`` makes of the scene at that step."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import splineviz as sv
from splineviz.cli import main
from splineviz.io.time_series import open_time_series
from splineviz.model.animation import (
    TIME_TARGET,
    AnimationError,
    orbit,
    time_playback,
)
from splineviz.model.scene import Scene
from splineviz.model.session import load_scene, save_scene
from splineviz.render.scene_view import render_scene

nib = pytest.importorskip("nibabel")

SIZE = (64, 48)


def _ball_steps(n=4, shape=(20, 18, 16)):
    """(x, y, z, t) uint8: a ball growing step by step."""
    x, y, z = np.meshgrid(*(np.linspace(-1, 1, k) for k in shape), indexing="ij")
    r = np.sqrt(x**2 + y**2 + z**2)
    return np.stack([((1.0 + 0.25 * t) * (1 - r) * 120 + 40).clip(0, 255).astype(np.uint8)
                     for t in range(n)], -1)


@pytest.fixture
def nifti4d(tmp_path):
    img = nib.Nifti1Image(_ball_steps(), np.eye(4))
    img.header.set_xyzt_units("mm", "sec")
    img.header["pixdim"][4] = 0.5
    path = tmp_path / "run.nii.gz"
    nib.save(img, path)
    return path


def _scene(path):
    scene = Scene()
    scene.add_time_series(open_time_series(path), step=0, path=str(path))
    scene.frame(view="isometric")
    scene.isosurfaces[0].update(model="trilinear")
    for vol in scene.volumes:
        vol.show_outline = False
    scene.view.show_scale = False
    return scene


def _step_of_frames(scene, anim):
    out = []
    for k in range(anim.frames):
        anim.apply(scene, k)
        out.append(scene.step_index())
    return out


def test_time_playback_keys_each_step(nifti4d):
    scene = _scene(nifti4d)
    assert _step_of_frames(scene, time_playback(scene)) == [0, 1, 2, 3]
    assert _step_of_frames(scene, time_playback(scene, frames_per_step=2)) == \
        [0, 0, 1, 1, 2, 2, 3, 3]
    assert _step_of_frames(scene, time_playback(scene, start=1, stop=-2)) == [1, 2]
    assert _step_of_frames(scene, time_playback(scene, frames=2)) == [0, 2]
    assert _step_of_frames(scene, time_playback(scene, frames=6)) == [0, 0, 1, 2, 2, 3]
    scene.play_rate = 10.0  # fps-matched: 30 fps / 10 steps a second -> 3 frames a step
    anim = time_playback(scene, frames_per_step=None, fps=30.0)
    assert anim.frames == 12 and [k.frame for k in anim.tracks[0].keys] == [0, 3, 6, 9]
    assert anim.tracks[0].keys[2].value == (scene.time_steps()[2],)
    # combined with an orbit of the same length: both tracks, the time still steps
    both = time_playback(scene) + orbit(scene, 90, frames=4)
    assert {t.target for t in both.tracks} == {"camera", TIME_TARGET}
    assert _step_of_frames(scene, both) == [0, 1, 2, 3]


def test_time_playback_refuses_what_is_not_a_range(nifti4d):
    scene = _scene(nifti4d)
    with pytest.raises(AnimationError, match=r"4 time step\(s\) \(0 to 3\)"):
        time_playback(scene, start=2, stop=1)
    with pytest.raises(AnimationError, match="1 or more frames"):
        time_playback(scene, frames_per_step=0)
    with pytest.raises(AnimationError, match="needs a time-varying volume"):
        time_playback(Scene())
    anim = time_playback(scene)
    scene.remove(scene.volumes[0])
    with pytest.raises(AnimationError, match="no time-varying volume"):
        anim.apply(scene, 0)


def test_png_movie_of_all_times_is_render_scene_at_each_step(nifti4d, tmp_path):
    scene = _scene(nifti4d)
    scene.set_step(2)
    stats = sv.movie(scene, tmp_path / "f_%02d.png", all_times=True, size=SIZE)
    assert stats.frames == 4
    assert scene.step_index() == 2  # the scene's time is put back
    frames = [np.asarray(Image.open(tmp_path / f"f_{k:02d}.png")) for k in range(4)]
    for k in range(4):
        scene.set_step(k)
        np.testing.assert_array_equal(frames[k], render_scene(scene, SIZE))
    assert not np.array_equal(frames[0], frames[3])  # the ball grows


def test_movie_cli_all_times_with_an_orbit(nifti4d, tmp_path, capsys):
    out = tmp_path / "m_%02d.png"
    assert main(["movie", str(nifti4d), "--all-times", "--orbit", "90", "--model",
                 "trilinear", "--size", "64x48", "-o", str(out)]) == 0
    assert "4 frames, 64x48" in capsys.readouterr().out
    # frame 3: the last step, the camera turned by 3/4 of 90 degrees (an open turn ends
    # on its last frame)
    for k in (0, 3):
        assert main(["render", str(nifti4d), "--time", str(k), "--model", "trilinear",
                     "--size", "64x48", "-o", str(tmp_path / f"still{k}.png")]) == 0
    frame0, frame3, still0, still3 = (
        np.asarray(Image.open(tmp_path / n))
        for n in ("m_00.png", "m_03.png", "still0.png", "still3.png"))
    np.testing.assert_array_equal(frame0, still0)
    assert not np.array_equal(frame3, still3)  # the camera moved
    assert main(["movie", str(tmp_path / "m_00.png"), "--all-times", "-o",
                 str(tmp_path / "x.mp4")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1


def test_session_with_a_time_track_round_trips(nifti4d, tmp_path, capsys):
    scene = _scene(nifti4d)
    scene.animation = time_playback(scene, frames_per_step=2, fps=12.0) + orbit(
        scene, 180, frames=8)
    path = save_scene(scene, tmp_path / "play.svs")
    again = load_scene(path)
    assert again.animation == scene.animation
    save_scene(again, tmp_path / "again.svs")
    assert (tmp_path / "again.svs").read_bytes() == path.read_bytes()
    assert _step_of_frames(again, again.animation) == [0, 0, 1, 1, 2, 2, 3, 3]
    # the session's own animation is what splineviz movie plays
    assert main(["movie", str(path), "--size", "64x48", "-o", str(tmp_path / "s.gif")]) == 0
    assert "8 frames, 64x48, 12 fps" in capsys.readouterr().out
