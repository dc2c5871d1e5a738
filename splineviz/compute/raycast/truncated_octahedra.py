"""The truncated-octahedral kernel family (``"to-quadratic"``, thesis §5.2).

Unit cells of the grid with per-parity-class tables of the (TO, tet) pieces meeting a cell
(:mod:`.to_tables`); a cell's relevance bit set computes each distinct B-net point of its
pieces once (generated straight-line code, :mod:`.to_program`), and the ray tests only the
relevant pieces of the subcells (5^3 per cell) its segment crosses. Each classified cell's
range (the min/max of its points, 2 bytes) is kept while the data stay, so a later isovalue
outside it skips the cell without its sums (isovalue-independent work once per data change,
thesis §6.1.1). The tables take a second of Python and are kept on disk between runs
(:mod:`splineviz.compute.table_cache`).
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.buffers import fill
from splineviz.compute.raycast.errors import RayCastError
from splineviz.compute.raycast.family import (
    SKIP_ACTIVE,
    TET_SLACK,
    TO_WORDS,
    KernelFamily,
    register_kernel_family,
)
from splineviz.compute.raycast.samples import padded_device_samples, sample_blocks
from splineviz.compute.raycast.tables import padded_rows, reduction_table


@register_kernel_family
class TruncatedOctahedraFamily(KernelFamily):
    """Q_k on truncated octahedra: a bit set of relevant pieces and a written flag per cell
    cached per brick, and the cells' isovalue-independent ranges."""

    name = "to"
    define = "MODEL_TO"
    ghost_layers = 3
    cache_words = TO_WORDS + 1

    def extra_bytes(self, bricks: int) -> dict:
        return {"cell ranges": 2 * 8 * bricks}

    def upload(self, rc) -> dict:
        """Upload the padded samples and the tables of the truncated-octahedral model.

        From the core model: the 144 x 10 coefficient stencils of Q_k (dense: each tet's 28
        data offsets from its TO's base data point, flattened with the padded strides, and
        (144, 28, 16) weights, zero-padded), barycentric matrices
        (144, 4, 4); from :mod:`splineviz.compute.raycast.to_tables`: the (TO, tet) pieces per cell
        parity class and the union of the data each class reads (for the cell bounds).
        """
        import pyopencl.array as cla

        from splineviz.compute.raycast import segment_program, to_program, to_tables
        from splineviz.compute.raycast.to_tables import cell_classes
        from splineviz.core.partitions import truncated_octahedra as to
        from splineviz.core.splines import to_quadratic

        q = rc._device.queue
        k = to_k(self.model_kwargs)  # the core spline itself is not built (a float64 copy)
        ghost = self.ghost_layers
        if ghost != to_quadratic.GHOST_LAYERS:
            raise AssertionError("TO ghost layers differ from the core model")  # a bug
        rc._data = padded_device_samples(rc._device, rc.volume.data, ghost, rc._sample_type[0])
        _, py, pz = rc._data.shape
        strides = np.array([py * pz, pz, 1], dtype=np.int64)
        rc._strides = (py, pz)
        tables = to_tables.stencils(k)
        self._to_stencil = tables[0][0].shape[0]
        if any(o.shape[0] != self._to_stencil for o, _ in tables):
            raise AssertionError("TO stencils of different sizes")  # a bug: all read 28
        # dense (144, K, 16): per tet, per data value, its weights in the 10 coefficients
        # (a float16 of the kernel)
        self._to_dense = [
            cla.to_device(q, np.stack([o @ strides for o, _ in tables]).astype(np.int32)),
            cla.to_device(q, padded_rows(np.stack([w.T for _, w in tables]), 16))]
        rc._negmass = float(max(np.sum(np.clip(-w, 0, None), axis=1).max()
                                for _, w in tables))
        start, centre, tet = cell_classes()
        # base data point of each piece's TO relative to the cell corner: centre - 1/2
        base_off = np.rint(centre.astype(np.float64) - 0.5).astype(np.int64)
        self._ent = {
            "start": cla.to_device(q, start),
            "centre": cla.to_device(q, np.c_[centre, np.zeros(len(centre))].astype(np.float32)),
            "base": cla.to_device(q, (base_off @ strides).astype(np.int32)),
            "tet": cla.to_device(q, tet),
        }
        if np.diff(start).max() > 32 * TO_WORDS:
            raise AssertionError("more pieces per cell than the bit set holds")  # a bug
        # the data each class reads (its union: the conservative cell bounds and the private
        # copy the generated relevance test sums, see splineviz.compute.raycast.to_program)
        pts = to_tables.class_points(k, TO_WORDS)
        self._nunion = int(np.diff(pts["union_start"]).max())
        self._cls_start = cla.to_device(q, pts["union_start"].astype(np.int32))
        self._cls_offsets = cla.to_device(q, (pts["union"] @ strides).astype(np.int32))
        # the 2 x 2 x 2 sample blocks that hold the data of a level-1 octree node (classify.cl
        # brick_bounds; the node's first cell corner is padded sample 2a + ghost)
        blocks = np.unique((to_tables.node_union(k, TO_WORDS) + ghost) >> 1, axis=0)
        _, by, bz = ((n + 1) // 2 for n in rc._data.shape)
        self._node_blocks = cla.to_device(q, (blocks @ [by * bz, bz, 1]).astype(np.int32))
        self._nblocks = len(blocks)
        self.prelude = (to_program.relevance_source(k, TO_WORDS)
                        + to_program.subcell_source(TO_WORDS)
                        + segment_program.segment_source(2))
        self._bary = cla.to_device(q, np.ascontiguousarray(to.barycentric_matrices(), np.float32))
        self._red = cla.to_device(
            q, np.concatenate([reduction_table(k).ravel() for k in (2, 1)]).astype(np.int32))
        return {"MODEL_TO": 1, "NCOEF": 10, "GHOST": ghost, "NWORDS": TO_WORDS,
                "NUNION": self._nunion, "NODE_BLOCKS": self._nblocks,
                "SKIP_ACTIVE": SKIP_ACTIVE}

    def upload_samples(self, rc) -> None:
        """The new samples only: the tables and the generated source depend on ``k`` and
        the padded shape alone."""
        rc._data = padded_device_samples(rc._device, rc.volume.data, self.ghost_layers,
                                         rc._sample_type[0], out=rc._data)

    def allocate(self, rc) -> None:
        import pyopencl.array as cla

        # isovalue-independent cell ranges (raycast.cl), all (0, 255): "not known yet"
        q = rc._device.queue
        size = 8 * int(np.prod(rc._levels[0][1:]))
        if getattr(self, "_ranges", None) is None or self._ranges.size != size:
            self._ranges = cla.empty(q, size, np.uint16)
        fill(self._ranges, 0xFF00, q)  # uchar2 (lo 0, hi 255)

    def defines(self, rc) -> dict:
        return {"DEGREE": 2, "TET_SLACK": TET_SLACK, "GHOST": self.ghost_layers,
                "NWORDS": TO_WORDS, "NUNION": self._nunion, "TO_STENCIL": self._to_stencil}

    def cell_args(self) -> list:
        return [self._cls_start.data, self._cls_offsets.data]

    def node_args(self, rc) -> list:
        """The (min, max) of the 2 x 2 x 2 sample blocks and the offsets of the blocks that
        hold a node's data."""
        return [*sample_blocks(rc), self._node_blocks.data]

    def ray_args(self, rc) -> list:
        e = self._ent
        return [self._ranges.data, self._cls_start.data, self._cls_offsets.data,
                e["start"].data, e["centre"].data, e["base"].data, e["tet"].data,
                *(a.data for a in self._to_dense), self._bary.data, self._red.data]

    def classify(self, rc, listed, cells: np.ndarray, iso: np.float32):
        """Bit sets of the relevant pieces of every candidate cell (not cached: they would
        need a pool entry per candidate)."""
        import pyopencl.array as cla

        q = rc._device.queue
        n = len(cells)
        relevant, codes = np.zeros(n, np.int32), np.zeros((n, TO_WORDS), np.uint32)
        if n:
            nrel = cla.empty(q, n, np.int32)
            bits = cla.empty(q, n * TO_WORDS, np.uint32)
            _, cy, cz = rc._cells
            rc._ray_kernel("to_codes")(
                q, (n,), None, rc._data.data, np.int32(rc._strides[0]),
                np.int32(rc._strides[1]), np.int32(cy), np.int32(cz), listed.data,
                self._cls_start.data, self._cls_offsets.data, np.float32(rc._negmass), iso,
                bits.data, nrel.data)
            relevant, codes = nrel.get(queue=q), bits.get(queue=q).reshape(n, TO_WORDS)
        return relevant, codes


def to_k(model_kwargs: dict) -> float:
    """The ``k`` of Q_k from the model options, with the core model's default and check."""
    import inspect

    from splineviz.core.splines.to_quadratic import TOQuadraticSpline

    default = inspect.signature(TOQuadraticSpline).parameters["k"].default
    k = float(model_kwargs.get("k", default))
    if not k >= 1:
        raise RayCastError(f"Q_k needs k >= 1, got {k}")
    return k
