"""A perspective camera with VTK conventions, in pure NumPy.

Conventions (as ``vtkCamera``): ``position`` is the eye, ``focal_point`` the point looked at,
``view_up`` is made orthogonal to the direction of projection, ``view_angle`` is the full
*vertical* opening angle in degrees. Images are ``(H, W)`` with row 0 at the top (like a PNG);
pixel ``(r, c)`` is sampled through its centre. Depth is OpenGL window depth in ``[0, 1]``
for the clipping range ``(near, far)`` (distances along the direction of projection).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splineviz.core.errors import SplinevizError


class CameraError(SplinevizError, ValueError):
    """A camera that cannot form an image (degenerate direction, bad angle or size)."""


#: relative margin added to the clipping range computed from a bounding box (VTK adds 0.5 %
#: of the range on each side; the near plane is also kept away from zero)
CLIP_MARGIN = 0.01
#: smallest near/far ratio, as VTK's ``NearClippingPlaneTolerance`` default
NEAR_TOLERANCE = 1e-3


#: largest image side: VTK's largest render window, and far beyond any screen or print use
MAX_IMAGE_SIDE = 16384


def parse_size(size) -> tuple[int, int]:
    """(width, height) from a pair or a ``"WxH"`` string, each side 1 to
    :data:`MAX_IMAGE_SIDE` (checked before any frame buffer is allocated)."""
    if isinstance(size, str):
        parts = size.lower().split("x")
        if len(parts) != 2:
            raise CameraError(f"image size must look like 640x480, got {size!r}")
        size = parts
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise CameraError(f"image size must be two integers, got {size!r}") from None
    if w < 1 or h < 1:
        raise CameraError(f"image size must be positive, got {w}x{h}")
    if max(w, h) > MAX_IMAGE_SIDE:
        raise CameraError(f"image size {w}x{h} is too large: at most {MAX_IMAGE_SIDE} pixels "
                          "per side")
    return w, h


@dataclass
class Camera:
    """Perspective camera (VTK conventions).

    Parameters
    ----------
    position, focal_point : (3,) float
        Eye and look-at point in world coordinates; they must differ.
    view_up : (3,) float
        Up direction; must not be parallel to the direction of projection.
    view_angle : float
        Vertical opening angle in degrees, in (0, 180).
    clipping_range : (near, far) or None
        Distances along the direction of projection mapped to depth 0 and 1; ``None`` lets
        the ray caster fit it to the data box (:meth:`fit_clipping_range`).

    Examples
    --------
    >>> cam = Camera((0, 0, 10), (0, 0, 0), view_up=(0, 1, 0))
    >>> o, d = cam.rays((3, 3))
    >>> d[1, 1].round(6).tolist()
    [0.0, 0.0, -1.0]
    """

    position: tuple = (0.0, 0.0, 1.0)
    focal_point: tuple = (0.0, 0.0, 0.0)
    view_up: tuple = (0.0, 0.0, 1.0)
    view_angle: float = 30.0
    clipping_range: tuple | None = None

    def __post_init__(self):
        self.position = tuple(float(v) for v in np.broadcast_to(self.position, 3))
        self.focal_point = tuple(float(v) for v in np.broadcast_to(self.focal_point, 3))
        self.view_up = tuple(float(v) for v in np.broadcast_to(self.view_up, 3))
        self.view_angle = float(self.view_angle)
        if not 0.0 < self.view_angle < 180.0:
            raise CameraError(f"view angle must be in (0, 180) degrees, got {self.view_angle}")
        if not np.all(np.isfinite(self.position + self.focal_point + self.view_up)):
            raise CameraError("camera position, focal point and view up must be finite")
        self.basis()  # validate the geometry now, not at render time
        if self.clipping_range is not None:
            near, far = (float(v) for v in self.clipping_range)
            if not 0.0 < near < far:
                raise CameraError(f"clipping range needs 0 < near < far, got ({near}, {far})")
            self.clipping_range = (near, far)

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal (right, up, direction of projection), each (3,) float64."""
        dop = np.subtract(self.focal_point, self.position)
        n = np.linalg.norm(dop)
        if n == 0.0:
            raise CameraError("camera position and focal point coincide")
        dop /= n
        up = np.asarray(self.view_up, dtype=np.float64)
        up = up - np.dot(up, dop) * dop  # VTK's OrthogonalizeViewUp
        nu = np.linalg.norm(up)
        if nu < 1e-12 * max(1.0, np.linalg.norm(self.view_up)):
            raise CameraError("view up is parallel to the viewing direction")
        up /= nu
        right = np.cross(dop, up)
        return right, up, dop

    def rays(self, size) -> tuple[np.ndarray, np.ndarray]:
        """One ray per pixel through the pixel centre.

        Parameters
        ----------
        size : (width, height) or "WxH"

        Returns
        -------
        origin : (3,) float64, the eye
        directions : (H, W, 3) float64 unit vectors; row 0 is the top image row
        """
        w, h = parse_size(size)
        right, up, dop = self.basis()
        tan_half = np.tan(np.radians(self.view_angle) / 2.0)
        # normalised device coordinates of pixel centres; y grows upwards, rows go down
        x = (2.0 * (np.arange(w) + 0.5) / w - 1.0) * tan_half * (w / h)
        y = (1.0 - 2.0 * (np.arange(h) + 0.5) / h) * tan_half
        d = dop + x[None, :, None] * right + y[:, None, None] * up
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        return np.asarray(self.position, dtype=np.float64), d

    def fit_clipping_range(self, bounds) -> tuple[float, float]:
        """(near, far) enclosing the box ``bounds`` along the direction of projection.

        Like ``vtkRenderer::ResetCameraClippingRange``: the extreme distances of the eight box
        corners, widened by :data:`CLIP_MARGIN`, with near >= far * :data:`NEAR_TOLERANCE`.
        An explicit :attr:`clipping_range` is returned unchanged.
        """
        if self.clipping_range is not None:
            return self.clipping_range
        b = np.asarray(bounds, dtype=np.float64).reshape(3, 2)
        corners = np.stack(np.meshgrid(*b, indexing="ij"), axis=-1).reshape(-1, 3)
        dist = (corners - self.position) @ self.basis()[2]
        near, far = float(dist.min()), float(dist.max())
        pad = CLIP_MARGIN * max(far - near, 1e-12)
        far = max(far + pad, 1e-6)
        near = max(near - pad, far * NEAR_TOLERANCE)
        return near, far

    def window_depth(self, points, clipping_range) -> np.ndarray:
        """OpenGL window depth of world points for a perspective projection.

        ``z_w = (z_ndc + 1) / 2`` with ``z_ndc = (f + n) / (f - n) - 2 f n / ((f - n) z_e)``,
        ``z_e`` the distance along the direction of projection (the standard
        ``glFrustum`` matrix followed by the perspective divide).

        Parameters
        ----------
        points : (..., 3) float
        clipping_range : (near, far)

        Returns
        -------
        (...) float64 depth, not clamped (points outside the range fall outside [0, 1]).
        """
        near, far = clipping_range
        ze = (np.asarray(points, dtype=np.float64) - self.position) @ self.basis()[2]
        with np.errstate(divide="ignore", invalid="ignore"):
            ndc = (far + near) / (far - near) - 2.0 * far * near / ((far - near) * ze)
        return 0.5 * (ndc + 1.0)

    def projection_constants(self, clipping_range) -> tuple[float, float]:
        """(A, B) with window depth = A - B / z_e (used by the OpenCL kernel)."""
        near, far = clipping_range
        return 0.5 * (far + near) / (far - near) + 0.5, far * near / (far - near)


def default_camera(bounds, view_angle: float = 30.0, direction=(1.0, -1.3, 0.8)) -> Camera:
    """An oblique view of the whole box ``bounds`` (fills about the frame height)."""
    b = np.asarray(bounds, dtype=np.float64)
    c = b.mean(axis=1)
    radius = 0.5 * np.linalg.norm(b[:, 1] - b[:, 0])
    d = np.asarray(direction, dtype=np.float64)
    d /= np.linalg.norm(d)
    dist = radius / np.sin(np.radians(view_angle) / 2.0) * 1.05
    return Camera(c + dist * d, c, view_up=(0, 0, 1), view_angle=view_angle)
