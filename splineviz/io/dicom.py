"""DICOM volumes read with pydicom."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from splineviz.io._util import MIN_SAMPLES_PER_AXIS, check_volume_size, confined
from splineviz.io.errors import CorruptFileError, FileFormatError, InvalidDataError
from splineviz.io.registry import register_format


def _read_dicom_folder(path: Path):
    """A DICOM series folder with pydicom: slices sorted by their position along the slice
    normal (ImageOrientationPatient), RescaleSlope/RescaleIntercept applied, spacing from
    PixelSpacing and the slice positions, origin = ImagePositionPatient of the first slice.
    Files that are not DICOM are skipped; with several series the largest is read."""
    import pydicom
    from pydicom.errors import InvalidDicomError

    headers = []
    for f in sorted(p for p in path.iterdir() if p.is_file()):
        # a symbolic link in the series folder must not pull in a file from elsewhere
        confined(f.name, path / f.name, what="DICOM file", folder=path)
        try:
            ds = pydicom.dcmread(str(f), stop_before_pixels=True)
        except (InvalidDicomError, EOFError, OSError, ValueError, TypeError, KeyError):
            continue
        if "Rows" in ds and "Columns" in ds:
            headers.append((f, ds))
    if not headers:
        raise InvalidDataError(f"folder {path.name} holds no DICOM images")
    series: dict[str, list] = {}
    for f, ds in headers:
        series.setdefault(str(ds.get("SeriesInstanceUID", "")), []).append((f, ds))
    slices = max(series.values(), key=len)
    if len(slices) < MIN_SAMPLES_PER_AXIS:
        raise InvalidDataError(
            f"folder {path.name} holds {len(slices)} DICOM slice; a volume needs at least "
            f"{MIN_SAMPLES_PER_AXIS}"
        )
    rows, cols = int(slices[0][1].Rows), int(slices[0][1].Columns)
    if any((int(ds.Rows), int(ds.Columns)) != (rows, cols) for _, ds in slices):
        raise InvalidDataError(f"the DICOM slices in {path.name} differ in size")
    try:
        iop = np.asarray(slices[0][1].get("ImageOrientationPatient", [1, 0, 0, 0, 1, 0]), float)
        normal = np.cross(iop[:3], iop[3:])
        pos = np.array([np.asarray(ds.get("ImagePositionPatient", [0, 0, i]), float)
                        for i, (_, ds) in enumerate(slices)])
    except (ValueError, TypeError) as exc:
        raise CorruptFileError(f"DICOM geometry in {path.name} is malformed: {exc}") from None
    depth = pos @ normal
    order = np.argsort(depth, kind="stable")
    if np.allclose(depth, depth[0]):  # no usable positions: fall back to InstanceNumber
        order = np.argsort([int(ds.get("InstanceNumber", i)) for i, (_, ds) in
                            enumerate(slices)], kind="stable")
        dz = float(slices[0][1].get("SliceThickness", 1.0) or 1.0)
    else:
        steps = np.diff(depth[order])
        if np.any(steps <= 0):
            raise InvalidDataError(f"{path.name} holds two DICOM slices at the same position")
        dz = float(np.median(steps))
        if np.max(np.abs(steps - dz)) > 1e-3 * max(dz, 1e-12) + 1e-4:
            raise InvalidDataError(f"the DICOM slices in {path.name} are not evenly spaced")
    check_volume_size((cols, rows, len(slices)), 4, path.name)
    out = np.empty((cols, rows, len(slices)), dtype=np.float32)
    for k, idx in enumerate(order):
        f = slices[idx][0]
        try:
            ds = pydicom.dcmread(str(f))
            px = ds.pixel_array.astype(np.float32)
        except Exception as exc:  # noqa: BLE001 - pixel handlers raise many types
            ts = getattr(getattr(ds, "file_meta", None), "TransferSyntaxUID", None) \
                if "ds" in locals() else None
            if ts is not None and getattr(ts, "is_compressed", False):
                raise FileFormatError(
                    f"{f.name} uses the compressed transfer syntax {ts.name}; install a "
                    "pydicom pixel handler for it (e.g. pylibjpeg or gdcm)") from None
            raise CorruptFileError(f"cannot decode the pixels of {f.name}: {exc}") from None
        if px.shape != (rows, cols):
            raise CorruptFileError(f"{f.name} holds pixels of shape {px.shape}, "
                                   f"expected {(rows, cols)}")
        slope = float(ds.get("RescaleSlope", 1.0) or 1.0)
        inter = float(ds.get("RescaleIntercept", 0.0) or 0.0)
        out[:, :, k] = (px * slope + inter).T  # pixel_array is [row, column]; x runs along
    ps = slices[0][1].get("PixelSpacing", [1.0, 1.0])
    spacing = (float(ps[1]), float(ps[0]), dz)  # PixelSpacing is (row step, column step)
    origin = tuple(float(v) for v in pos[order[0]])
    # the volume is axis-aligned; an oblique series keeps its orientation in meta only
    from splineviz.io.volumes import VolumeData

    return VolumeData(out, spacing, origin, "dicom",
                      {"series": str(slices[0][1].get("SeriesInstanceUID", "")),
                       "orientation": [float(v) for v in iop]})


register_format("dicom", (), _read_dicom_folder, None, kind="volume", folder=True,
                description="DICOM series folder")
