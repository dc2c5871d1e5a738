"""``splineviz movie``: a movie of a volume file or a session, rendered headless.

The scene is built as ``splineviz render`` builds it (:func:`splineviz.cli.render.run`'s
steps: the app's opening, outline and axes off, the camera of ``--camera`` or the default
one for a volume, the session's for a session); :func:`splineviz.render.movie.movie` (what
``sv.movie`` is) takes the frames from the presets asked for (``--all-times``, ``--orbit``,
``--iso-sweep``, ``--clip-sweep``, combined), else from the session's animation, else a
full orbit, renders each exactly and encodes it beside the rendering.
"""

from __future__ import annotations

import sys

from splineviz.cli.render import (
    RenderArgumentError,
    add_renderer_argument,
    finite_float,
    make_camera,
)
from splineviz.core.camera import CameraError, parse_size


def _sweep(text: str) -> tuple[float, float]:
    import argparse

    parts = text.split(":")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected START:STOP isovalues, got {text!r}")
    return finite_float(parts[0]), finite_float(parts[1])


def _positive_int(text: str) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected 1 or more, got {value}")
    return value


def run(args) -> int:
    import argparse

    from tqdm import tqdm

    from splineviz.cli.render import _time_scene
    from splineviz.model.opening import override, scene_from_path
    from splineviz.render.movie import movie

    size = parse_size(args.size)
    if args.all_times:
        # a 4-D file, a series or a session, opened as splineviz render --all-times does
        scene = _time_scene(argparse.Namespace(
            volume=args.file, time=None, iso=args.iso, model=args.model,
            allow_outside_data=args.allow_outside_data), {})
    else:
        scene = scene_from_path(args.file, isovalue=args.iso, model=args.model,
                                allow_outside=args.allow_outside_data)
    if not scene.isosurfaces:
        raise RenderArgumentError(f"{args.file} holds no volume to render")
    override(scene, renderer=args.renderer)
    for vol in scene.volumes:
        vol.show_outline = False
    scene.view.show_scale = False
    scene.view.show_time = args.time_label
    session = str(args.file).lower().endswith(".svs")
    if not session or args.camera is not None:
        scene.aspect = size[0] / size[1]
        try:
            cam = make_camera(args.camera, scene.bounds(), args.view_angle)
        except CameraError as exc:
            raise RenderArgumentError(f"bad --camera: {exc}") from None
        scene.camera.update(position=cam.position, focal_point=cam.focal_point,
                            view_up=cam.view_up, view_angle=cam.view_angle)
    bar = tqdm(total=0, unit="frame", desc=args.output, file=sys.stderr, leave=False,
               disable=not sys.stderr.isatty())

    def progress(done, total):
        bar.total = total
        bar.n = done
        bar.refresh()

    try:
        stats = movie(scene, args.output, orbit=args.orbit, iso_sweep=args.iso_sweep,
                      clip_sweep=args.clip_sweep, all_times=args.all_times,
                      frames=args.frames, fps=args.fps, size=size,
                      quality=args.quality, transparent_background=args.transparent,
                      device=args.device, progress=progress)
    finally:
        bar.close()
    print(f"{stats.path}: {stats.frames} frames, {size[0]}x{size[1]}, {stats.fps:g} fps, "
          f"{stats.seconds_per_frame:.2f} s a frame")
    return 0


def register(subparsers) -> None:
    """Add the ``movie`` sub-command (see :mod:`splineviz.cli`)."""
    from splineviz.core.splines import MODELS
    from splineviz.model.animation import SWEEP_AXES
    from splineviz.render.movie import DEFAULT_QUALITY

    p = subparsers.add_parser(
        "movie", help="render an animation (orbit, isovalue or clip sweep, time steps) into "
        "MP4/GIF/PNGs",
        description="Render a movie of a volume or session without a display: every frame "
        "is an exact ray-cast picture. With no preset flag a session's own animation is "
        "used, else a full orbit.")
    p.add_argument("file", help="volume file (any format splineviz reads) or session")
    p.add_argument("-o", "--output", required=True,
                   help="out.mp4 | out.gif | frames_%%04d.png (a PNG sequence)")
    p.add_argument("--orbit", type=finite_float, default=None, metavar="DEG",
                   help="turn the camera DEG degrees about its view up")
    p.add_argument("--iso-sweep", type=_sweep, default=None, metavar="A:B",
                   help="isovalue of the first isosurface from A to B")
    p.add_argument("--clip-sweep", choices=tuple(SWEEP_AXES), default=None, metavar="AXIS",
                   help="a clip plane moving through the volume along " + "|".join(SWEEP_AXES))
    p.add_argument("--time-label", action="store_true",
                   help="draw the time step (t = 0.75 s (step 4/6)) in the upper-left corner "
                   "of a time-varying volume's pictures")
    p.add_argument("--all-times", action="store_true",
                   help="play every time step of a 4-D file, a series (a folder or a pattern "
                   "such as run_####.vti) or a session's time-varying volume: one frame a "
                   "step, or spread over --frames; combines with the other presets")
    p.add_argument("--frames", type=_positive_int, default=None,
                   help="number of frames (default 120, one per step with --all-times, or "
                   "the session animation's)")
    p.add_argument("--fps", type=finite_float, default=None,
                   help="frames per second (default 30, or the session animation's)")
    p.add_argument("--size", default="1280x720", help="frame size WxH (even for MP4)")
    p.add_argument("--quality", type=finite_float, default=DEFAULT_QUALITY,
                   help="1..10, 10 best (MP4: the H.264 rate factor)")
    p.add_argument("--transparent", action="store_true",
                   help="PNG sequences: a transparent background")
    p.add_argument("--iso", type=finite_float, default=None, help="isovalue")
    p.add_argument("--model", default=None,
                   help=" | ".join(MODELS) + " (default: cubic-c1, or the session's)")
    add_renderer_argument(p)
    p.add_argument("--camera", default=None,
                   help="px,py,pz[,fx,fy,fz[,ux,uy,uz]] starting eye [focal point [view up]]")
    p.add_argument("--view-angle", type=float, default=30.0, help="vertical view angle, degrees")
    p.add_argument("--device", default=None, help="gpu | cpu | numpy | device-name substring")
    p.add_argument("--allow-outside-data", action="store_true",
                   help="read data files that a header or session names outside its folder")
    p.set_defaults(func=run)
