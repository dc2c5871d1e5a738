"""``splineviz render``: ray cast an isosurface of a volume file into a PNG.

The PNG is written by a small pure-Python encoder (zlib), so this command needs neither VTK
nor a display.
"""

from __future__ import annotations

import struct
import sys
import zlib

import numpy as np

from splineviz.core.camera import Camera, CameraError, parse_size
from splineviz.core.errors import SplinevizError


class RenderArgumentError(SplinevizError, ValueError):
    """A malformed ``--camera`` or ``--clip`` argument."""


def write_png(path, rgba: np.ndarray) -> None:
    """Write an ``(H, W, 4)`` uint8 image as an 8-bit RGBA PNG (filter type 0 per row)."""
    img = np.ascontiguousarray(rgba, dtype=np.uint8)
    if img.ndim != 3 or img.shape[2] != 4:
        raise ValueError(f"write_png needs an (H, W, 4) image, got shape {img.shape}")
    h, w, _ = img.shape
    raw = np.concatenate([np.zeros((h, 1), np.uint8), img.reshape(h, w * 4)], axis=1)

    def chunk(tag: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    with open(path, "wb") as fh:
        fh.write(b"\x89PNG\r\n\x1a\n")
        fh.write(chunk(b"IHDR", header))
        fh.write(chunk(b"IDAT", zlib.compress(raw.tobytes(), 6)))
        fh.write(chunk(b"IEND", b""))


def _floats(text: str, counts, what: str) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise RenderArgumentError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if len(vals) not in counts or not np.all(np.isfinite(vals)):
        raise RenderArgumentError(
            f"{what} needs {' or '.join(map(str, counts))} finite numbers, got {text!r}")
    return vals


def default_camera(bounds, view_angle: float = 30.0, direction=(1.0, -1.3, 0.8)) -> Camera:
    """An oblique view of the whole box ``bounds`` (fills about the frame height)."""
    b = np.asarray(bounds, dtype=np.float64)
    c = b.mean(axis=1)
    radius = 0.5 * np.linalg.norm(b[:, 1] - b[:, 0])
    d = np.asarray(direction, dtype=np.float64)
    d /= np.linalg.norm(d)
    dist = radius / np.sin(np.radians(view_angle) / 2.0) * 1.05
    return Camera(c + dist * d, c, view_up=(0, 0, 1), view_angle=view_angle)


def make_camera(spec: str | None, bounds, view_angle: float) -> Camera:
    """Camera from ``--camera``: ``px,py,pz`` (looks at the box centre), ``+focal`` (6
    numbers) or ``+view up`` (9 numbers); ``None`` gives :func:`default_camera`."""
    if spec is None:
        return default_camera(bounds, view_angle)
    v = _floats(spec, (3, 6, 9), "--camera")
    focal = v[3:6] if len(v) >= 6 else np.asarray(bounds, float).mean(axis=1)
    up = v[6:9] if len(v) == 9 else (0, 0, 1)
    return Camera(v[:3], focal, view_up=up, view_angle=view_angle)


def run(args) -> int:
    from splineviz.compute.raycast import RayCaster
    from splineviz.io.volumes import read_volume

    vol = read_volume(args.volume)
    lo, hi = vol.finite_range
    iso = 0.5 * (lo + hi) if args.iso is None else args.iso
    size = parse_size(args.size)
    try:
        cam = make_camera(args.camera, vol.bounds, args.view_angle)
    except CameraError as exc:
        raise RenderArgumentError(f"bad --camera: {exc}") from None
    planes = []
    for text in args.clip or ():
        p = _floats(text, (6,), "--clip")
        planes.append((p[:3], p[3:]))
    rc = RayCaster(vol, model=args.model, device=args.device)
    if rc.stats["path"] == "numpy":
        from splineviz.compute.raycast import KERNEL_MODELS

        why = ("no OpenCL device" if args.model in KERNEL_MODELS
               else f"OpenCL kernels exist for {', '.join(sorted(KERNEL_MODELS))} only")
        print(f"splineviz: note: model {args.model!r} renders on the NumPy reference path "
              f"(slow): {why}", file=sys.stderr)
    rc.set_isovalue(iso)
    frame = rc.render(cam, size, clip_planes=planes)
    write_png(args.output, frame.color)
    s = rc.stats
    # the frame classifies the cells its rays reach (visible-first): counts of those
    active = "" if s["active_cells"] is None else f", {s['active_cells']} active cells reached"
    print(f"{args.output}: {size[0]}x{size[1]}, iso {iso:g}, model {args.model}, "
          f"{int(frame.hit.sum())} hit pixels{active}, "
          f"classify {s['classify_s']:.3f} s, render {s['render_s']:.3f} s on {s['device']}")
    return 0


def register(subparsers) -> None:
    """Add the ``render`` sub-command (see :mod:`splineviz.cli`)."""
    p = subparsers.add_parser("render", help="ray cast a spline isosurface into a PNG",
                              description="Ray cast the isosurface of a spline model of a volume.")
    p.add_argument("volume", help="volume file (any format splineviz reads)")
    p.add_argument("--iso", type=float, default=None, help="isovalue (default: mid-range)")
    p.add_argument("--model", default="cubic-c1",
                   help="trilinear | super-quadratic | cubic-c1 | to-quadratic")
    p.add_argument("--size", default="1024x768", help="image size WxH")
    p.add_argument("--camera", default=None,
                   help="px,py,pz[,fx,fy,fz[,ux,uy,uz]] eye [focal point [view up]] in world units")
    p.add_argument("--view-angle", type=float, default=30.0, help="vertical view angle, degrees")
    p.add_argument("--clip", action="append", metavar="OX,OY,OZ,NX,NY,NZ",
                   help="clip plane keeping the side its normal points to (repeatable)")
    p.add_argument("--device", default=None, help="gpu | cpu | numpy | device-name substring "
                   "(default: $SPLINEVIZ_DEVICE, else GPU before CPU)")
    p.add_argument("-o", "--output", required=True, help="output PNG")
    p.set_defaults(func=run)
