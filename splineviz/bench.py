"""``splineviz bench``: the benchmarks, each printing ratios against baselines run in the same
process (VTK flying edges and trilinear ray casting for ``raycast``; Open3D Poisson, ball
pivoting and Poisson + pymeshlab remeshing for ``remesh``)."""

from __future__ import annotations

from pathlib import Path


def _run(args) -> int:
    if args.which == "raycast":
        from splineviz.compute.bench import run_bench

        data = args.data_dir or str(Path.cwd() / ".." / "shared" / "data" / "volumes")
        w, h = (int(v) for v in args.size.lower().split("x"))
        run_bench(data, size=(w, h), repeats=args.repeats, device=args.device)
    else:
        from splineviz.pointcloud.bench import CLOUDS, run_bench

        clouds = tuple(args.clouds.split(",")) if args.clouds else CLOUDS
        run_bench(args.data_dir, clouds, args.timeout)
    return 0


def register(subparsers) -> None:
    """Add the ``bench`` sub-command."""
    p = subparsers.add_parser("bench", help="benchmarks printing ratios against baselines")
    p.add_argument("which", choices=["raycast", "remesh"], help="benchmark to run")
    p.add_argument("--data-dir", default=None,
                   help="data folder (default ../shared/data/volumes or ../shared/data/points)")
    p.add_argument("--size", default="512x512", help="raycast: image size WxH")
    p.add_argument("--repeats", type=int, default=3, help="raycast: frames per measurement")
    p.add_argument("--device", default=None, help="raycast: OpenCL device (see SPLINEVIZ_DEVICE)")
    p.add_argument("--timeout", type=float, default=180.0, help="remesh: seconds per peer run")
    p.add_argument("--clouds", default=None,
                   help="remesh: comma-separated clouds (bunny,kitten,bunny-noisy,bunny-open)")
    p.set_defaults(func=_run)
