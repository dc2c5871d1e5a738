"""The issue's acceptance check (``-m slow``, minutes): ``splineviz movie`` of a bonsai
session writes a 120-frame 1920x1080 orbit MP4 headless; the decoded video has 120 frames,
frame k matches a still ``splineviz render`` at its camera to 40 dB, frames 0 and 60 differ
where the camera moved, a frame takes at most 1.2x one still, and the peak memory of the
process does not grow with the frame count."""

import re
import resource
import subprocess
import sys
import time

import imageio
import numpy as np
import pytest
from movie_helpers import decoded_frames, psnr

from splineviz.model.animation import orbit
from splineviz.model.opening import scene_from_path
from splineviz.model.session import load_scene, save_scene
from splineviz.render.scene_view import render_scene

SIZE = "1920x1080"


def _cli(*args) -> str:
    """Run ``splineviz`` in a child process; what it printed."""
    # the session names the shared bonsai, outside its folder
    return subprocess.run([sys.executable, "-m", "splineviz.cli", *args,
                           "--allow-outside-data"], check=True,
                          capture_output=True, text=True).stdout


@pytest.mark.slow
def test_120_frame_1080p_orbit_of_a_session(shared_data, tmp_path):
    scene = scene_from_path(shared_data / "volumes" / "bonsai.vti", isovalue=40.0)
    scene.aspect = 16 / 9
    scene.frame(view="isometric")
    for frames, name in ((20, "short"), (120, "turn")):
        scene.animation = orbit(scene, 360, frames=frames)
        save_scene(scene, tmp_path / f"{name}.svs")
    _cli("movie", str(tmp_path / "short.svs"), "-o", str(tmp_path / "short.mp4"),
         "--size", SIZE)
    peak_short = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    printed = _cli("movie", str(tmp_path / "turn.svs"), "-o", str(tmp_path / "turn.mp4"),
                   "--size", SIZE)
    per_frame = float(re.search(r"([0-9.]+) s a frame", printed).group(1))
    peak_long = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    session = tmp_path / "turn.svs"
    frames = decoded_frames(tmp_path / "turn.mp4")
    assert len(frames) == 120 and frames[0].shape == (1080, 1920, 3)
    with imageio.get_reader(tmp_path / "turn.mp4") as reader:  # imageio's own decoding
        default_decoded = [f for i, f in zip(range(61), reader, strict=False)][::60]
    loaded = load_scene(session, allow_outside=True)
    for vol in loaded.volumes:  # as splineviz render and movie draw it
        vol.show_outline = False
    loaded.view.show_scale = False
    loaded.animation.apply(loaded, 30)
    render_scene(loaded, (1920, 1080))  # kernels built, cells classified: warm
    t = time.perf_counter()
    render_scene(loaded, (1920, 1080))
    still_s = time.perf_counter() - t
    stills = {}
    for k in (0, 60, 119):
        loaded.animation.apply(loaded, k)
        cam = loaded.camera
        camera = ",".join(repr(v) for v in (*cam.position, *cam.focal_point, *cam.view_up))
        _cli("render", str(session), "--size", SIZE, f"--camera={camera}",
             "-o", str(tmp_path / f"still{k}.png"))
        stills[k] = imageio.v3.imread(tmp_path / f"still{k}.png")
        assert psnr(frames[k], stills[k]) >= 40.0
    moved = np.abs(frames[0].astype(int) - frames[60]).max(axis=2) > 40
    default = [round(psnr(f, stills[k]), 1)
               for f, k in zip(default_decoded, (0, 60), strict=True)]
    print(f"\n1080p orbit: {per_frame:.2f} s a frame, one still render_scene {still_s:.2f} s, "
          f"ratio {per_frame / still_s:.2f}; PSNR "
          f"{[round(psnr(frames[k], stills[k]), 1) for k in stills]} dB (accurate decoding), "
          f"{default} dB (imageio's default); moved {moved.mean():.0%} of pixels; peak RSS "
          f"{peak_short / 1024:.0f} MiB (20 frames), {peak_long / 1024:.0f} MiB (120)")
    assert moved.mean() > 0.05
    assert per_frame <= 1.2 * still_s
    # six times the frames: the peak moves with the views' classification caches and the
    # allocator (measured 1277 and 1443 MiB), while keeping the frames would add 6 MiB
    # each (+600 MiB for the 100 more)
    assert peak_long <= 1.25 * peak_short
