"""OpenCL ray casting of spline isosurfaces (thesis §6.1.1, §6.2; docs/api.md ``RayCaster``).

Pipeline on the device, without a CPU round trip of the volume:

* on a data change (isovalue-independent, thesis §6.1.1, §6.2.1): the samples (padded with
  ghost layers where the model needs them, written straight into a device buffer) and a
  min-max octree of conservative value bounds, stored from level 1 (bricks of 2^3 cells);
  new data of the same shape and sample type (the next time step) are written into the
  buffers there are, the programs and tables kept;
* on an isovalue change: nothing but a new cache epoch (constant time, nothing uploaded).
  The work the picture needs is done by the rays that need it (§6.2.3): the skip index of a
  cell comes from the octree when a ray reaches the cell, and the relevance of a candidate
  cell's tetrahedra (its tet code, §6.1.1) is computed by the first ray that reaches it and
  cached per brick for later frames at the same isovalue (visible-first classification; only
  the bricks the rays reach take memory). :meth:`RayCaster.classify_all` classifies every
  cell at once (prefix-scan compaction of the candidates, Fig. 6.3) for counts and checks;
* per frame: one work-item per pixel; macro-cell leaping with the Heaviside plane choice,
  cell traversal, the exact restriction of the model to the ray in each candidate cell, first
  root, gradient, Phong headlight shading and OpenGL window depth.

:class:`RayCaster` (:mod:`.caster`) is a facade over the model's kernel family
(:mod:`.family`), which owns its tables, buffers, defines, ghost layers and cache words:

* ``"trilinear"`` (:mod:`.trilinear`): cells between samples, an exact cubic per cell;
* ``"type6"`` (:mod:`.type6`): ``"cubic-c1"``, ``"super-quadratic"``, cubes centred at the
  samples, tet codes cached per brick;
* ``"to"`` (:mod:`.truncated_octahedra`): ``"to-quadratic"``, per-parity-class piece tables;
* families brought by plugins (:class:`CustomKernelFamily`, registered through
  ``api.add_model(..., kernel_family=...)``), e.g. the tricubic B-spline of
  ``plugins/splineviz-bspline``.

A brick of a bigger volume (:mod:`splineviz.compute.bricked`) is cast by the same kernel,
compiled with ``BRICKS``, in the whole volume's coordinates and over a window of the frame
(``RayCaster.render(placement=..., window=...)``): its hits are those of one cast of the
whole volume, bit for bit. A volume past 2^31 device samples is cast with 64-bit sample
offsets (``OFFSET64``) when the device holds it (:meth:`RayCaster.limits`).

Models without a kernel family render through the NumPy reference ray caster
(:mod:`splineviz.core.raycast_reference`); ``stats["path"]`` says which path made the frame.
"""

from splineviz.compute.raycast import trilinear as _trilinear  # noqa: F401  (registers)
from splineviz.compute.raycast import truncated_octahedra as _to  # noqa: F401  (registers)
from splineviz.compute.raycast import type6 as _type6  # noqa: F401  (registers)
from splineviz.compute.raycast.caster import (
    MAX_EPOCH,
    MAX_POOL,
    MAX_SAMPLES,
    RAY_GROUP,
    Classification,
    RayCaster,
    _shading_defines,
)
from splineviz.compute.raycast.errors import RayCastError
from splineviz.compute.raycast.family import (
    KERNEL_FAMILIES,
    SKIP_ACTIVE,
    TET_SLACK,
    TO_WORDS,
    CustomKernelFamily,
    KernelFamily,
    KernelFamilyError,
    family_class,
    kernel_define,
    register_kernel_family,
    renders_in_bricks,
)
from splineviz.compute.raycast.limits import Limits
from splineviz.compute.raycast.samples import (
    SAMPLE_TYPES,
    numpy_cell_bounds,
    pad_linear_into,
    sample_type_for,
)
from splineviz.compute.raycast.type6_program import cube_program as _cube_program

__all__ = [
    "KERNEL_FAMILIES", "MAX_EPOCH", "MAX_POOL", "MAX_SAMPLES", "RAY_GROUP", "SAMPLE_TYPES",
    "SKIP_ACTIVE", "TET_SLACK", "TO_WORDS", "Classification", "CustomKernelFamily",
    "KernelFamily", "KernelFamilyError", "Limits", "RayCastError", "RayCaster",
    "_cube_program", "_shading_defines", "family_class", "kernel_define", "numpy_cell_bounds",
    "pad_linear_into", "register_kernel_family", "renders_in_bricks", "sample_type_for",
]
