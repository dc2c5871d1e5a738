"""Shared helpers of the ray-casting tests: data loading, cameras and the acceptance metrics
of issue 4 (kernel frame vs. NumPy reference frame)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from splineviz.compute import device as _devmod
from splineviz.core.camera import Camera
from splineviz.core.volume import Volume


def _have_opencl() -> bool:
    try:
        _devmod.get_device("auto")
    except _devmod.NoDeviceError:
        return False
    return True


#: whether any OpenCL device exists; OpenCL tests skip only when none does
HAVE_CL = _have_opencl()

DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "volumes"


def load_volume(name: str) -> Volume:
    """bonsai.vti / engine.vti (pyvista) or tooth.nrrd (pynrrd) as a Volume."""
    path = DATA / name
    if path.suffix == ".nrrd":
        import nrrd

        data, header = nrrd.read(str(path))
        spacing = np.linalg.norm(header.get("space directions", np.eye(3)), axis=1)
        origin = header.get("space origin", np.zeros(3))
        return Volume(data, spacing=spacing, origin=origin)
    import pyvista as pv

    img = pv.read(str(path))
    arr = np.asarray(img.point_data[img.array_names[0]])
    nx, ny, nz = img.dimensions
    data = arr.reshape(nz, ny, nx).transpose(2, 1, 0)  # VTK: x varies fastest
    return Volume(data, spacing=img.spacing, origin=img.origin)


def marschner_lobb(n: int = 41) -> tuple[Volume, float]:
    """Marschner-Lobb sampled on n^3 points over its thesis domain, and its isovalue."""
    from splineviz.core.testfunctions import TEST_FUNCTIONS

    f = TEST_FUNCTIONS["ml"]
    return Volume.from_function(f, (n, n, n), f.domain), float(f.isovalue)


def cameras(volume: Volume) -> list[Camera]:
    """Three off-axis cameras looking at the data box from different sides."""
    b = np.asarray(volume.bounds)
    c = b.mean(axis=1)
    r = np.linalg.norm(b[:, 1] - b[:, 0])
    dirs = [(1.0, -1.3, 0.8), (-1.2, -0.4, -0.9), (0.3, 1.1, 1.4)]
    ups = [(0, 0, 1), (0, 0, 1), (1, 0, 0)]
    out = []
    for d, up in zip(dirs, ups, strict=True):
        d = np.asarray(d) / np.linalg.norm(d)
        out.append(Camera(c + 1.6 * r * d, c, view_up=up, view_angle=35.0))
    return out


def compare_frames(test, ref, spline, isovalue, clip_planes=()) -> dict:
    """Acceptance metrics of issue 4 for a kernel frame ``test`` against ``ref``.

    Returns
    -------
    dict with hit_agreement (fraction of pixels), both (number of pixels hit by both),
    pos_ok (fraction of both-hit pixels whose positions agree within 1e-3 voxel), pos_max
    (voxels), value_max (max |s(x) - iso| / data range over the kernel's hits), normal_ok
    (fraction within 0.5 degree), normal_max (degrees), clip_violations (hits on a cut side).
    """
    vol = spline.volume
    lo, hi = vol.finite_range
    both = test.hit & ref.hit
    spacing = np.asarray(vol.spacing)
    dpos = np.linalg.norm((test.position[both] - ref.position[both]) / spacing, axis=1)
    cosang = np.clip(np.sum(test.normal[both] * ref.normal[both], axis=1), -1, 1)
    ang = np.degrees(np.arccos(cosang))
    vals = spline.evaluate(test.position[test.hit]) if test.hit.any() else np.zeros(0)
    viol = 0
    for o, n in clip_planes:
        n = np.asarray(n, float) / np.linalg.norm(n)
        viol += int(np.sum((test.position[test.hit] - np.asarray(o)) @ n < -1e-4))
    return {
        "hit_agreement": float(np.mean(test.hit == ref.hit)),
        "both": int(both.sum()),
        "pos_ok": float(np.mean(dpos <= 1e-3)) if both.any() else 1.0,
        "pos_max": float(dpos.max()) if both.any() else 0.0,
        "value_max": float(np.max(np.abs(vals - isovalue)) / (hi - lo)) if vals.size else 0.0,
        "normal_ok": float(np.mean(ang <= 0.5)) if both.any() else 1.0,
        "normal_max": float(ang.max()) if both.any() else 0.0,
        "clip_violations": viol,
    }
