"""``splineviz movie`` and ``sv.movie``: a session's animation or the presets, headless; each
frame matches the still ``splineviz render`` makes at its camera."""

import imageio
import numpy as np
import pytest
from movie_helpers import blob_scene, decoded_frames, psnr

import splineviz as sv
from splineviz.cli import main
from splineviz.model.animation import orbit
from splineviz.model.session import load_scene, save_scene


@pytest.fixture
def session(tmp_path):
    scene = blob_scene((4, 3))
    scene.animation = orbit(scene, 360, frames=4, fps=8)
    return save_scene(scene, tmp_path / "turn.svs")


def test_movie_of_a_session_plays_its_animation(session, tmp_path, capsys):
    out = tmp_path / "turn.mp4"
    assert main(["movie", str(session), "-o", str(out), "--size", "128x96"]) == 0
    assert "4 frames, 128x96, 8 fps" in capsys.readouterr().out
    meta = {}
    frames = decoded_frames(out, meta)
    assert len(frames) == 4 and meta["fps"] == 8
    scene = load_scene(session)
    for k in (0, 2):
        scene.animation.apply(scene, k)
        cam = scene.camera
        still = tmp_path / f"still{k}.png"
        camera = ",".join(f"{v!r}" for v in (*cam.position, *cam.focal_point, *cam.view_up))
        assert main(["render", str(session), "--size", "128x96", f"--camera={camera}",
                     "--view-angle", repr(cam.view_angle), "-o", str(still)]) == 0
        assert psnr(frames[k], imageio.v3.imread(still)) >= 40.0
    moved = np.abs(frames[0].astype(int) - frames[2]).max(axis=2) > 40
    assert moved.mean() > 0.05


def test_presets_from_the_command_line(session, tmp_path):
    out = tmp_path / "f_%02d.png"
    assert main(["movie", str(session), "-o", str(out), "--size", "64x48", "--frames", "3",
                 "--iso-sweep", "0.3:0.6", "--orbit", "30"]) == 0
    assert sorted(p.name for p in tmp_path.glob("f_*.png")) == ["f_00.png", "f_01.png",
                                                                 "f_02.png"]


def test_bad_arguments_are_one_line(session, tmp_path, capsys):
    assert main(["movie", str(session), "-o", str(tmp_path / "a.mp4"), "--size",
                 "63x48"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("splineviz: error:") and "even" in err and err.count("\n") == 1
    assert main(["movie", str(session), "-o", str(tmp_path / "a.mp4"), "--iso-sweep",
                 "1"]) == 2
    assert "START:STOP" in capsys.readouterr().err
    assert list(tmp_path.glob("a*")) == []


def test_sv_movie_from_python(session, tmp_path):
    scene = load_scene(session)
    stats = sv.movie(scene, tmp_path / "m.gif", size=(64, 48))  # the scene's animation
    assert stats.frames == 4
    assert imageio.v3.imread(tmp_path / "m.gif", index=None).shape[0] == 4
    stats = sv.movie(scene, tmp_path / "o.gif", orbit=90, frames=3, size=(64, 48))
    assert stats.frames == 3
    with pytest.raises(sv.SplinevizError, match="has 4 frames"):
        sv.movie(scene, tmp_path / "x.gif", scene.animation, frames=5, size=(64, 48))
