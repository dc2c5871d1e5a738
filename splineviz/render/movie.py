"""Movies of an animated scene: every frame an exact picture, encoded beside the rendering.

:func:`export_movie` applies frame ``k`` of an :class:`~splineviz.model.animation.Animation`
to the scene and renders it with an :class:`~splineviz.render.scene_view.OffscreenRenderer`
(the picture :func:`~splineviz.render.scene_view.render_scene` makes of that scene, never a
preview), at any size. The rendering thread hands each picture to a writer thread through a
queue of :data:`QUEUE_FRAMES` pictures, so encoding overlaps rendering (the time per frame
is the larger of the two, not their sum) and memory does not grow with the frame count.

Formats (:data:`MOVIE_FORMATS`, by the file's suffix): MP4 (H.264, yuv420p, even sizes, a
chosen frame rate and quality) and GIF (a palette made for each frame, with error-diffusion
dithering, so smooth shading does not band) through the ffmpeg that ``imageio-ffmpeg``
carries, and PNG sequences (``frames_%04d.png``; RGBA with ``transparent_background``).

Progress: ``progress(done, total)`` after each frame; returning False cancels. ``cancel``
(anything with ``is_set()``, e.g. a :class:`threading.Event`) is checked before each frame.
A cancelled or failed export removes what it wrote: a movie is written to
:func:`partial_path` and renamed onto its name only when complete.
"""

from __future__ import annotations

import os
import queue
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizError
from splineviz.core.registry import Registry

#: pictures waiting between the renderer and the writer (bounds memory at any length)
QUEUE_FRAMES = 3
#: x264 quality: quality 1..10 (imageio's scale, 10 best) -> constant rate factor
#: ``round(51 * (1 - q / 10))``. The default (rate factor 5) costs ~0.2 dB against a
#: lossless encoding: what remains of the difference to the still (~40.4 dB for the bonsai
#: at 1080p, measured) is yuv420p's chroma at silhouettes, which no rate factor gives back
DEFAULT_QUALITY = 9.0


class MovieError(SplinevizError, ValueError):
    """A movie that cannot be written as asked (one sentence)."""


class MovieCancelled(SplinevizError):
    """The export was cancelled; nothing of it is left on disk."""


def partial_path(path) -> Path:
    """Where a movie is written until it is complete: ``<stem>.partial<suffix>`` beside it
    (the suffix kept: ffmpeg chooses the container by it)."""
    p = Path(os.fspath(path))
    return p.with_name(f"{p.stem}.partial{p.suffix}")


# ---------------------------------------------------------------------------- writers
class _FFmpegWriter:
    """Frames piped into ffmpeg (``imageio_ffmpeg.write_frames``), written to
    :func:`partial_path` and renamed onto ``path`` by :meth:`finish`."""

    codec = ""
    pix_fmt_out = ""

    def __init__(self, path: Path, size, fps: float, quality: float):
        import imageio_ffmpeg

        self.path = path
        self.partial = partial_path(path)
        self.partial.unlink(missing_ok=True)
        self._gen = imageio_ffmpeg.write_frames(
            str(self.partial), tuple(size), fps=fps, codec=self.codec, quality=None,
            pix_fmt_in="rgb24", pix_fmt_out=self.pix_fmt_out, macro_block_size=1,
            ffmpeg_log_level="error", output_params=self.output_params(quality))
        self._gen.send(None)

    def output_params(self, quality: float) -> list[str]:
        return []

    def write(self, frame: np.ndarray) -> None:
        self._gen.send(np.ascontiguousarray(frame[..., :3]))

    def finish(self) -> None:
        self._gen.close()
        os.replace(self.partial, self.path)

    def abort(self) -> None:
        try:
            self._gen.close()
        finally:
            self.partial.unlink(missing_ok=True)

    def leftovers(self) -> list[Path]:
        return [self.partial]


class _MP4Writer(_FFmpegWriter):
    codec = "libx264"
    pix_fmt_out = "yuv420p"

    def output_params(self, quality: float) -> list[str]:
        crf = round(51 * (1.0 - quality / 10.0))
        # BT.709, converted with accurate rounding and tagged: players (and ffmpeg's own
        # decoder) then convert back with the same matrix
        return ["-crf", str(crf), "-preset", "medium", "-movflags", "+faststart",
                "-vf", "scale=out_color_matrix=bt709:out_range=tv:flags=accurate_rnd",
                "-colorspace", "bt709", "-color_primaries", "bt709", "-color_trc", "bt709",
                "-color_range", "tv"]


class _GIFWriter(_FFmpegWriter):
    codec = "gif"
    pix_fmt_out = "pal8"

    def output_params(self, quality: float) -> list[str]:
        # a palette of each frame's own colours (stats_mode=single, new=1: streamed, so
        # memory stays constant) with error diffusion: no bands in smooth shading
        graph = ("split[a][b];[a]palettegen=stats_mode=single:reserve_transparent=0[p];"
                 "[b][p]paletteuse=new=1:dither=sierra2_4a")
        return ["-vf", graph, "-loop", "0"]


class _PNGWriter:
    """One PNG per frame, named by the printf pattern of ``path`` (``%04d`` added before
    the suffix when it has none)."""

    def __init__(self, path: Path, size, fps: float, quality: float):
        self.pattern = png_pattern(path)
        self.written: list[Path] = []

    def name(self, index: int) -> Path:
        return Path(str(self.pattern) % index)

    def write(self, frame: np.ndarray) -> None:
        from splineviz.io.meshes import write_screenshot

        p = self.name(len(self.written))
        write_screenshot(p, frame)
        self.written.append(p)

    def finish(self) -> None:
        pass

    def abort(self) -> None:
        for p in self.written:
            p.unlink(missing_ok=True)

    def leftovers(self) -> list[Path]:
        return list(self.written)


_PRINTF = re.compile(r"%0?\d*d")


def png_pattern(path) -> Path:
    """The printf pattern of a PNG sequence's names: ``path`` when it holds one
    (``frames_%04d.png``), else ``<stem>_%04d.png``."""
    p = Path(os.fspath(path))
    if len(_PRINTF.findall(p.name)) == 1 and "%" not in p.name.replace(
            _PRINTF.search(p.name).group(0), ""):
        return p
    if "%" in p.name:
        raise MovieError(f"a PNG sequence name holds one frame-number field such as %04d, "
                         f"got {p.name!r}")
    return p.with_name(f"{p.stem}_%04d{p.suffix}")


@dataclass(frozen=True)
class MovieFormat:
    """A movie format: its writer class, suffixes, whether it needs even sizes and whether
    it keeps a transparent background."""

    writer: type
    suffixes: tuple[str, ...]
    even: bool = False
    alpha: bool = False
    description: str = ""


#: format name -> :class:`MovieFormat`
MOVIE_FORMATS: Registry[MovieFormat] = Registry("movie format", {
    "mp4": MovieFormat(_MP4Writer, (".mp4", ".m4v"), even=True,
                       description="H.264 video (yuv420p)"),
    "gif": MovieFormat(_GIFWriter, (".gif",), description="animated GIF, a palette a frame"),
    "png": MovieFormat(_PNGWriter, (".png",), alpha=True, description="PNG sequence"),
}, error=MovieError)


def movie_format(path) -> str:
    """The :data:`MOVIE_FORMATS` name of ``path``'s suffix."""
    suffix = Path(os.fspath(path)).suffix.lower()
    for name, fmt in MOVIE_FORMATS.items():
        if suffix in fmt.suffixes:
            return name
    known = ", ".join(s for f in MOVIE_FORMATS.values() for s in f.suffixes)
    raise MovieError(f"cannot tell the movie format of {Path(os.fspath(path)).name!r}: name it "
                     f"with one of {known}")


# ---------------------------------------------------------------------------- export
@dataclass
class MovieStats:
    """What an export did: the file (or PNG pattern), frames, and seconds per frame spent
    rendering and encoding (the writer's, overlapping the rendering) and in all."""

    path: Path
    fps: float = 0.0
    frames: int = 0
    render_s: list = field(default_factory=list)
    encode_s: list = field(default_factory=list)
    total_s: float = 0.0

    @property
    def seconds_per_frame(self) -> float:
        return self.total_s / max(self.frames, 1)


class _Writer(threading.Thread):
    """Takes pictures from a bounded queue and encodes them; an error stops it and is
    kept for the rendering thread to raise."""

    def __init__(self, sink, stats: MovieStats):
        super().__init__(name="splineviz movie writer", daemon=True)
        self.sink = sink
        self.stats = stats
        self.frames: queue.Queue = queue.Queue(maxsize=QUEUE_FRAMES)
        self.error: BaseException | None = None
        self.stop = threading.Event()

    def run(self) -> None:
        while True:
            frame = self.frames.get()
            if frame is None or self.stop.is_set():
                return
            t0 = time.perf_counter()
            try:
                self.sink.write(frame)
            except BaseException as exc:  # noqa: BLE001  (raised by the rendering thread)
                self.error = exc
                return
            self.stats.encode_s.append(time.perf_counter() - t0)

    def put(self, frame) -> None:
        """Queue ``frame``, waiting for room; raises the writer's error if it stopped."""
        while True:
            if self.error is not None or not self.is_alive():
                raise self.error or MovieError("the movie writer stopped")
            try:
                self.frames.put(frame, timeout=0.1)
                return
            except queue.Full:
                continue

    def end(self) -> None:
        """Let the writer take what is queued and stop."""
        while self.is_alive():
            try:
                self.frames.put(None, timeout=0.1)
                break
            except queue.Full:
                continue
        self.join()
        if self.error is not None:
            raise self.error

    def drop(self) -> None:
        """Stop without writing what is queued."""
        self.stop.set()
        while True:
            try:
                self.frames.get_nowait()
            except queue.Empty:
                break
        try:
            self.frames.put_nowait(None)
        except queue.Full:
            pass
        self.join()


def _check(path: Path, fmt: MovieFormat, name: str, size, fps, quality, transparent) -> None:
    w, h = size
    if fmt.even and (w % 2 or h % 2):
        raise MovieError(f"{name.upper()} needs an even width and height (H.264, yuv420p), "
                         f"got {w}x{h}")
    if transparent and not fmt.alpha:
        raise MovieError(f"a transparent background needs a PNG sequence, not {name.upper()}")
    if not (np.isfinite(fps) and 0 < fps <= 240):
        raise MovieError(f"the frame rate must be above 0 and at most 240, got {fps}")
    if not (np.isfinite(quality) and 1 <= quality <= 10):
        raise MovieError(f"the quality must be between 1 and 10, got {quality}")
    if not path.parent.is_dir():
        raise MovieError(f"the folder {path.parent} does not exist")


def export_movie(scene, animation, path, *, size=(1280, 720), fps: float | None = None,
                 quality: float = DEFAULT_QUALITY, transparent_background: bool = False,
                 device=None, progress: Callable[[int, int], object] | None = None,
                 cancel=None) -> MovieStats:
    """Render every frame of ``animation`` on ``scene`` into the movie ``path``.

    Parameters
    ----------
    scene : splineviz.model.Scene
        Its animated properties are back at their values from before when this returns.
    animation : splineviz.model.animation.Animation
    path : path-like
        ``.mp4``, ``.gif`` or ``.png`` (a PNG sequence: ``frames_%04d.png``).
    size : (int, int) or str
        Width and height of every frame (``"1920x1080"`` too).
    fps : float, optional
        Frames per second (default: the animation's).
    quality : float
        1..10, 10 best (MP4: the x264 rate factor, see :data:`DEFAULT_QUALITY`).
    transparent_background : bool
        PNG sequences only: RGBA frames with a transparent background.
    device : str, optional
        OpenCL device preference.
    progress : callable, optional
        ``progress(done, total)`` after each frame; False cancels.
    cancel : object with ``is_set()``, optional
        Checked before each frame.

    Returns
    -------
    MovieStats

    Raises
    ------
    MovieCancelled
        After a cancel, with the partial file removed.
    MovieError
        Bad format, size, frame rate or quality (nothing written).
    """
    from splineviz.core.camera import parse_size
    from splineviz.render.scene_view import OffscreenRenderer

    path = Path(os.fspath(path)).expanduser()
    name = movie_format(path)
    fmt = MOVIE_FORMATS[name]
    size = parse_size(size)
    fps = float(animation.fps if fps is None else fps)
    quality = float(quality)
    _check(path, fmt, name, size, fps, quality, transparent_background)
    animation.check(scene)
    saved = animation.state_of(scene)
    stats = MovieStats(path if name != "png" else png_pattern(path), fps=fps)
    t_start = time.perf_counter()
    sink = fmt.writer(path, size, fps, quality)
    writer = _Writer(sink, stats)
    writer.start()
    finished = False
    try:
        with OffscreenRenderer(scene, size, transparent_background=transparent_background,
                               device=device) as renderer:
            for k in range(animation.frames):
                if cancel is not None and cancel.is_set():
                    raise MovieCancelled("the movie export was cancelled")
                animation.apply(scene, k)
                t0 = time.perf_counter()
                frame = renderer.render()
                stats.render_s.append(time.perf_counter() - t0)
                writer.put(frame)
                del frame
                stats.frames = k + 1
                if progress is not None and progress(k + 1, animation.frames) is False:
                    raise MovieCancelled("the movie export was cancelled")
        writer.end()
        sink.finish()
        finished = True
    finally:
        if not finished:
            writer.drop()
            sink.abort()
        animation.restore(scene, saved)
    stats.total_s = time.perf_counter() - t_start
    return stats


def staging_folder(path) -> Path:
    """The folder an export in another process writes into (``.<name>.partial`` beside
    ``path``): its files move onto their names when the export is complete, and whoever
    stops that process removes the folder, whatever was in it."""
    p = Path(os.fspath(path)).expanduser()
    return p.with_name(f".{p.name}.partial")


def export_session(session, data: dict, path, *, job=None, **options) -> MovieStats:
    """:func:`export_movie` of a session's scene and animation, written in
    :func:`staging_folder` and moved onto ``path`` when complete (what a worker process
    runs: ``session`` and ``data`` as :func:`splineviz.model.session.apply_session` takes
    them). ``job.progress(fraction, message)`` hears of each frame, with the time left;
    its False cancels."""
    import shutil

    from splineviz.model.scene import Scene
    from splineviz.model.session import apply_session

    scene = apply_session(Scene(), session, data)
    if scene.animation is None:
        raise MovieError("the session has no animation to export")
    path = Path(os.fspath(path)).expanduser()
    staging = staging_folder(path)
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    start = time.perf_counter()

    def progress(done, total):
        if job is None:
            return True
        left = (time.perf_counter() - start) / done * (total - done)
        return job.progress(done / total, f"frame {done} of {total}, {left:.0f} s left")

    try:
        stats = export_movie(scene, scene.animation, staging / path.name, progress=progress,
                             **options)
        for f in sorted(staging.iterdir()):
            os.replace(f, path.parent / f.name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    stats.path = path.parent / stats.path.name
    return stats


def movie(scene, path, animation=None, *, orbit: float | None = None,
          iso_sweep=None, clip_sweep: str | None = None, all_times: bool = False,
          frames: int | None = None, fps: float | None = None, size=(1280, 720),
          **options) -> MovieStats:
    """``sv.movie``: write a movie of ``scene`` to ``path``.

    The frames come from ``animation``, else from the presets asked for (``all_times``:
    every time step of the scene's time-varying volumes, one frame each, or spread over
    ``frames``; ``orbit``: degrees of a turntable; ``iso_sweep``: ``(start, stop)``
    isovalues of the first isosurface; ``clip_sweep``: an axis of
    :data:`~splineviz.model.animation.SWEEP_AXES`, combined when several are given), else
    from the scene's own animation, else a 360-degree orbit. ``frames`` and ``fps``
    default to the animation's (120 and 30 for presets; the number of steps with
    ``all_times``). The other keywords are :func:`export_movie`'s.

    Examples
    --------
    >>> import splineviz as sv                                        # doctest: +SKIP
    >>> sv.movie(scene, "turn.mp4", orbit=360, frames=120, size=(1920, 1080))  # doctest: +SKIP
    """
    from splineviz.model.animation import preset_animation

    if animation is not None:
        if frames is not None and frames != animation.frames:
            raise MovieError(f"the animation has {animation.frames} frames, not {frames}; "
                             "leave frames out or make the animation with it")
    else:
        animation = preset_animation(scene, orbit_degrees=orbit, iso_sweep=iso_sweep,
                                     clip_axis=clip_sweep, all_times=all_times,
                                     frames=frames, fps=fps or 30.0)
    if animation is None:
        animation = scene.animation
        if animation is None or (frames is not None and frames != animation.frames):
            animation = preset_animation(scene, orbit_degrees=360.0, frames=frames or 120,
                                         fps=fps or 30.0)
    return export_movie(scene, animation, path, size=size, fps=fps, **options)
