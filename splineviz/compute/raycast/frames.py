"""Frames of the OpenCL path: the Hessian rows of the ray kernel in world coordinates, empty
frames and windows of frames."""

from __future__ import annotations

import numpy as np

from splineviz.core import raycast_reference as ref


def world_hessian(hv: np.ndarray):
    """(H, W, 3, 3) symmetric Hessians and (H, W) gradient norms from the kernel's (H, W, 8)
    rows (xx, yy, zz, xy, xz, yz, |grad|, 0)."""
    hv = hv.astype(np.float64)
    i, j = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])
    hess_w = np.empty((*hv.shape[:2], 3, 3))
    hess_w[..., i, j] = hv[..., :6]
    hess_w[..., j, i] = hv[..., :6]
    return hess_w, hv[..., 6]


def empty_frame(h: int, w: int, hessian: bool) -> ref.Frame:
    """A frame of ``h`` x ``w`` pixels without hits (an empty window has none)."""
    bg = [*(int(round(v * 255)) for v in ref.BACKGROUND), 255]
    return ref.Frame(np.zeros((h, w), bool), np.full((h, w, 3), np.nan),
                     np.full((h, w, 3), np.nan), np.ones((h, w), np.float32),
                     np.tile(np.asarray(bg, np.uint8), (h, w, 1)),
                     np.full((h, w, 3, 3), np.nan) if hessian else None,
                     np.full((h, w), np.nan) if hessian else None)


def crop(frame: ref.Frame, window) -> ref.Frame:
    """The pixels of ``window`` (r0, r1, c0, c1) of a frame."""
    r0, r1, c0, c1 = window
    if (r0, c0) == (0, 0) and (r1, c1) == frame.hit.shape:
        return frame
    sl = (slice(r0, r1), slice(c0, c1))
    return ref.Frame(*(None if v is None else v[sl] for v in (
        frame.hit, frame.position, frame.normal, frame.depth, frame.color, frame.hessian,
        frame.gradient_norm)))
