"""Grid geometry from an index-to-world affine: spacing, origin, direction and axis flips.

Every format states where its samples lie as a 4x4 affine from array index ``(i, j, k, 1)``
to world ``(x, y, z, 1)`` (NIfTI qform/sform, MGH, MINC direction cosines, PAR/REC, AFNI,
MetaImage ``TransformMatrix``/``Offset``, NRRD ``space directions``/``space origin``, DICOM
``ImageOrientationPatient``/``ImagePositionPatient``). World coordinates stay in the space
the format uses (RAS+ for the nibabel formats, LPS for DICOM and usually for MetaImage and
NRRD), so a surface lands where the file's own library and ITK/VTK put it.

The array is first transposed and flipped by the signed permutation that brings its axes
nearest to the world axes with positive steps (the usual RAS/LPS/LAS storage of scanners is
such a permutation exactly), so every sample keeps its world position and the anatomy shows
the right way up; a flip is announced with a :class:`~splineviz.core.errors.SplinevizWarning`.
What remains is a rotation by less than 45 degrees per axis: the identity for an axis-aligned
file, the tilt of an **oblique** scan otherwise. An oblique grid keeps that rotation as the
:class:`~splineviz.Volume`'s ``direction`` (ITK's and Slicer's convention: the surface lands
where the scanner put it, in the same world as meshes); on request it is resampled onto
axis-aligned axes instead (:func:`resample_axis_aligned`) or refused. An affine whose axes
are not perpendicular (a sheared grid) has no rotation to keep: it is resampled, with a
warning, each new sample taken at its own world point.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from splineviz.core.errors import SplinevizWarning
from splineviz.core.volume import ROTATION_TOLERANCE
from splineviz.io.errors import InvalidDataError

#: largest angle, in degrees, between an axis of the file and the world axis it is taken
#: along. Scanner headers store directions in float32 (NIfTI quaternions, DICOM decimal
#: strings), so an axis-aligned scan arrives tilted by up to ~1e-5 degrees; 0.01 degrees
#: moves no sample of a 4096-sample axis by more than a tenth of a step.
OBLIQUE_TOLERANCE_DEG = 0.01

#: names of the world spaces formats declare
SPACES = ("RAS", "LPS", "")
#: what :func:`~splineviz.io.volumes.read_volume` does with an oblique grid: keep its rotation
#: as the volume's direction (default), resample it onto axis-aligned axes, or refuse it
OBLIQUE_MODES = ("direction", "resample", "error")

#: the six orders of three axes
_PERMUTATIONS = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))


@dataclass(frozen=True)
class Orientation:
    """How to make an index-to-world affine axis-aligned: a transpose, flips and the grid.

    Attributes
    ----------
    perm : (3,) tuple of int
        ``perm[w]`` is the array axis that runs along world axis ``w``.
    flips : (3,) tuple of bool
        ``flips[w]``: world axis ``w`` runs against its array axis (the transposed array is
        reversed along ``w``).
    spacing : (3,) tuple of float
        Positive step along world x, y, z.
    origin : (3,) tuple of float
        World position of the first sample of the transposed, flipped array.
    direction : (3, 3) ndarray
        Unit world direction of each array axis of the file (columns), before any transpose.
    angle : float
        Largest angle in degrees between an array axis and the world axis it is taken along
        (0 for an axis-aligned file).
    affine : (4, 4) ndarray
        The file's index-to-world affine.
    space : str
        ``"RAS"``, ``"LPS"`` or ``""`` (unknown): the world the affine maps into.
    rotation : (3, 3) ndarray
        World direction (columns) of each axis of the transposed, flipped array: what is
        left after the signed permutation, the identity for an axis-aligned file; with
        ``spacing`` and ``origin`` it places the transposed array
        (``origin + rotation @ (i*sx, j*sy, k*sz)``).
    """

    perm: tuple[int, int, int]
    flips: tuple[bool, bool, bool]
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    direction: np.ndarray
    angle: float
    affine: np.ndarray
    space: str = ""
    rotation: np.ndarray = None

    @property
    def oblique(self) -> bool:
        """Whether the axes are rotated beyond :data:`OBLIQUE_TOLERANCE_DEG`."""
        return self.angle > OBLIQUE_TOLERANCE_DEG

    @property
    def shear(self) -> float:
        """Largest deviation of the axes from perpendicular (``|R.T R - I|``, 0 for a
        rectilinear grid; a rotation is kept only within
        :data:`~splineviz.core.volume.ROTATION_TOLERANCE`)."""
        r = self.rotation
        return float(np.abs(r.T @ r - np.eye(3)).max())

    @property
    def sheared(self) -> bool:
        """Whether the axes are too far from perpendicular for a rotation to place them
        (:attr:`shear` beyond :data:`~splineviz.core.volume.ROTATION_TOLERANCE`)."""
        return self.shear > ROTATION_TOLERANCE

    @property
    def volume_direction(self) -> np.ndarray | None:
        """The direction a :class:`~splineviz.Volume` of the transposed array keeps: the
        rotation of an oblique grid, None (the identity) otherwise."""
        return self.rotation if self.oblique else None

    @property
    def identity(self) -> bool:
        """Whether the array is already in world order with positive steps."""
        return self.perm == (0, 1, 2) and not any(self.flips)

    def apply(self, data):
        """The array in world order: its first three axes transposed and flipped.

        Parameters
        ----------
        data : (n0, n1, n2, ...) ndarray
            Samples as the file indexes them; trailing axes (time, channel) are kept.

        Returns
        -------
        (nx, ny, nz, ...) ndarray
            A view where NumPy allows.
        """
        if self.identity:
            return data
        order = tuple(self.perm) + tuple(range(3, data.ndim))
        out = np.transpose(data, order)
        flipped = tuple(w for w in range(3) if self.flips[w])
        return np.flip(out, axis=flipped) if flipped else out


def affine_from(spacing, origin, direction=None) -> np.ndarray:
    """The 4x4 index-to-world affine of a grid.

    Parameters
    ----------
    spacing : (3,) float
        Step along each array axis (a negative step runs against its direction).
    origin : (3,) float
        World position of sample ``(0, 0, 0)``.
    direction : (3, 3) array_like, optional
        Unit world direction of each array axis, as columns (ITK's ``Direction``, VTK's
        ``DirectionMatrix``); identity by default.

    Returns
    -------
    (4, 4) ndarray
    """
    d = np.eye(3) if direction is None else np.asarray(direction, dtype=float).reshape(3, 3)
    out = np.eye(4)
    out[:3, :3] = d * np.asarray(spacing, dtype=float)[None, :]
    out[:3, 3] = np.asarray(origin, dtype=float)
    return out


def orientation(affine, shape, name: str, *, space: str = "") -> Orientation:
    """Read an index-to-world affine as an axis-aligned grid (see the module notes).

    Parameters
    ----------
    affine : (4, 4) array_like
        Index ``(i, j, k, 1)`` to world ``(x, y, z, 1)``.
    shape : sequence of int
        The array's shape; its first three entries are the spatial axes.
    name : str
        File name for messages.
    space : {"RAS", "LPS", ""}
        The world space the affine maps into (kept for :func:`describe` and the caller).

    Returns
    -------
    Orientation
        Check :attr:`Orientation.oblique` (and :func:`check_oblique` for what a mode
        refuses).

    Raises
    ------
    InvalidDataError
        The affine is not finite or has a zero-length axis.
    """
    a = np.asarray(affine, dtype=float)
    if a.shape != (4, 4) or not np.all(np.isfinite(a)):
        raise InvalidDataError(f"{name} has a malformed or non-finite index-to-world affine")
    m = a[:3, :3]
    steps = np.linalg.norm(m, axis=0)
    if not np.all(steps > 0):
        raise InvalidDataError(f"{name} has an index-to-world affine with a zero-length axis "
                               f"(voxel sizes {', '.join(f'{s:g}' for s in steps)})")
    direction = m / steps[None, :]
    # the signed permutation nearest the identity: each world axis w takes the array axis
    # perm[w] whose direction is most along it (the largest sum of |cosines| over the six
    # orders; a per-axis choice when the axes are nearly aligned, also past 45 degrees)
    perm = max(_PERMUTATIONS, key=lambda p: sum(abs(direction[w, p[w]]) for w in range(3)))
    flips = [bool(direction[w, perm[w]] < 0) for w in range(3)]
    cosines = np.abs(direction[[0, 1, 2], list(perm)]).clip(0.0, 1.0)
    angle = float(np.degrees(np.arccos(cosines)).max())
    shape = [int(n) for n in shape[:3]]
    index0 = np.zeros(3)
    for w, ax in enumerate(perm):
        index0[ax] = shape[ax] - 1 if flips[w] else 0
    origin = m @ index0 + a[:3, 3]
    rotation = np.stack([direction[:, ax] * (-1.0 if flips[w] else 1.0)
                         for w, ax in enumerate(perm)], axis=1)
    return Orientation(tuple(int(p) for p in perm), tuple(flips),
                       tuple(float(steps[ax]) for ax in perm),
                       tuple(float(v) for v in origin), direction, angle, a,
                       space if space in SPACES else "", rotation)


def axis_aligned(data, affine, name: str, *, space: str = "", warn: bool = True,
                 oblique: str = "direction"):
    """The samples of a file's grid transposed and flipped nearest to the world axes.

    This is the one rule every reader follows (see the module notes): a signed-permutation
    direction is transposed and flipped (announced by a warning when ``warn``); the rotation
    left over of an oblique grid is :attr:`Orientation.volume_direction`.

    Parameters
    ----------
    data : (n0, n1, n2, ...) ndarray
        Samples in the file's index order; trailing (time, channel) axes are kept.
    affine : (4, 4) array_like
        Index-to-world affine of ``data``.
    name : str
        File name for messages.
    space : {"RAS", "LPS", ""}
    warn : bool
        Warn when an axis is flipped.
    oblique : {"direction", "error"}
        Keep an oblique grid's rotation (default) or refuse the grid.

    Returns
    -------
    data : (nx, ny, nz, ...) ndarray
        A view of ``data`` in world order with positive steps.
    orient : Orientation
        Its ``spacing``, ``origin`` and ``volume_direction`` place ``data``; ``direction``
        and ``affine`` are the file's.

    Raises
    ------
    InvalidDataError
        An oblique affine when ``oblique="error"``, a sheared one (no rotation places it),
        a malformed one.
    """
    orient = orientation(affine, np.shape(data), name, space=space)
    check_oblique(orient, name, oblique)
    if orient.oblique and orient.sheared:
        raise InvalidDataError(f"{name} has a sheared grid (its axes are not perpendicular), "
                               "which splineviz cannot show in place")
    if warn:
        warn_flips(orient, name)
    return orient.apply(data), orient


def check_oblique(orient: Orientation, name: str, mode: str) -> None:
    """Refuse an oblique grid when ``mode`` (one of :data:`OBLIQUE_MODES`) is ``"error"``
    (one sentence, the angle)."""
    if mode not in OBLIQUE_MODES:
        raise ValueError(f"oblique must be one of {', '.join(OBLIQUE_MODES)}, got {mode!r}")
    if mode == "error":
        refuse_oblique(orient, name)


def refuse_oblique(orient: Orientation, name: str) -> None:
    """Raise :class:`InvalidDataError` if ``orient`` is oblique (one sentence, the angle)."""
    if orient.oblique:
        raise InvalidDataError(
            f"{name} is an oblique scan (its axes are rotated by {orient.angle:.3g} degrees "
            "from the world axes) and was read with oblique='error'; read it with "
            "oblique='direction' to show it in place or oblique='resample' to resample it "
            "onto axis-aligned axes")


def resample_axis_aligned(data, orient: Orientation, name: str, *, fill: float):
    """Trilinear resampling of an oblique grid onto the axis-aligned grid that covers it,
    every new sample taken at its own world point (nothing is rotated into place).

    The new step along each world axis is the step of the file axis nearest to it, so the
    sample count grows only by the bounding box's share; points outside the file's grid get
    ``fill`` (the smallest sample: outside every isosurface above it).

    Parameters
    ----------
    data : (n0, n1, n2) ndarray
        Samples in the file's index order.
    orient : Orientation
        From :func:`orientation` of the file's affine.
    name : str
        File name for the warning.
    fill : float

    Returns
    -------
    data : (nx, ny, nz) float32 ndarray
    spacing, origin : (3,) tuple of float
    """
    from scipy import ndimage

    from splineviz.io._util import check_volume_size

    a = orient.affine
    corners = np.array(np.meshgrid(*[[0, n - 1] for n in data.shape[:3]],
                                   indexing="ij")).reshape(3, -1)
    world = a[:3, :3] @ corners + a[:3, 3:4]
    lo, hi = world.min(axis=1), world.max(axis=1)
    spacing = np.asarray(orient.spacing, dtype=float)
    shape = tuple(int(np.floor((h - l) / s + 1e-9)) + 1 for l, h, s in zip(lo, hi, spacing,
                                                                             strict=True))
    check_volume_size(shape, 4, name)
    # output index o -> world lo + o * spacing -> file index inv(M) (world - t)
    inv = np.linalg.inv(a[:3, :3])
    matrix = inv @ np.diag(spacing)
    offset = inv @ (lo - a[:3, 3])
    out = ndimage.affine_transform(np.asarray(data, dtype=np.float32), matrix, offset,
                                   output_shape=shape, order=1, mode="constant",
                                   cval=float(fill))
    what = "a sheared grid (its axes are not perpendicular)" if orient.sheared else \
        f"an oblique scan (rotated by {orient.angle:.3g} degrees)"
    warnings.warn(f"{name} is {what}: it is resampled trilinearly onto axis-aligned axes, each "
                  "sample at its own world point", SplinevizWarning, stacklevel=4)
    return out, tuple(float(s) for s in spacing), tuple(float(v) for v in lo)


def warn_flips(orient: Orientation, name: str, *, stacklevel: int = 3) -> None:
    """Announce the axes :meth:`Orientation.apply` reverses, as today's negative spacings."""
    flipped = [w for w in range(3) if orient.flips[w]]
    if flipped:
        warnings.warn(f"{name} has a negative spacing along "
                      f"{', '.join('xyz'[w] for w in flipped)} (its grid runs against the "
                      "world axis): the axis is flipped so that every sample keeps its world "
                      "position", SplinevizWarning, stacklevel=stacklevel)
