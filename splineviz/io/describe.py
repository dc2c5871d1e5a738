"""What a volume, point, mesh or session file holds (dims, sample type, range, spacing, affine,
frames): :func:`describe` and its text form :func:`format_info`, which ``splineviz info``
prints."""

from __future__ import annotations

import numpy as np

from splineviz.io.errors import UnknownFormatError


def describe(path, *, allow_outside: bool = False, channel=None, **raw) -> dict:
    """Summary of a file: kind, format and geometry.

    Parameters
    ----------
    path : path-like
    allow_outside : bool
        Accept data files that a header or session names outside its own folder.
    channel : int, optional
        The channel of a multi-channel volume file to describe.
    **raw
        ``dims``, ``dtype``, ``byteorder``, ``offset`` for headerless raw volumes.

    Returns
    -------
    dict
        For volumes: ``kind, format, dims, dtype, range, spacing, origin, bounds, affine``
        (index to world, the file's own axes; with ``space``, ``unit`` (of lengths),
        ``values`` (the unit of the samples) and ``frames`` where the file has them,
        ``oblique`` and ``direction`` for a rotated grid); for points:
        ``kind, format, points, normals, colors, bounds``; for sessions: ``kind,
        schema_version, objects, views``.
    """
    from splineviz.io._util import regular_input
    from splineviz.io.points import load_point_data, validate_point_data
    from splineviz.io.session import load_session
    from splineviz.io.volumes import load_volume_data, validate_volume_data

    p = regular_input(path, allow_dir=True, allow_pattern=True)
    if p.suffix.lower() == ".svs":
        s = load_session(p, check_data=False, allow_outside=allow_outside)
        return {"kind": "session", "file": str(p), "schema_version": s.schema_version,
                "objects": [f"{o.id} ({o.type})" for o in s.objects],
                "views": [v.id for v in s.views]}
    try:
        vd = load_volume_data(p, allow_outside=allow_outside, channel=channel,
                              **{k: v for k, v in raw.items() if v is not None})
    except UnknownFormatError:
        try:
            raw = load_point_data(p)
        except UnknownFormatError:
            from splineviz.io.registry import formats

            names = ", ".join(f.name for k in ("volume", "points") for f in formats(k))
            raise UnknownFormatError(f"cannot tell the format of {p.name}; readable formats: "
                                     f"{names}") from None
        pd = validate_point_data(raw, p.name, dedupe=False)
        lo, hi = pd.points.min(axis=0), pd.points.max(axis=0)
        return {"kind": "points", "file": str(p), "format": pd.format,
                "points": int(len(pd.points)), "normals": pd.normals is not None,
                "colors": pd.colors is not None,
                "bounds": [[float(a), float(b)] for a, b in zip(lo, hi, strict=True)]}
    validate_volume_data(vd, p.name)
    from splineviz.io.chunked import is_lazy

    if is_lazy(vd.data):
        return {**_describe_chunked(vd, p), **_geometry(vd, p.name, channel)}
    data = np.asarray(vd.data)
    finite = np.isfinite(data) if data.dtype.kind == "f" else None
    vals = data[finite] if finite is not None else data
    rng = [float(vals.min()), float(vals.max())] if vals.size else None
    shape = tuple(int(n) for n in data.shape)
    return {"kind": "volume", "file": str(p), "format": vd.format, "dims": list(shape),
            "dtype": str(data.dtype), "range": rng,
            "nonfinite": int(data.size - finite.sum()) if finite is not None else 0,
            "spacing": [float(s) for s in vd.spacing], "origin": [float(o) for o in vd.origin],
            "bounds": [[o, o + (n - 1) * s] for o, n, s in zip(vd.origin, shape, vd.spacing,
                                                              strict=True)],
            **_geometry(vd, p.name, channel)}


def _geometry(vd, name: str, channel) -> dict:
    """The index-to-world affine, its space, the world bounds of the grid's corners (the
    affine may reorder, reverse and rotate axes), the direction an oblique grid keeps, the
    unit of the values where the reader knows it, and the frames of a 4-D file."""
    from splineviz.io.geometry import orientation
    from splineviz.io.volume_data import select_frames

    shape = vd.data.shape[:3]
    corners = np.array(np.meshgrid(*[[0, n - 1] for n in shape], indexing="ij")).reshape(3, -1)
    world = vd.affine[:3, :3] @ corners + vd.affine[:3, 3:4]
    out = {"bounds": [[float(lo), float(hi)] for lo, hi in zip(world.min(axis=1),
                                                               world.max(axis=1), strict=True)],
           "affine": [[float(v) for v in row] for row in vd.affine]}
    if vd.meta.get("value_unit"):  # what the samples measure (DICOM: Gy, relative dose, HU)
        dose = vd.meta.get("dose")
        out["values"] = str(vd.meta["value_unit"]) + (f" (RT dose, {dose})" if dose else "")
    if vd.space:
        out["space"] = vd.space
    if vd.meta.get("length_unit"):  # of spacing, origin and bounds, where the file says
        out["unit"] = vd.meta["length_unit"]
    orient = orientation(vd.affine, shape, name)
    if orient.oblique and orient.sheared:
        out["oblique"] = ("sheared (axes not perpendicular): resampled onto axis-aligned "
                          "axes when read")
    elif orient.oblique:
        out["oblique"] = (f"rotated by {orient.angle:.3g} degrees: shown in place with its "
                          "direction (--oblique resample resamples it when it fits in memory)")
        # the rotation the volume keeps, after the transpose and flips (world = origin +
        # direction @ (i*sx, j*sy, k*sz) of the reordered grid)
        out["direction"] = [[float(v) for v in row] for row in orient.rotation]
    if vd.frames is not None:
        sel = select_frames(vd.frames, name, channel)
        unit = f" ({sel.axis.unit})" if sel.axis.unit else ""
        out["frames"] = f"{len(sel.indices)} along {sel.axis.name}{unit}"
        if sel.channels:
            out["channel"] = f"{sel.channel} of {sel.channels}"
    return out


def _describe_chunked(vd, p) -> dict:
    """A chunked volume from its metadata alone: no sample is read (the range is unknown
    until the data are read: ``"not read"``)."""
    shape = tuple(int(n) for n in vd.data.shape)
    levels = [list(shape)] + [list(lv.shape) for lv in vd.meta.get("levels", ())]
    return {"kind": "volume", "file": str(p), "format": vd.format, "dims": list(shape),
            "dtype": str(vd.data.dtype), "range": "not read (chunked)",
            "chunks": [int(max(c)) for c in vd.data.chunks],
            "levels": " ".join("x".join(map(str, lv)) for lv in levels),
            "spacing": [float(s) for s in vd.spacing], "origin": [float(o) for o in vd.origin],
            "bounds": [[o, o + (n - 1) * s] for o, n, s in zip(vd.origin, shape, vd.spacing,
                                                              strict=True)]}


def format_info(info: dict) -> str:
    """Human-readable lines for :func:`describe`'s dict."""
    lines = []
    for key, val in info.items():
        if isinstance(val, list) and val and isinstance(val[0], list) and len(val[0]) != 2:
            val = "  ".join("[" + " ".join(f"{v:g}" for v in row) + "]" for row in val)
        elif isinstance(val, list) and val and isinstance(val[0], list):
            val = "  ".join(f"[{a:g}, {b:g}]" for a, b in val)
        elif isinstance(val, list) and val and isinstance(val[0], float):
            val = " ".join(f"{v:g}" for v in val)
        elif isinstance(val, list):
            val = " ".join(str(v) for v in val)
        lines.append(f"{key:>15}: {val}")
    return "\n".join(lines)
