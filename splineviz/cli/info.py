"""``splineviz info FILE``: what a volume, point, mesh or session file holds
(:func:`splineviz.io.describe.describe`)."""

from __future__ import annotations

import os
from pathlib import Path

from splineviz.io.describe import describe, format_info


def register(subparsers) -> None:
    """Add the ``info`` sub-command (cli.SUBCOMMANDS)."""
    p = subparsers.add_parser("info", help="what a file holds (dims, dtype, range, spacing)")
    p.add_argument("file", help="volume, point cloud, mesh or session file (or DICOM folder)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.add_argument("--dims", type=int, nargs=3, metavar=("NX", "NY", "NZ"),
                   help="raw volumes: samples per axis (x fastest)")
    p.add_argument("--dtype", help="raw volumes: sample type, e.g. uint8, int16, float32")
    p.add_argument("--byteorder", choices=("little", "big"), default=None,
                   help="raw volumes: byte order (default little)")
    p.add_argument("--offset", type=int, default=None, help="raw volumes: header bytes to skip")
    p.add_argument("--allow-outside-data", action="store_true",
                   help="read data files that a header or session names outside its folder")
    p.add_argument("--series", metavar="UID|INDEX",
                   help="DICOM folders of several series: the one to describe")
    p.add_argument("--channel", type=int, default=None,
                   help="multi-channel volumes: the channel to describe (from 0)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    import json

    from splineviz.io.dicom import describe_series, series_file

    path = Path(os.fspath(args.file))
    listed = describe_series(path) if args.series is None else None
    if listed is not None:  # several DICOM series: list them
        rest = format_info({k: v for k, v in listed.items() if k != "series"})
        print(json.dumps(listed, indent=2) if args.json else "\n".join(
            [rest, *(f"{'series':>15}: {s}" for s in listed["series"])]))
        return 0
    from splineviz.io.time_series import series_files, series_info

    files = series_files(path) if args.series is None else None
    info = describe(path if files is None and args.series is None else
                    files[0] if files is not None else series_file(path, args.series),
                    dims=args.dims, dtype=args.dtype,
                    byteorder=args.byteorder, offset=args.offset,
                    allow_outside=args.allow_outside_data, channel=args.channel)
    if files is not None or "frames" in info or info.get("format") == "ome-zarr":
        # time steps (a 4-D file's, a series', an OME-Zarr t axis'): how many, and when
        info.update(series_info(path if files is not None else info["file"],
                                channel=args.channel,
                                allow_outside=args.allow_outside_data) or {})
    print(json.dumps(info, indent=2) if args.json else format_info(info))
    return 0
