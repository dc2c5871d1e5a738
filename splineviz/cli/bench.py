"""``splineviz bench``: the benchmarks of :mod:`splineviz.bench`, each printing ratios against
baselines run in the same run (VTK flying edges and trilinear ray casting for ``raycast``;
flying edges + an offscreen render of its mesh for ``isovalue``; 1 against 2 dask workers for
``bricks``; Open3D Poisson, ball pivoting and Poisson + pymeshlab remeshing for ``remesh``;
the 100 ms budget of the GUI thread for ``gui``; reading + flying edges + render of each step
for ``time``; VTK's volume mappers and an analytic reference for ``dvr``; one still
``render_scene`` picture and the renderer and encoder alone for ``movie``; cell projection
against the ray caster over surface sizes for ``renderers``; flying edges and flying edges +
pymeshlab remeshing for ``spline-mesh``; Open3D screened Poisson, density-trimmed, on
simulated range scans of parts with creases for ``cad-scans``)."""

from __future__ import annotations

from pathlib import Path

from splineviz.cli.render import finite_float
from splineviz.core.errors import SplinevizError


def _run(args) -> int:
    data = args.data_dir or str(Path.cwd() / ".." / "shared" / "data" / "volumes")
    w, h = (int(v) for v in args.size.lower().split("x"))
    if args.which == "raycast":
        from splineviz.bench.raycast import run_bench

        run_bench(data, size=(w, h), repeats=args.repeats, device=args.device)
    elif args.which == "isovalue":
        from splineviz.bench.isovalue import MODELS, run_isovalue_bench

        pw, ph = (int(v) for v in args.preview.lower().split("x"))
        sizes = tuple(int(n) for n in (args.sizes or "256,512").split(","))
        models = tuple(args.models.split(",")) if args.models else MODELS
        run_isovalue_bench(data, sizes=sizes, models=models, size=(w, h), preview=(pw, ph),
                           device=args.device, timeout=args.timeout or 600.0)
    elif args.which == "bricks":
        from splineviz.bench.bricks import run_bricks_bench

        workers = tuple(int(n) for n in args.workers.split(","))
        model = args.models.split(",")[0] if args.models else "cubic-c1"
        run_bricks_bench(n=args.n or 512, model=model, size=(w, h), brick=args.brick,
                         workers=workers, device=args.device)
    elif args.which == "time":
        from splineviz.bench.time import MODELS, run_time_bench

        pw, ph = (int(v) for v in args.preview.lower().split("x"))
        models = tuple(args.models.split(",")) if args.models else MODELS
        run_time_bench(n=args.n or 256, steps=args.steps, models=models, size=(w, h),
                       preview=(pw, ph), device=args.device, timeout=args.timeout or 900.0)
    elif args.which == "dvr":
        from splineviz.bench.dvr import run_dvr_bench

        sizes = tuple(int(n) for n in (args.sizes or "256,512").split(","))
        run_dvr_bench(data, size=(w, h), step=args.step, repeats=args.repeats,
                      device=args.device, out_dir=args.out, volume_sizes=sizes)
    elif args.which == "movie":
        from splineviz.bench.movie import SIZES, run_movie_bench

        labels = [v.strip() for v in args.sizes.split(",")] if args.sizes else None
        sizes = [s for s in SIZES if labels is None or s[0] in labels]
        if labels is not None and len(sizes) != len(labels):
            from splineviz.cli import UsageError

            raise UsageError(f"bench movie: --sizes takes {','.join(s[0] for s in SIZES)}, "
                             f"got {args.sizes!r}")
        run_movie_bench(data, sizes=sizes, frames=args.frames, device=args.device)
    elif args.which == "renderers":
        from splineviz.bench.renderers import SIZES, run_renderers_bench

        sizes = tuple(int(n) for n in args.sizes.split(",")) if args.sizes else SIZES
        model = args.models.split(",")[0] if args.models else "cubic-c1"
        run_renderers_bench(sizes=sizes, model=model, size=(w, h), repeats=args.repeats,
                            device=args.device)
    elif args.which == "spline-mesh":
        from splineviz.bench.spline_mesh import SETS, run

        sets = args.sets.split(",") if args.sets else ["tooth", "bonsai"]
        unknown = [name for name in sets if name not in SETS]
        if unknown:
            raise SplinevizError(f"unknown spline-mesh set {unknown[0]!r}; choose from "
                                 f"{', '.join(SETS)}")
        model = args.models.split(",")[0] if args.models else "cubic-c1"
        for name in sets:
            run(Path(data), name, model)
    elif args.which == "cad-scans":
        from splineviz.bench.cad_scans import NOISES, SHAPES
        from splineviz.bench.cad_scans import run_bench as run_cad

        shapes = tuple(args.shapes.split(",")) if args.shapes else SHAPES
        unknown = [name for name in shapes if name not in SHAPES]
        if unknown:
            raise SplinevizError(f"unknown cad-scans shape {unknown[0]!r}; choose from "
                                 f"{', '.join(SHAPES)}")
        try:
            noises = tuple(float(n) for n in args.noises.split(",")) if args.noises else NOISES
        except ValueError:
            raise SplinevizError(f"--noises takes comma-separated fractions of the diagonal "
                                 f"(0,0.0025,0.005), got {args.noises!r}") from None
        run_cad(shapes, noises, args.points, args.timeout or 300.0, pictures=args.out)
    elif args.which == "gui":
        from splineviz.bench.gui import run_gui_bench

        clouds = args.clouds.split(",") if args.clouds else ["kitten.xyz"]
        run_gui_bench(args.data_dir, volume=args.volume, points=clouds[0], iso=args.iso,
                      repeats=args.repeats)
    else:
        from splineviz.bench.remesh import CLOUDS, run_bench

        clouds = tuple(args.clouds.split(",")) if args.clouds else CLOUDS
        run_bench(args.data_dir, clouds, args.timeout or 180.0)
    return 0


def register(subparsers) -> None:
    """Add the ``bench`` sub-command."""
    p = subparsers.add_parser("bench", help="benchmarks printing ratios against baselines")
    p.add_argument("which", choices=["raycast", "isovalue", "bricks", "remesh", "gui", "time",
                                     "dvr", "movie", "renderers", "spline-mesh", "cad-scans"],
                   help="benchmark to run")
    p.add_argument("--data-dir", default=None,
                   help="data folder (default ../shared/data/volumes or ../shared/data/points; "
                        "gui: ../shared/data)")
    p.add_argument("--size", default="512x512",
                   help="raycast, isovalue: image size WxH; dvr: that and twice its side")
    p.add_argument("--preview", default="128x128", help="isovalue: preview frame size WxH")
    p.add_argument("--sizes", default=None,
                   help="isovalue, dvr: volume sizes n (bonsai resampled to n^3), "
                        "comma-separated (256,512); "
                        "movie: frame sizes among 720p,1080p,4K (default all); "
                        "renderers: sphere volume sizes n (16,32,64,128,256,512)")
    p.add_argument("--frames", type=int, default=4, help="movie: frames per size")
    p.add_argument("--models", default=None,
                   help="isovalue, time: comma-separated spline models (default: all four)")
    p.add_argument("--repeats", type=int, default=3,
                   help="raycast: frames per measurement; gui: measurements per action")
    p.add_argument("--n", type=int, default=None,
                   help="bricks: samples per axis of the lazy gyroid (default 512; 2048: 32 GiB "
                   "as float32); time: samples per axis of each step (default 256)")
    p.add_argument("--steps", type=int, default=20, help="time: steps of the series")
    p.add_argument("--brick", type=int, default=128, help="bricks: cells per brick and axis")
    p.add_argument("--workers", default="1,2",
                   help="bricks: LocalCluster sizes to compare, comma-separated")
    p.add_argument("--device", default=None,
                   help="raycast, isovalue: OpenCL device (see SPLINEVIZ_DEVICE)")
    p.add_argument("--timeout", type=float, default=None,
                   help="remesh: seconds per peer run (180); cad-scans: per method (300); "
                        "isovalue: per measurement (600)")
    p.add_argument("--clouds", default=None,
                   help="remesh: comma-separated clouds (bunny,kitten,bunny-noisy,bunny-open; "
                        "dense samples of a shared mesh with noise: lucy-2m,bunny-500k); "
                        "gui: the point cloud file to open and remesh (kitten.xyz)")
    p.add_argument("--volume", default=None,
                   help="gui: volume file in the data folder's volumes/ (default: the embedded "
                        "default data)")
    p.add_argument("--sets", default=None,
                   help="spline-mesh: comma-separated sets (tooth,bonsai; bonsai-crop: 40^3)")
    p.add_argument("--shapes", default=None,
                   help="cad-scans: comma-separated shapes (box-cylinder,bracket,airplane)")
    p.add_argument("--noises", default=None,
                   help="cad-scans: scanner noise levels in fractions of the diagonal "
                        "(0,0.0025,0.005)")
    p.add_argument("--points", type=int, default=40000,
                   help="cad-scans: points of each merged scan")
    p.add_argument("--iso", type=finite_float, default=None, help="gui: isovalue of --volume")
    p.add_argument("--step", type=finite_float, default=0.5,
                   help="dvr: sample distance along the rays in voxels")
    p.add_argument("--out", default=None,
                   help="dvr: folder for the pictures; cad-scans: folder for each mesh and "
                        "cloud (.npz)")
    p.set_defaults(func=_run)
