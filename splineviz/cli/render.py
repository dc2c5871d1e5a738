"""``splineviz render``: the isosurface of a volume file (or a whole session) as a PNG.

The scene is built like the app's (:mod:`splineviz.model.opening`) and drawn by
:func:`~splineviz.render.scene_view.render_scene`, off-screen (no display needed), so the
picture is the one the window would show for the same camera.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from splineviz.core.camera import Camera, CameraError, default_camera, parse_size
from splineviz.core.errors import SplinevizError


class RenderArgumentError(SplinevizError, ValueError):
    """A malformed ``--camera`` or ``--clip`` argument."""


def _floats(text: str, counts, what: str) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise RenderArgumentError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if len(vals) not in counts or not np.all(np.isfinite(vals)):
        raise RenderArgumentError(
            f"{what} needs {' or '.join(map(str, counts))} finite numbers, got {text!r}")
    return vals


def finite_float(text: str) -> float:
    """argparse type of a finite number (``nan`` and ``inf`` parse as floats but are no
    isovalue)."""
    import argparse

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def make_camera(spec: str | None, bounds, view_angle: float) -> Camera:
    """Camera from ``--camera``: ``px,py,pz`` (looks at the box centre), ``+focal`` (6
    numbers) or ``+view up`` (9 numbers); ``None`` gives :func:`default_camera`."""
    if spec is None:
        return default_camera(bounds, view_angle)
    v = _floats(spec, (3, 6, 9), "--camera")
    focal = v[3:6] if len(v) >= 6 else np.asarray(bounds, float).mean(axis=1)
    up = v[6:9] if len(v) == 9 else (0, 0, 1)
    return Camera(v[:3], focal, view_up=up, view_angle=view_angle)


def _configure_bricks(scene, args):
    """For chunked volumes: the dask scheduler (``--scheduler``, else a LocalCluster of
    ``--workers``) and a bricks-done progress bar on stderr; returns the bar and the settings
    to restore afterwards (None when the scene holds no chunked volume)."""
    from splineviz.core.chunked import ChunkedVolume

    if not any(isinstance(v.data, ChunkedVolume) for v in scene.volumes):
        return None
    from tqdm import tqdm

    from splineviz.compute import bricked

    bar = tqdm(total=0, unit="brick", desc="bricks", file=sys.stderr, leave=False,
               disable=not sys.stderr.isatty())

    def progress(done, total):
        bar.total = total
        bar.n = done
        bar.refresh()

    saved = dict(bricked.DEFAULTS)
    # one frame: a brick's caster is not asked again, so none is kept (their device buffers
    # are the larger part of a worker's memory)
    bricked.configure(scheduler=args.scheduler or saved["scheduler"], workers=args.workers,
                      progress=progress, cache_bytes=0)
    return bar, saved


def _time_scene(args, options: dict):
    """The scene of a time-varying volume (``--time``, ``--all-times``): its step ``--time``
    (the first with ``--all-times``), or a session's scene moved to that step."""
    from splineviz.io.opening import SESSION_SUFFIXES, data_name
    from splineviz.io.time_series import open_time_series
    from splineviz.model.opening import override, scene_from_path
    from splineviz.model.scene import Scene

    if str(args.volume).lower().endswith(SESSION_SUFFIXES):
        scene = scene_from_path(args.volume, isovalue=args.iso, model=args.model,
                                allow_outside=args.allow_outside_data, **options)
        if not scene.time_varying:
            raise RenderArgumentError(f"{args.volume} holds no time-varying volume; --time "
                                      "and --all-times need one")
        if args.time is not None:
            node = scene.time_varying[0]
            scene.set_time(node.times[node.series.parse_step(args.time)])
        return scene
    series = open_time_series(args.volume, allow_outside=args.allow_outside_data, **options)
    step = 0 if args.time is None else series.parse_step(args.time)
    scene = Scene()
    scene.add_time_series(series, data_name(args.volume), step=step, path=str(args.volume))
    scene.frame(view="isometric")
    override(scene, isovalue=args.iso, model=args.model)
    return scene


def _frame_names(pattern: str, times) -> list[str]:
    """The file of each step of ``--all-times -o PATTERN`` (``{t}``: the step index,
    ``{time}``: its time); a one-sentence error when the pattern names every step alike."""
    try:
        names = [pattern.format(t=k, time=t) for k, t in enumerate(times)]
    except (KeyError, IndexError, ValueError):
        raise RenderArgumentError(f"-o {pattern!r} may name only {{t}} (the step index) and "
                                  "{time} (its time), e.g. frame_{t:04d}.png") from None
    if len(set(names)) != len(names):
        raise RenderArgumentError("--all-times needs -o with the step in it, e.g. "
                                  "frame_{t:04d}.png")
    return names


def _volume_rendering(scene, args) -> None:
    """Volume-render every volume with the transfer function of ``--volume-rendering``; the
    isosurfaces stay (embedded) only when ``--iso`` asks for one."""
    from splineviz.model.nodes import ModelError
    from splineviz.render.volume_rendering import transfer_function_of

    for vol in scene.volumes:
        try:
            vol.update(volume_rendering=True, transfer_function=args.volume_rendering,
                       transfer_function_points=None,  # a session's edit gives way
                       **({"rendering_model": args.model} if args.model else {}))
        except ModelError as exc:
            raise RenderArgumentError(f"bad --volume-rendering: {exc}") from None
        transfer_function_of(vol)  # a file that cannot be read fails here, in one sentence
    if args.iso is None:
        for iso in scene.isosurfaces:
            iso.visible = False


def run(args) -> int:
    from splineviz.core.splines import model_spec
    from splineviz.model.opening import override, scene_from_path
    from splineviz.render.scene_view import render_scene

    size = parse_size(args.size)
    if args.series is not None:
        from splineviz.io.dicom import series_file

        args.volume = str(series_file(args.volume, args.series))
    options = {k: v for k, v in (("channel", args.channel), ("oblique", args.oblique))
               if v is not None}
    if args.time is not None and args.all_times:
        raise RenderArgumentError("give either --time or --all-times, not both")
    if args.time is not None or args.all_times:
        scene = _time_scene(args, options)
    else:
        scene = scene_from_path(args.volume, isovalue=args.iso, model=args.model,
                                allow_outside=args.allow_outside_data, **options)
    if not scene.isosurfaces:
        raise RenderArgumentError(f"{args.volume} holds no volume to render")
    for vol in scene.volumes:
        vol.show_outline = False
    scene.view.show_scale = False
    scene.view.show_time = args.time_label
    if not str(args.volume).lower().endswith(".svs") or args.camera is not None:
        bounds = scene.bounds()
        try:
            cam = make_camera(args.camera, bounds, args.view_angle)
        except CameraError as exc:
            raise RenderArgumentError(f"bad --camera: {exc}") from None
        scene.camera.update(position=cam.position, focal_point=cam.focal_point,
                            view_up=cam.view_up, view_angle=cam.view_angle)
    if args.volume_rendering is not None:
        _volume_rendering(scene, args)
    for text in args.clip or ():
        p = _floats(text, (6,), "--clip")
        scene.add_clip_plane(p[:3], p[3:])
    override(scene, renderer=args.renderer)
    chunked = _configure_bricks(scene, args)
    spec = model_spec(scene.isosurfaces[0].model)
    if spec.family is None:
        print(f"splineviz: note: model {spec.name!r} renders on the NumPy reference path "
              "(slow): it has no OpenCL kernel", file=sys.stderr)
    drawn_by = _renderers(scene, args.device)
    outputs = [(None, args.output)]
    if args.all_times:
        steps = scene.time_steps()
        outputs = list(enumerate(_frame_names(args.output, steps)))
    try:
        for step, output in outputs:
            if step is not None:
                scene.set_step(step)
            render_scene(scene, size, output, device=args.device)
            if step is not None:
                print(f"{output}: step {step}, time {scene.time:g}")
    finally:
        if chunked is not None:
            bar, saved = chunked
            bar.close()
            from splineviz.compute import bricked

            bricked.configure(**saved)
            bricked.close_clients()
    if args.measures:
        from splineviz.model.quantities import quantities_over_time

        steps = None if args.all_times or not scene.time_steps() else [scene.step_index()]
        quantities_over_time(scene, steps=steps).to_csv(args.measures)
        print(f"{args.measures}: area and enclosed volume of the isosurface"
              f"{' at each step' if args.all_times else ''}")
    iso = scene.isosurfaces[0]
    what = f"{len(outputs)} steps" if args.all_times else args.output
    print(f"{what}: {size[0]}x{size[1]}, iso {iso.isovalue:g}, model {iso.model}, "
          f"{drawn_by[0]}")
    return 0


def _renderers(scene, device) -> list[str]:
    """The renderer that draws each isosurface (:func:`~splineviz.core.renderers.
    choose_renderer`); its note, when it has one, goes to stderr."""
    from splineviz.compute.device import opencl_works
    from splineviz.core.renderers import CELL_PROJECTION, RAY_CASTING, choose_renderer
    from splineviz.render.cell_projection import MAX_CLIP_PLANES
    from splineviz.render.isosurface import not_projectable

    out = []
    for iso in scene.isosurfaces:
        choice = choose_renderer(iso.renderer, iso.model, iso.color_by, opencl_works(device),
                                 not_projectable(scene.volume_of(iso).active))
        note, renderer = choice.note, choice.renderer
        planes = [p for p in scene.clip_planes
                  if p.enabled and p.volume_id in (None, iso.volume_id)]
        if renderer == CELL_PROJECTION and len(planes) > MAX_CLIP_PLANES:
            # as the view decides (SplineScene.renderer_of)
            renderer = RAY_CASTING
            note = (f"cell projection takes at most {MAX_CLIP_PLANES} clip planes; "
                    f"{len(planes)} are ray cast")
        if note:
            print(f"splineviz: note: {iso.name}: {note}", file=sys.stderr)
        out.append(renderer)
    return out


def add_renderer_argument(parser) -> None:
    """``--renderer`` of ``render``, ``movie`` and the app (applied by
    :func:`splineviz.model.opening.override`)."""
    from splineviz.core.renderers import RENDERERS

    parser.add_argument("--renderer", default=None, metavar="|".join(RENDERERS),
                        help="what draws the isosurfaces: ray casting (OpenCL), cell "
                        "projection (OpenGL; the type-6 models super-quadratic and cubic-c1, "
                        "and to-quadratic), or auto: ray casting where an OpenCL device works, "
                        "else cell projection (default: auto, or the session's)")


def register(subparsers) -> None:
    """Add the ``render`` sub-command (see :mod:`splineviz.cli`)."""
    from splineviz.core.splines import MODELS

    p = subparsers.add_parser("render", help="ray cast a spline isosurface into a PNG",
                              description="Ray cast the isosurface of a spline model of a "
                              "volume (or render a session) into a PNG, without a display.")
    p.add_argument("volume", help="volume file (any format splineviz reads) or session")
    p.add_argument("--iso", type=finite_float, default=None,
                   help="isovalue (default: from the data, see splineviz.core.default_isovalue)")
    p.add_argument("--model", default=None,
                   help=" | ".join(MODELS) + " (default: cubic-c1, or the session's)")
    p.add_argument("--size", default="1024x768", help="image size WxH")
    p.add_argument("--series", metavar="UID|INDEX",
                   help="DICOM folders of several series: the one to render")
    p.add_argument("--camera", default=None,
                   help="px,py,pz[,fx,fy,fz[,ux,uy,uz]] eye [focal point [view up]] in world units")
    p.add_argument("--view-angle", type=float, default=30.0, help="vertical view angle, degrees")
    p.add_argument("--clip", action="append", metavar="OX,OY,OZ,NX,NY,NZ",
                   help="clip plane keeping the side its normal points to (repeatable)")
    add_renderer_argument(p)
    p.add_argument("--device", default=None, help="gpu | cpu | numpy | device-name substring "
                   "(default: $SPLINEVIZ_DEVICE, else GPU before CPU)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="chunked volumes (OME-Zarr, Zarr, HDF5): dask scheduler that renders "
                   "the bricks (default: $SPLINEVIZ_SCHEDULER, else a LocalCluster here)")
    p.add_argument("--workers", type=int, default=None,
                   help="chunked volumes: workers of the LocalCluster (default: one per core, "
                   "at most 4)")
    p.add_argument("-o", "--output", required=True, help="output PNG")
    p.add_argument("--allow-outside-data", action="store_true",
                   help="read data files that a header or session names outside its folder")
    p.add_argument("--channel", type=int, default=None,
                   help="multi-channel volumes: the channel to render (from 0)")
    p.add_argument("--oblique", choices=("direction", "resample", "error"), default=None,
                   help="a scan rotated against the world axes: show it in place with its "
                   "direction (default), resample it trilinearly onto axis-aligned axes, or "
                   "refuse it")
    p.add_argument("--time", default=None, metavar="T",
                   help="time-varying volumes (4-D files, a folder or a pattern such as "
                   "run_####.vti): the step to render, by index (0, -1) or by time with its "
                   "unit (2.5s, 250ms)")
    p.add_argument("--time-label", action="store_true",
                   help="draw the time step (t = 0.75 s (step 4/6)) in the upper-left corner "
                   "of a time-varying volume's pictures")
    p.add_argument("--all-times", action="store_true",
                   help="render every step, to -o with {t} (the step) in it, e.g. "
                   "frame_{t:04d}.png")
    p.add_argument("--measures", default=None, metavar="CSV",
                   help="also write the area and enclosed volume of the isosurface (from the "
                   "spline surface; at every step with --all-times) to a CSV file")
    p.add_argument("--volume-rendering", default=None, metavar="PRESET|TF.json",
                   help="direct volume rendering with a transfer function preset (ct-bone, "
                   "ct-soft-tissue, ct-lungs, mri, cryo-em) or a ParaView JSON colour-map "
                   "preset; the isosurface is drawn in it only when --iso is given")
    p.set_defaults(func=run)
