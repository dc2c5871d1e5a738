"""``splineviz serve``: the interactive view of a file or session as a web page on 127.0.0.1.

The scene is built as for ``splineviz render`` (:mod:`splineviz.model.opening`; no argument:
the embedded default data) and served by :class:`splineviz.web.server.ViewServer`: drag to
orbit, wheel to zoom, an isovalue slider, the model, a clip plane and colour-by. From another
machine, forward the port over SSH (``ssh -L 8890:127.0.0.1:8890 host``).
"""

from __future__ import annotations

import sys

#: the port served when none is given (``--port 0``: any free one)
DEFAULT_PORT = 8890


def run(args) -> int:
    from splineviz.core.camera import parse_size
    from splineviz.model.opening import default_scene, override, scene_from_path
    from splineviz.web.server import serve_forever

    size = parse_size(args.size)
    if args.file is None:
        scene = default_scene()
        override(scene, isovalue=args.iso, model=args.model)
    else:
        scene = scene_from_path(args.file, isovalue=args.iso, model=args.model,
                                allow_outside=args.allow_outside_data)

    def ready(url):
        print(f"splineviz: serving {url} (Ctrl-C to stop)", flush=True)

    try:
        serve_forever(scene, size=size, port=args.port, device=args.device, ready=ready)
    except KeyboardInterrupt:
        print("splineviz: stopped", file=sys.stderr)
    return 0


def register(subparsers) -> None:
    """Add the ``serve`` sub-command (see :mod:`splineviz.cli`)."""
    from splineviz.cli.render import finite_float

    p = subparsers.add_parser("serve", help="the interactive view as a web page on 127.0.0.1",
                              description="Serve the interactive view of a volume, point "
                              "cloud or session (default: the embedded default data) as a web "
                              "page on 127.0.0.1.")
    p.add_argument("file", nargs="?", default=None, help="volume, point cloud or session")
    p.add_argument("--port", type=int, default=DEFAULT_PORT,
                   help=f"port on 127.0.0.1 (default {DEFAULT_PORT}; 0: any free port)")
    p.add_argument("--size", default="640x480", help="view size WxH")
    p.add_argument("--iso", type=finite_float, default=None, help="isovalue")
    p.add_argument("--model", default=None, help="spline model")
    p.add_argument("--device", default=None, help="gpu | cpu | numpy | device-name substring")
    p.add_argument("--allow-outside-data", action="store_true",
                   help="read data files that a header or session names outside its folder")
    p.set_defaults(func=run)
