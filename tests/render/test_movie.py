"""Movies: every frame the still render_scene makes of the animated scene, encoded as MP4,
GIF or PNG sequence; cancel leaves nothing behind."""

import threading

import imageio
import numpy as np
import pytest
from movie_helpers import blob_scene, decoded_frames, psnr

from splineviz.model.animation import clip_sweep, isovalue_sweep, orbit
from splineviz.render.movie import (
    MovieCancelled,
    MovieError,
    export_movie,
    partial_path,
)
from splineviz.render.scene_view import OffscreenRenderer, render_scene

SIZE = (192, 144)


def _scene(grid=False):
    return blob_scene(SIZE, grid)


def test_renderer_frames_are_render_scene_stills_after_camera_moves():
    scene = _scene(grid=True)  # the axes grid's labels too
    anim = orbit(scene, 360, frames=4)
    with OffscreenRenderer(scene, (96, 72)) as renderer:
        frames = []
        for k in range(4):
            anim.apply(scene, k)
            frames.append(renderer.render())
    for k in (1, 3):
        anim.apply(scene, k)
        np.testing.assert_array_equal(frames[k], render_scene(scene, (96, 72)))


def test_orbit_mp4_frames_match_stills(tmp_path):
    scene = _scene()
    anim = orbit(scene, 360, frames=6)
    before = scene.camera.pose()
    seen = []
    stats = export_movie(scene, anim, tmp_path / "orbit.mp4", size=SIZE, fps=12,
                         progress=lambda i, n: seen.append((i, n)))
    assert scene.camera.pose() == before  # the scene is as it was
    assert seen == [(i, 6) for i in range(1, 7)]
    assert stats.frames == 6 and len(stats.render_s) == 6 and len(stats.encode_s) == 6
    assert not partial_path(tmp_path / "orbit.mp4").exists()
    meta = {}
    frames = decoded_frames(tmp_path / "orbit.mp4", meta)
    assert meta["fps"] == 12 and meta["codec"] == "h264"
    assert meta["pix_fmt"].startswith("yuv420p")
    assert len(frames) == 6 and frames[0].shape == (SIZE[1], SIZE[0], 3)
    stills = {}
    for k in (0, 3):
        anim.apply(scene, k)
        stills[k] = render_scene(scene, SIZE)
        assert psnr(frames[k], stills[k]) >= 40.0
    # the camera moved: the middle frame is another picture, and the stills tell them apart
    moved = np.abs(frames[0].astype(int) - frames[3]).max(axis=2) > 40
    assert moved.mean() > 0.05
    assert psnr(frames[3], stills[0]) < 30.0


def test_isovalue_sweep_frames_are_stills_at_the_interpolated_isovalue(tmp_path):
    scene = _scene()
    iso = scene.isosurfaces[0]
    anim = isovalue_sweep(scene, 0.3, 0.7, frames=5)
    export_movie(scene, anim, tmp_path / "sweep_%02d.png", size=SIZE)
    names = sorted(tmp_path.glob("sweep_*.png"))
    assert [p.name for p in names] == [f"sweep_{k:02d}.png" for k in range(5)]
    export_movie(scene, anim, tmp_path / "sweep.mp4", size=SIZE)
    video = decoded_frames(tmp_path / "sweep.mp4")
    for k, value in ((1, 0.4), (4, 0.7)):
        iso.isovalue = value
        still = render_scene(scene, SIZE)
        np.testing.assert_array_equal(imageio.v3.imread(names[k])[..., :3], still)
        assert psnr(video[k], still) >= 40.0


def test_clip_sweep_moves_a_plane_through_the_volume(tmp_path):
    scene = _scene()
    anim = clip_sweep(scene, "x", frames=5)
    plane = scene.clip_planes[0]
    export_movie(scene, anim, tmp_path / "clip_%d.png", size=SIZE)
    frames = [imageio.v3.imread(tmp_path / f"clip_{k}.png") for k in range(5)]
    background = frames[0][0, 0]
    covered = [np.any(f != background, axis=2).mean() for f in frames]
    assert covered[0] > covered[2] > covered[4]  # less and less is kept
    lo, hi = scene.volumes[0].bounds[0]
    plane.origin = (lo + 0.5 * (hi - lo), *plane.origin[1:])
    np.testing.assert_array_equal(frames[2][..., :3], render_scene(scene, SIZE))


def test_gif_of_48_frames_decodes(tmp_path):
    scene = _scene()
    anim = orbit(scene, 360, frames=48)
    export_movie(scene, anim, tmp_path / "turn.gif", size=(64, 48), fps=24)
    frames = imageio.v3.imread(tmp_path / "turn.gif", index=None)
    assert frames.shape[:3] == (48, 48, 64)


def test_transparent_png_sequence(tmp_path):
    scene = _scene()
    anim = orbit(scene, 90, frames=2)
    export_movie(scene, anim, tmp_path / "t.png", size=(64, 48), transparent_background=True)
    img = imageio.v3.imread(tmp_path / "t_0001.png")
    assert img.shape == (48, 64, 4)
    assert img[0, 0, 3] == 0 and img[..., 3].max() == 255


def test_cancel_removes_the_partial_file(tmp_path):
    scene = _scene()
    anim = orbit(scene, 360, frames=20)
    out = tmp_path / "c.mp4"
    with pytest.raises(MovieCancelled):
        export_movie(scene, anim, out, size=(64, 48), progress=lambda i, n: i < 3)
    assert list(tmp_path.iterdir()) == []
    stop = threading.Event()
    stop.set()
    with pytest.raises(MovieCancelled):
        export_movie(scene, anim, tmp_path / "p_%03d.png", size=(64, 48), cancel=stop)
    with pytest.raises(MovieCancelled):
        export_movie(scene, anim, tmp_path / "q_%03d.png", size=(64, 48),
                     progress=lambda i, n: i < 2)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name, size, options, message", [
    ("odd.mp4", (65, 48), {}, "even width and height"),
    ("a.mov", (64, 48), {}, "cannot tell the movie format"),
    ("a.gif", (64, 48), {"transparent_background": True}, "transparent background"),
    ("a.mp4", (64, 48), {"quality": 11}, "quality"),
    ("a.mp4", (64, 48), {"fps": 0}, "frame rate"),
    ("a_%d_%d.png", (64, 48), {}, "one frame-number field"),
])
def test_bad_requests_are_refused_before_anything_is_written(tmp_path, name, size, options,
                                                             message):
    scene = _scene()
    with pytest.raises(MovieError, match=message):
        export_movie(scene, orbit(scene, 90, frames=2), tmp_path / name, size=size, **options)
    assert list(tmp_path.iterdir()) == []
