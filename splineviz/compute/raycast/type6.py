"""The type-6 kernel family (``"cubic-c1"``, ``"super-quadratic"``, thesis §4.4): cubes
centred at the samples.

Cube bounds come from the 27-point stencil (every coefficient is an affine combination of it,
widened by the negative weight mass). A cube's tet code comes from its determining set and
the averaging rules (§5.1-5.2), written out as straight-line code
(:mod:`~splineviz.compute.raycast.type6_program`). The ray part inside each relevant tet
comes from the tet's four barycentric plane equations (§6.2.2), its coefficients from the
stencil with the core model's masks, the Bernstein coefficients of the segment from blossoms
(§6.1.2), the first root by the monotone-piece cubic solver, the gradient from the last de
Casteljau step. Deviation from Listing 6.2: tets of a cube are clipped independently instead
of walked via the neighbour table (same result, no special cases at cube faces).
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.raycast import segment_program, type6_program
from splineviz.compute.raycast.family import (
    SKIP_ACTIVE,
    TET_SLACK,
    KernelFamily,
    register_kernel_family,
)
from splineviz.compute.raycast.samples import padded_device_samples, sample_blocks
from splineviz.compute.raycast.tables import padded_rows, reduction_table


@register_kernel_family
class Type6Family(KernelFamily):
    """Type-6 splines: one 24-bit tet code per cube cached per brick."""

    name = "type6"
    define = "MODEL_TYPE6"
    ghost_layers = 1
    centred = True
    cache_words = 1

    def upload(self, rc) -> dict:
        """Upload the padded samples and the constant tables of a type-6 model.

        All tables come from the core model (``rc.spline.scheme``), so the kernel computes
        exactly the core spline: tet masks (24, n_d, 27), barycentric matrices (24, 4, 4) and
        the de Casteljau reduction tables of :mod:`splineviz.core.bform`; the cube program and
        per cube point the tets whose B-net holds it (from ``tet_points``, (24, n_d)) are
        literals of the generated tet code (:mod:`.type6_program`), the reduction steps of a
        ray segment's blossoms those of :mod:`.segment_program`.
        """
        import pyopencl.array as cla

        from splineviz.core import bform
        from splineviz.core.partitions import type6
        from splineviz.core.splines import type6_rules

        q = rc._device.queue
        scheme = rc.spline.scheme
        self.degree = scheme.degree
        rc._data = padded_device_samples(rc._device, rc.volume.data, self.ghost_layers,
                                         rc._sample_type[0])
        _, py, pz = rc._data.shape
        rc._strides = (py, pz)
        stencil = (type6_rules.OFFSETS @ np.array([py * pz, pz, 1])).astype(np.int32)
        self._stencil = cla.to_device(q, stencil)
        # dense tet masks (24, 27, NCHUNK * 8): per tet and stencil value, its weights in the
        # tet's coefficients (whole float8s of the kernel)
        self._tet_dense = cla.to_device(q, padded_rows(scheme.tet_masks.transpose(0, 2, 1), 8))
        # generated: the tet code (the cube program written out, tet masks as literals) and
        # the blossoms of a ray segment in a tet
        self.prelude = (type6_program.code_source(rc.spline.scheme_name)
                        + segment_program.segment_source(scheme.degree))
        self._bary = cla.to_device(
            q, np.ascontiguousarray(type6.barycentric_matrices(), np.float32))
        red = [reduction_table(k) for k in range(scheme.degree, 0, -1)]
        self._red = cla.to_device(q, np.concatenate([r.ravel() for r in red]).astype(np.int32))
        # largest negative weight mass of any coefficient (bounds of stencil_bounds)
        rc._negmass = float(np.max(np.sum(np.clip(-scheme.cube_masks, 0, None), axis=1)))
        return {"MODEL_TYPE6": 1, "NCOEF": bform.n_coefficients(scheme.degree),
                "SKIP_ACTIVE": SKIP_ACTIVE}

    def upload_samples(self, rc) -> None:
        """The new samples only: the tables come from the model, the stencil offsets from
        the padded shape, both unchanged."""
        rc._data = padded_device_samples(rc._device, rc.volume.data, self.ghost_layers,
                                         rc._sample_type[0], out=rc._data)

    def node_args(self, rc) -> list:
        """The (min, max) of the 2 x 2 x 2 sample blocks (a node's 4^3 samples are 8)."""
        return sample_blocks(rc)

    def defines(self, rc) -> dict:
        return {"DEGREE": self.degree, "TET_SLACK": TET_SLACK}

    def ray_args(self, rc) -> list:
        return [self._stencil.data, self._tet_dense.data, self._bary.data, self._red.data]

    def classify(self, rc, listed, cells: np.ndarray, iso: np.float32):
        """Tet codes of every candidate cube, written into the cache too (the next frames use
        them)."""
        import pyopencl.array as cla

        q = rc._device.queue
        n = len(cells)
        relevant, codes = np.zeros(n, np.int32), np.zeros(n, np.uint32)
        if n:
            nrel = cla.empty(q, n, np.int32)
            code_buf = cla.empty(q, n, np.uint32)
            _, ny, nz = rc.volume.shape
            # room in the pool for every candidate brick, and their entries taken
            ijk = np.stack(np.unravel_index(cells, rc._cells))
            bricks = np.unique(np.ravel_multi_index(ijk >> 1, rc._levels[0][1:]))
            rc._grow_pool(int(rc._counts[2:3].get(queue=q)[0]) + len(bricks))
            rc._ray_kernel("brick_entries")(
                q, (len(bricks),), None, cla.to_device(q, bricks.astype(np.int32)).data,
                *rc._cache_args()[:-1])
            rc._ray_kernel("tet_codes")(
                q, (n,), None, rc._data.data, np.int32(rc._strides[0]),
                np.int32(rc._strides[1]), np.int32(ny), np.int32(nz), listed.data,
                self._stencil.data, np.float32(rc._negmass), iso,
                *rc._cache_args()[:-1], code_buf.data, nrel.data)
            relevant, codes = nrel.get(queue=q), code_buf.get(queue=q)
        # the cache is complete: later frames count nothing new
        rc._counts[:2].set(
            np.array([np.count_nonzero(relevant), relevant.sum()], np.int32), queue=q)
        return relevant, codes

