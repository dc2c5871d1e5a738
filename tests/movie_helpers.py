"""Helpers of the movie tests: a small smooth scene, decoding a video, PSNR."""

import subprocess

import numpy as np

import splineviz as sv
from splineviz.core.testfunctions import blob
from splineviz.model import Scene

#: decoding with swscale's accurate rounding: its default fast YUV -> RGB path is off by up
#: to 2 levels in flat areas, a loss of the decoder, not of the encoder
ACCURATE = ["-sws_flags", "accurate_rnd+full_chroma_int"]


def decoded_frames(path, meta=None):
    """The decoded RGB frames of a video by imageio's ffmpeg, and its header."""
    import imageio_ffmpeg

    header = imageio_ffmpeg.read_frames(str(path))
    try:
        info = next(header)
    finally:
        header.close()  # ffmpeg still runs: closing stops it and its pipes
    w, h = info["size"]
    raw = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path),
                          "-f", "rawvideo", "-pix_fmt", "rgb24", *ACCURATE, "-"],
                         capture_output=True, check=True).stdout
    if meta is not None:
        meta.update(info)
    return list(np.frombuffer(raw, np.uint8).reshape(-1, h, w, 3))


def psnr(a, b) -> float:
    """Peak signal-to-noise ratio of two uint8 pictures' RGB, dB."""
    mse = np.mean((a[..., :3].astype(float) - b[..., :3].astype(float)) ** 2)
    return 10 * np.log10(255.0 ** 2 / mse)


def blob_scene(size, grid=False) -> Scene:
    """Two blended metaballs filling most of a ``size`` frame, seen isometrically; the
    outline and axes grid shown only with ``grid``."""
    scene = Scene()
    scene.add_volume(sv.Volume.from_function(blob, (17, 17, 17), blob.domain), name="blob",
                     isovalue=blob.isovalue)
    scene.aspect = size[0] / size[1]
    scene.frame(view="isometric")
    cam = scene.camera
    f, p = np.array(cam.focal_point), np.array(cam.position)
    cam.position = tuple(f + 0.6 * (p - f))
    scene.volumes[0].show_outline = grid
    scene.view.show_scale = grid
    return scene
