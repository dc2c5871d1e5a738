"""``splineviz remesh POINTS -o mesh.ply [--edge-length L | --rho R] [--no-sharp-creases]
[--report report.json]``.

Reads a point cloud, runs :func:`~splineviz.pointcloud.remesh.remesh` with a tqdm progress bar
on stderr, writes the mesh, and optionally a JSON report (parameters, stage timings, front
events and :func:`~splineviz.pointcloud.quality.mesh_quality` against the input points).
"""

from __future__ import annotations

import json
import math
import os
import sys


def _positive(text: str) -> float:
    import argparse

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _json_safe(value):
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return _json_safe(value.item())
    return value


def run(args) -> int:
    """Execute the ``remesh`` sub-command; returns the exit code."""
    from tqdm import tqdm

    from splineviz.io.meshes import write_mesh
    from splineviz.io.points import read_points
    from splineviz.pointcloud.quality import mesh_quality
    from splineviz.pointcloud.remesh import RemeshReport, remesh

    cloud = read_points(args.points)
    report = RemeshReport()
    bar = tqdm(total=1000, desc="remesh", unit="‰", file=sys.stderr,
               disable=args.quiet or None, bar_format="{desc}: {percentage:3.0f}%|{bar}| "
               "{elapsed}<{remaining} {postfix}")

    def progress(fraction, message):
        bar.n = int(1000 * fraction)
        bar.set_postfix_str(message, refresh=False)
        bar.refresh()
        return True

    try:
        mesh = remesh(cloud, edge_length=args.edge_length, rho=args.rho, progress=progress,
                      min_length=args.min_length, max_length=args.max_length,
                      smoothing=args.smoothing, optimize_mesh=not args.no_optimize,
                      sharp_creases=not args.no_sharp_creases, report=report)
    finally:
        bar.close()
    if report.front.get("truncated"):
        print("splineviz: warning: the advancing front overlapped itself and was stopped; "
              "the mesh is incomplete", file=sys.stderr)
    out = write_mesh(args.output, mesh)
    quality = mesh_quality(mesh, reference=cloud)
    summary = {
        "input": os.fspath(args.points),
        "output": os.fspath(out),
        "n_points": len(cloud),
        "parameters": report.parameters,
        "timings": report.timings,
        "front": report.front,
        "flips": report.flips,
        "quality": quality,
    }
    if args.report:
        from splineviz.io._util import atomic_write_bytes

        # through the atomic writer: a failed write keeps an earlier report intact
        atomic_write_bytes(args.report, (json.dumps(_json_safe(summary), indent=2) + "\n")
                           .encode("utf-8"))
    if not args.quiet:
        print(f"{quality['n_vertices']} vertices, {quality['n_faces']} triangles, "
              f"radius ratio {quality['radius_ratio_mean']:.3f}, "
              f"valence 6 {100 * quality['valence6_fraction']:.1f} %, "
              f"Hausdorff {quality['hausdorff']:.4g}, {report.timings['total_s']:.1f} s "
              f"-> {out}")
    return 0


def register(subparsers) -> None:
    """Add the ``remesh`` sub-command."""
    p = subparsers.add_parser(
        "remesh", help="triangulate a point cloud (advancing front, thesis ch. 7)",
        description="Build a near-equilateral, curvature-adapted triangle mesh of a point "
                    "cloud and write it as PLY/OBJ/STL/VTP.")
    p.add_argument("points", help="point cloud (PLY, XYZ, PCD, OBJ/OFF/STL vertices)")
    p.add_argument("-o", "--output", required=True, help="mesh file to write")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--edge-length", type=_positive, default=None,
                      help="uniform target edge length (world units)")
    size.add_argument("--rho", type=_positive, default=None,
                      help="curvature adaptation angle in radians (default 0.35)")
    p.add_argument("--min-length", type=_positive, default=None,
                   help="smallest adaptive edge length (default 1.5 x median spacing)")
    p.add_argument("--max-length", type=_positive, default=None,
                   help="largest adaptive edge length (default 5 x median spacing)")
    p.add_argument("--smoothing", type=_positive, default=None,
                   help="fixed width of the local fits in spacings (default: chosen per "
                        "point from the noise in the data)")
    p.add_argument("--no-optimize", action="store_true",
                   help="skip the valence flips and tangential relaxation")
    p.add_argument("--no-sharp-creases", action="store_true",
                   help="round the sharp edges of scanned parts like the rest of the surface "
                        "(default: vertices put on them, edges along them)")
    p.add_argument("--report", default=None, help="write a JSON report here")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)
