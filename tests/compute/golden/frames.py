"""Hashes of the frames every spline model renders on the shared data, recorded before the
architecture refactor of issue 24 (``python -m tests.compute.golden.frames --record`` rewrites
``frames.json``; the test compares against it).

A frame's hash is the SHA-256 of its arrays' bytes (hit, colour, depth, position, normal and,
when asked, Hessian and gradient norm). Hashes are kept per device name, since OpenCL compilers
round differently on different processors; the NumPy path's hashes hold on any machine with
the same NumPy build, so every entry also keeps a few sums for a tolerant comparison.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RECORD = HERE / "frames.json"

#: (case, model, data, size, with a clip plane, hessian, numpy path)
CASES = [
    (f"{model}-{data}-{'numpy' if numpy else 'cl'}{'-hess' if hess else ''}",
     model, data, size, clip, hess, numpy)
    for model in ("trilinear", "super-quadratic", "cubic-c1", "to-quadratic", "tricubic-bspline")
    for data, size, clip, hess, numpy in (
        ("tooth", (96, 72), True, False, False),
        ("ml41", (96, 72), False, True, False),
        ("blob13", (20, 16), True, False, True),
    )
    if not (model == "trilinear" and hess)
]


def _volume(name: str):
    import splineviz as sv

    from ..helpers import load_volume, marschner_lobb

    if name == "tooth":
        vol = load_volume("tooth.nrrd")
        lo, hi = vol.finite_range
        return vol, lo + 0.35 * (hi - lo)
    if name == "ml41":
        return marschner_lobb(41)
    f = sv.testfunctions.TEST_FUNCTIONS["blob"]
    return sv.Volume.from_function(f, (13, 13, 13), f.domain), float(f.isovalue)


def _camera(vol):
    from splineviz.core.camera import Camera

    b = np.asarray(vol.bounds, dtype=float)
    c = b.mean(axis=1)
    r = float(np.linalg.norm(b[:, 1] - b[:, 0]))
    return Camera(c + r * np.array([0.9, -1.4, 0.7]), c, view_up=(0, 0, 1))


def render_case(case):
    """The frame of one case (model, data, ...) of :data:`CASES`."""
    import splineviz as sv
    from splineviz import plugins

    plugins.ensure_loaded()
    _, model, data, size, clip, hess, numpy_path = case
    vol, iso = _volume(data)
    rc = sv.RayCaster(vol, model=model, device="numpy" if numpy_path else None)
    rc.set_isovalue(iso)
    planes = []
    if clip:
        c = np.asarray(vol.bounds, dtype=float).mean(axis=1)
        planes = [(c, (0.3, 1.0, 0.2))]
    frame = rc.render(_camera(vol), size, clip_planes=planes, hessian=hess)
    return rc, frame


def digest(frame) -> dict:
    """SHA-256 of the frame's arrays and a few sums for tolerant comparison."""
    h = hashlib.sha256()
    arrays = [frame.hit, frame.color, frame.depth, frame.position, frame.normal]
    if frame.hessian is not None:
        arrays += [frame.hessian, frame.gradient_norm]
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(str(a.dtype).encode() + str(a.shape).encode())
        h.update(a.tobytes())
    hit = frame.hit
    return {"sha256": h.hexdigest(), "hits": int(hit.sum()),
            "depth_sum": float(np.asarray(frame.depth, dtype=np.float64)[hit].sum()),
            "color_sum": int(np.asarray(frame.color, dtype=np.int64).sum())}


def record() -> None:
    doc = json.loads(RECORD.read_text()) if RECORD.exists() else {}
    for case in CASES:
        rc, frame = render_case(case)
        device = rc.stats["device"]
        doc.setdefault(case[0], {})[device] = digest(frame)
        print(case[0], device, doc[case[0]][device]["sha256"][:12], flush=True)
    RECORD.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    if "--record" in sys.argv:
        record()
