"""The rigid map between a volume's own frame and world, for volumes with a direction.

A :class:`~splineviz.core.volume.Volume` puts ``data[i, j, k]`` at world point
``origin + R @ (i*sx, j*sy, k*sz)`` with ``R`` its ``direction`` (a rotation). Splines, ray
casters, sections and slices work in the volume's own axis-aligned frame
``v = origin + (i*sx, j*sy, k*sz)``; the two are related by the rotation about ``origin``

    world = origin + R @ (v - origin),        v = origin + R.T @ (world - origin).

A rigid map keeps distances, so a ray cast in the volume frame from the camera moved there
hits at the same ray parameter and the same window depth as in world; only positions,
normals and Hessians are rotated back. Every function here returns its input unchanged for
an axis-aligned volume (no arithmetic at all: frames of such volumes stay bit-identical).
The functions take any volume-like object with ``origin`` and ``direction`` (a
:class:`~splineviz.core.volume.Volume`, a :class:`~splineviz.core.chunked.ChunkedVolume`).
"""

from __future__ import annotations

import numpy as np

from splineviz.core.camera import Camera


def rotation(volume) -> np.ndarray | None:
    """The (3, 3) direction of ``volume``, or None when it is axis-aligned."""
    d = getattr(volume, "direction", None)
    if d is None or not np.any(d != np.eye(3)):
        return None
    return d


def to_world(volume, points) -> np.ndarray:
    """(..., 3) points of the volume frame -> world (float64; ``points`` as they are when
    axis-aligned)."""
    r = rotation(volume)
    if r is None:
        return points
    o = np.asarray(volume.origin, dtype=np.float64)
    return (np.asarray(points, dtype=np.float64) - o) @ r.T + o


def from_world(volume, points) -> np.ndarray:
    """(..., 3) world points -> the volume frame (float64; unchanged when axis-aligned)."""
    r = rotation(volume)
    if r is None:
        return points
    o = np.asarray(volume.origin, dtype=np.float64)
    return (np.asarray(points, dtype=np.float64) - o) @ r + o


def vectors_to_world(volume, vectors) -> np.ndarray:
    """(..., 3) directions (normals, gradients) of the volume frame -> world."""
    r = rotation(volume)
    return vectors if r is None else np.asarray(vectors, dtype=np.float64) @ r.T


def corners(bounds) -> np.ndarray:
    """(8, 3) corners of the box ``((x0, x1), (y0, y1), (z0, z1))``."""
    b = np.asarray(bounds, dtype=np.float64).reshape(3, 2)
    return np.stack(np.meshgrid(*b, indexing="ij"), axis=-1).reshape(-1, 3)


def world_bounds(volume) -> tuple[tuple[float, float], ...]:
    """``((xmin, xmax), (ymin, ymax), (zmin, zmax))`` of the volume's grid box in world: the
    box of its eight rotated corners (``volume.bounds`` when axis-aligned)."""
    if rotation(volume) is None:
        return volume.bounds
    w = to_world(volume, corners(volume.bounds))
    return tuple((float(lo), float(hi)) for lo, hi in zip(w.min(axis=0), w.max(axis=0),
                                                          strict=True))


def world_matrix(volume) -> np.ndarray:
    """(4, 4) homogeneous map of volume-frame points to world (a VTK ``UserMatrix``)."""
    m = np.eye(4)
    r = rotation(volume)
    if r is not None:
        o = np.asarray(volume.origin, dtype=np.float64)
        m[:3, :3] = r
        m[:3, 3] = o - r @ o
    return m


def camera_to_volume(volume, camera: Camera) -> Camera:
    """``camera`` moved rigidly into the volume frame (the same picture of the grid; its
    clipping range is kept, so window depths are those of world)."""
    r = rotation(volume)
    if r is None:
        return camera
    return Camera(from_world(volume, camera.position), from_world(volume, camera.focal_point),
                  np.asarray(camera.view_up, dtype=np.float64) @ r, camera.view_angle,
                  camera.clipping_range)


def planes_to_volume(volume, planes) -> np.ndarray:
    """(P, 2, 3) clip planes (origin, unit normal) of world -> the volume frame."""
    r = rotation(volume)
    if r is None or len(planes) == 0:
        return planes
    p = np.asarray(planes, dtype=np.float64)
    return np.stack([from_world(volume, p[:, 0]), p[:, 1] @ r], axis=1)


def frame_to_world(volume, frame):
    """A :class:`~splineviz.core.raycast_reference.Frame` cast in the volume frame, with its
    positions, normals and Hessians rotated into world (read lazily, like the frame's own:
    colour and depth need no change). ``frame`` itself when axis-aligned."""
    from splineviz.core.raycast_reference import Frame

    r = rotation(volume)
    if r is None:
        return frame

    def position():
        return to_world(volume, frame.position)

    def normal():
        return vectors_to_world(volume, frame.normal)

    hessian = None if frame.hessian is None else r @ frame.hessian @ r.T
    return Frame(frame.hit, position, normal, frame.depth, frame.color, hessian,
                 frame.gradient_norm)
