"""The ray caster's facade: :class:`RayCaster` (docs/api.md ``RayCaster``).

What every kernel family shares lives here: the device, the device samples (their type and
ghost layers come from the family), the min-max octree, the classification cache's slots and
pool, the frame buffers and the launch of the ray kernel; the model-specific tables, buffers,
defines and kernel arguments come from the model's :class:`~splineviz.compute.raycast.family.
KernelFamily` (see :mod:`splineviz.compute.raycast` for the pipeline).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from splineviz.compute.buffers import fill
from splineviz.compute.device import try_get_device
from splineviz.compute.program import get_kernel
from splineviz.compute.raycast.errors import RayCastError
from splineviz.compute.raycast.family import SKIP_ACTIVE, family_class
from splineviz.compute.raycast.frames import crop, empty_frame, world_hessian
from splineviz.compute.raycast.limits import Limits
from splineviz.compute.raycast.octree import octree_levels, octree_nodes
from splineviz.compute.raycast.samples import numpy_cell_bounds
from splineviz.core import frame as volume_frame
from splineviz.core import raycast_reference as ref
from splineviz.core.bricks import Placement
from splineviz.core.camera import Camera, parse_size
from splineviz.core.splines.registry import UnknownModelError, model_spec
from splineviz.core.volume import Volume

#: work-group size of the ray-casting kernel (pixels): fixed so the kernel is compiled once
RAY_GROUP = (8, 8)
#: most samples (ghost layers included) the kernels address with 32-bit offsets; past it they
#: are compiled with ``OFFSET64`` (64-bit sample offsets), when the device holds the volume
MAX_SAMPLES = 2**31 - 1
#: most cells a whole-grid pass (classify_all, skip_volume) numbers with 32-bit indices
MAX_CELLS = 2**31 - 1
#: epochs of the per-cell classification caches: 8 bits beside 24 bits of code or pool
#: index, 0 = never valid
MAX_EPOCH = 255
#: largest pool of the classification cache (24-bit entry indices beside the epoch; the
#: largest index marks a slot being allocated)
MAX_POOL = 2**24 - 2
#: share of the device's global memory the kept buffers may take (the frame buffers and the
#: compaction of classify_all need room beside them)
MEMORY_SHARE = 0.8


@dataclass
class Classification:
    """Every cell classified at once (:meth:`RayCaster.classify_all`).

    Attributes
    ----------
    cells : (n,) int32
        Flat indices of the candidate cells (value bounds straddle the isovalue), ascending.
    relevant : (n,) int32 or None
        Relevant tetrahedra per candidate (coefficients straddle the isovalue); ``None`` for
        the trilinear model.
    codes : (n,) uint32 or (n, TO_WORDS) uint32 or None
        Type-6: the 24-bit tet code per candidate cube; ``"to-quadratic"``: the bit set of the
        relevant (TO, tet) pieces of the cell's parity class; ``None`` for trilinear.
    """

    cells: np.ndarray
    relevant: np.ndarray | None
    codes: np.ndarray | None


def _shading_defines() -> dict:
    """Phong constants from :mod:`splineviz.core.raycast_reference` (one source of truth)."""
    d = {
        "AMBIENT": float(ref.AMBIENT),
        "DIFFUSE": float(ref.DIFFUSE),
        "SPECULAR": float(ref.SPECULAR),
        "SHININESS": float(ref.SHININESS),
        "SKIP_ACTIVE": SKIP_ACTIVE,
    }
    for prefix, rgb in (("FRONT", ref.FRONT_COLOR), ("BACK", ref.BACK_COLOR)):
        for ch, v in zip("RGB", rgb, strict=True):
            d[f"{prefix}_{ch}"] = float(v)
    for ch, v in zip("RGB", ref.BACKGROUND, strict=True):
        d[f"BG_{ch}"] = int(round(v * 255))
    return d


class RayCaster:
    """Geometry-free ray caster of the isosurface of a spline model (docs/api.md).

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array
    model : str
        Spline model name (see :data:`splineviz.core.splines.MODELS`).
    device : str or None
        ``"gpu"``, ``"cpu"``, ``"numpy"`` or a device-name substring; ``None`` reads
        ``$SPLINEVIZ_DEVICE`` and otherwise prefers a GPU.
    **model_kwargs
        Passed to :func:`splineviz.build_spline` (e.g. ``k`` of ``"to-quadratic"``).

    Notes
    -----
    Classification is visible-first: :meth:`set_isovalue` takes constant time and the first
    frame after it classifies the cells its rays reach (so a reduced-size frame right after
    a change is a cheap preview). ``stats``: ``active_cells``/``active_tets`` count the
    relevant cells/tets found so far at this isovalue (type-6 and TO; ``None`` for
    trilinear) and ``classified`` is ``"visible"``; after :meth:`classify_all` they are the
    totals and ``classified`` is ``"all"``. ``classify_s`` is the time of the isovalue change.
    A volume the device cannot hold raises :class:`RayCastError` before anything is allocated
    (:meth:`limits` says what it needs); past 2^31 device samples the kernels are compiled
    with 64-bit sample offsets. ``family`` is the model's kernel family (None: the NumPy
    reference renders it).

    Examples
    --------
    >>> import numpy as np, splineviz as sv
    >>> x = np.linspace(-1, 1, 9)
    >>> vol = sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2))
    >>> rc = sv.RayCaster(vol, model="trilinear", device="cpu")
    >>> rc.set_isovalue(0.5)
    >>> frame = rc.render(sv.Camera((4, -20, 6), (4, 4, 4)), size=(32, 24))
    >>> frame.hit.shape, bool(frame.hit[12, 16])
    ((24, 32), True)
    """

    def __init__(self, volume, model: str = "cubic-c1", device: str | None = None,
                 **model_kwargs):
        try:
            model_spec(model)
        except UnknownModelError as exc:
            raise RayCastError(str(exc)) from None
        self.model = model
        self._model_kwargs = model_kwargs
        family = family_class(model)
        #: the model's kernel family (None: only the NumPy reference renders it)
        self.family = None if family is None else family(model, model_kwargs)
        self._device = None
        self._offsets_64 = False
        if self.family is not None:
            self._device = try_get_device(device)
        self._isovalue = None
        self._spline = None
        self.stats = {"active_cells": None, "active_tets": None, "classify_s": None,
                      "render_s": None, "device": "numpy", "path": "numpy", "classified": None}
        if self._device is not None:
            self.stats["device"] = self._device.name
            self.stats["path"] = "opencl"
        self.set_volume(volume)

    @property
    def _family(self) -> str | None:
        """The ``-D`` define of the kernel family (None: NumPy path only)."""
        return None if self.family is None else self.family.define

    def __getattr__(self, name: str):
        # the family's buffers and tables (e.g. the TO cell ranges), for inspection and tests
        family = self.__dict__.get("family")
        if name.startswith("_") and not name.startswith("__") and family is not None \
                and name in family.__dict__:
            return family.__dict__[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    # -- data ----------------------------------------------------------------------------

    @property
    def volume(self) -> Volume:
        return self._volume

    @property
    def isovalue(self):
        return self._isovalue

    @property
    def spline(self):
        """The core spline model (built lazily; used by the NumPy path and for checks)."""
        if self._spline is None:
            from splineviz.core.splines import build_spline

            self._spline = build_spline(self._volume, self.model, **self._model_kwargs)
        return self._spline

    def set_volume(self, volume) -> None:
        """Replace the data (e.g. after smoothing); cell bounds and octree are rebuilt.

        Data of the same shape and device sample type (the next step of a time series) are
        written into the device buffers there are, the programs and tables kept; the frames
        are those of a fresh caster of the new data.

        Raises
        ------
        RayCastError
            When the device cannot hold the volume and its octree.
        """
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        if min(volume.shape) < 2:
            raise RayCastError(f"ray casting needs at least 2 samples per axis, got {volume.shape}")
        cells = self._grid(volume.shape)
        same = False
        if self._device is not None:
            sample_type = self.family.sample_type(volume.data)
            limits = self.limits(volume.shape, np.dtype(sample_type[0]).itemsize)
            self._check_limits(limits)
            # the next step of a time series: programs, tables and buffers stay
            same = (getattr(self, "_data", None) is not None and cells == self._cells
                    and volume.shape == self._volume.shape
                    and sample_type == self._sample_type
                    and limits.offsets_64 == self._offsets_64)
            self._sample_type = sample_type
            self._offsets_64 = limits.offsets_64
        self._volume = volume
        self._spline = None
        self._cells = cells
        if same:
            self._upload_samples()
        elif self._device is not None:
            self._upload()
        if self._isovalue is not None:
            self._new_epoch()

    def _ghost(self) -> int:
        """Ghost layers of the device samples."""
        return 0 if self.family is None else self.family.ghost_layers

    def _grid(self, shape) -> tuple[int, int, int]:
        """Cells of the traversal grid of ``shape`` samples: unit cells between samples, or
        cubes centred at the samples (one more per axis)."""
        shift = int(self.family is not None and self.family.centred)
        return tuple(int(n) - 1 + shift for n in shape)

    def device_bytes(self, shape, cells, itemsize: int = 4) -> dict:
        """Bytes of the device buffers kept for a volume of ``shape`` (per buffer name).

        Parameters
        ----------
        shape : (3,) samples per axis
        cells : (3,) cells of the traversal grid per axis
        itemsize : bytes per device sample (see :func:`sample_type_for`)
        """
        ghost = self._ghost()
        levels = octree_levels(cells)
        bricks = int(np.prod(levels[0][1:]))
        out = {"samples": itemsize * int(np.prod([n + 2 * ghost for n in shape])),
               "octree": 8 * octree_nodes(levels)}
        if self._cached():
            out["classification cache"] = 4 * (bricks + self._entry_words()
                                               * _initial_pool(bricks))
        if self.family is not None:
            out.update(self.family.extra_bytes(bricks))
        return out

    def _cached(self) -> bool:
        """Whether the rays cache the per-cell classification of this model."""
        return self.family is not None and self.family.cache_words > 0

    def _entry_words(self) -> int:
        """32-bit words of a pool entry of the classification cache (8 cells of a brick)."""
        return 8 * self.family.cache_words

    def limits(self, shape=None, itemsize: int | None = None, cells=None) -> Limits:
        """What a volume of ``shape`` samples needs of this caster's device and what the
        device offers (OpenCL path): tests and front ends ask here instead of reading the
        device's memory themselves.

        Parameters
        ----------
        shape : (3,) samples per axis; default the current volume's
        itemsize : bytes per device sample; default the current volume's
        cells : (3,) cells of the traversal grid; default those of ``shape``
        """
        if self._device is None:
            raise RayCastError("device limits exist on the OpenCL path")
        shape = tuple(int(n) for n in (self._volume.shape if shape is None else shape))
        if itemsize is None:
            itemsize = np.dtype(self._sample_type[0]).itemsize
        dev = self._device.device
        samples = int(np.prod([n + 2 * self._ghost() for n in shape]))
        cells = self._grid(shape) if cells is None else tuple(cells)
        return Limits(shape, samples, self.device_bytes(shape, cells, itemsize),
                      MAX_SAMPLES, int(MEMORY_SHARE * dev.global_mem_size),
                      int(dev.max_mem_alloc_size))

    def _check_device_memory(self, shape, cells, itemsize: int = 4) -> None:
        """Refuse, before allocating anything, a volume the device cannot hold (``cells``:
        of the traversal grid, as :meth:`device_bytes` takes them)."""
        self._check_limits(self.limits(shape, itemsize, cells))

    def _check_limits(self, limits: Limits) -> None:
        """Refuse a volume whose buffers the device cannot hold; one past 2^31 samples is
        cast with 64-bit sample offsets (``OFFSET64``) when it fits."""
        if limits.fits:
            return
        need, gib = limits.need, 2.0**30
        big = max(need, key=need.get)
        dev = self._device.device
        raise RayCastError(
            f"a {'x'.join(map(str, limits.shape))} volume with the {self.model} "
            f"model needs {limits.total / gib:.2f} GiB of device memory ({big}: "
            f"{need[big] / gib:.2f} GiB), but {self._device.name} has "
            f"{dev.global_mem_size / gib:.2f} GiB (at most {dev.max_mem_alloc_size / gib:.2f} "
            f"GiB per buffer); open it as a chunked volume (Zarr, HDF5 or sv.Volume.from_dask), "
            f"which is rendered in bricks, or downsample it")

    #: device bytes per pixel of the frame buffers of _render_cl: hit flag, position and
    #: normal (float4 each), depth, RGBA colour; the largest single buffer is a float4
    FRAME_BYTES_PER_PIXEL = 1 + 16 + 16 + 4 + 4

    def _check_frame_memory(self, w: int, h: int) -> None:
        """Refuse, before allocating anything, a frame the device cannot hold (pyopencl would
        fail with INVALID_BUFFER_SIZE or MEM_OBJECT_ALLOCATION_FAILURE half-way)."""
        dev = self._device.device
        n = w * h
        if n * 16 > dev.max_mem_alloc_size or \
                n * self.FRAME_BYTES_PER_PIXEL > 0.5 * dev.global_mem_size:
            raise RayCastError(
                f"a {w}x{h} frame needs {n * self.FRAME_BYTES_PER_PIXEL / 2**30:.2f} GiB of "
                f"device memory, more than {self._device.name} offers (at most "
                f"{dev.max_mem_alloc_size / 2**30:.2f} GiB per buffer); render a smaller image")

    def _defines(self) -> dict:
        """-D options of this model's ray-casting programs."""
        d = {self.family.define: 1, "DATA_T": self._sample_type[1], **_shading_defines(),
             **self.family.defines(self)}
        if self._offsets_64:
            d["OFFSET64"] = 1
        return d

    def _ray_kernel(self, kernel: str, bricks: bool = False):
        """Kernel ``kernel`` of raycast.cl for this model (its defines and generated prelude);
        ``bricks``: the variant that casts a brick of a bigger volume (``BRICKS``)."""
        defines = {**self._defines(), "BRICKS": 1} if bricks else self._defines()
        return get_kernel(self._device.context, "raycast", kernel, defines, self._prelude())

    def _prelude(self) -> str:
        """The family's generated source, after the sample offset type it may use."""
        if not self.family.prelude:
            return ""
        return f"#define offset_t {'long' if self._offsets_64 else 'int'}\n{self.family.prelude}"

    def _upload(self):
        """Samples and tables (the family's), min-max octree and the cleared classification
        cache on the device."""
        import pyopencl.array as cla

        dev = self._device
        q = dev.queue
        levels = octree_levels(self._cells)
        self._levels = levels
        self._levels_buf = cla.to_device(q, np.array(levels, dtype=np.int32).reshape(-1, 4))
        # float2 (lo, hi) per node
        self._bounds = cla.empty(q, 2 * octree_nodes(levels), np.float32)
        tables = self.family.upload(self)
        self._cls_defines = {**tables, "DATA_T": self._sample_type[1]}
        if self._offsets_64:
            self._cls_defines["OFFSET64"] = 1
        self._build_octree()
        self._epoch = 0
        if self._cached():
            # the classification cache (raycast.cl): per level-1 brick a slot, (epoch << 24) |
            # pool entry; counts: cells and tets classified at this epoch, entries asked for
            bricks = int(np.prod(levels[0][1:]))
            self._slots = cla.empty(q, bricks, np.uint32)
            fill(self._slots, 0, q)
            self._counts = cla.zeros(q, 3, np.int32)
            self._pool_cap = _initial_pool(bricks)
            self._pool = cla.empty(q, self._pool_cap * self._entry_words(), np.uint32)
        self.family.allocate(self)
        q.finish()

    def _upload_samples(self):
        """New samples of the same shape and device type (a time step): the samples and the
        octree are rewritten in their buffers, the family's per-data buffers cleared; the
        programs, tables, the cache's slots and pool stay (the new epoch that follows
        invalidates every cached classification)."""
        self.family.upload_samples(self)
        self._build_octree()
        self.family.allocate(self)
        self._device.queue.finish()

    def _build_octree(self) -> None:
        """The min-max octree of the device samples, on the device (classify.cl)."""
        q, ctx, levels = self._device.queue, self._device.context, self._levels
        get_kernel(ctx, "classify", "brick_bounds", self._cls_defines)(
            q, levels[0][:0:-1], None, *self._cell_args(), *self.family.node_args(self),
            self._bounds.data)
        k_reduce = get_kernel(ctx, "classify", "reduce_level", self._cls_defines)
        for (so, sx, sy, sz), (do, dx, dy, dz) in zip(levels[:-1], levels[1:], strict=True):
            k_reduce(q, (dz, dy, dx), None, self._bounds.data,
                     *(np.int32(v) for v in (so, sx, sy, sz, do, dx, dy, dz)))

    def _cell_args(self) -> list:
        """Leading arguments of the per-cell kernels of classify.cl: data, strides, cells,
        negative mass (and the family's)."""
        return [self._data.data, *(np.int32(v) for v in self._strides),
                *(np.int32(c) for c in self._cells), np.float32(self._negmass),
                *self.family.cell_args()]

    # -- classification ------------------------------------------------------------------

    def set_isovalue(self, value) -> None:
        """Set the isovalue.

        Constant time: cells are classified by the rays that reach them (visible-first), and
        type-6 tet codes cached for an older isovalue become invalid by a new cache epoch.
        ``stats["active_cells"]``/``["active_tets"]`` then count, for the type-6 models, the
        relevant cubes/tets found so far by the frames at this isovalue (``None`` for the
        other models) until :meth:`classify_all` gives the totals.
        """
        value = float(value)
        if not np.isfinite(value):
            raise RayCastError(f"the isovalue must be finite, got {value}")
        t = time.perf_counter()
        if value != self._isovalue:
            self._isovalue = value
            self._new_epoch()
        self.stats["classify_s"] = time.perf_counter() - t

    def _new_epoch(self) -> None:
        """Invalidate every cached classification (new isovalue or new data)."""
        visible = 0 if self._cached() else None
        if self._device is None:
            visible = None
            if self.family is not None:
                visible = self.family.numpy_candidates(self._volume, self._isovalue)
        elif self._cached():
            q = self._device.queue
            self._epoch += 1
            if self._epoch > MAX_EPOCH:
                # the 8-bit stamp wraps: clear once every MAX_EPOCH isovalues
                fill(self._slots, 0, q)
                self._epoch = 1
            self._counts.fill(np.int32(0), queue=q)  # the pool is refilled from entry 0
        self.stats.update(active_cells=visible, active_tets=visible, classified="visible")
        if self.family is not None and not self.family.counts_tets:
            self.stats["active_tets"] = None

    def classify_all(self) -> Classification:
        """Classify every cell at the current isovalue (OpenCL path).

        Candidate cells (value bounds straddle the isovalue) by a prefix-scan compaction
        (thesis Fig. 6.3); for the tetrahedral models the relevant tets of each candidate. The
        type-6 tet codes go into the cache, so the next frames use them (TO bit sets do not:
        they would need a pool entry per candidate). Sets
        ``stats["active_cells"]`` (cells with a relevant tet; trilinear: candidates) and
        ``stats["active_tets"]``. Seconds on big volumes: frames do not need it.
        """
        import pyopencl.array as cla

        if self._device is None or self._isovalue is None:
            raise RayCastError("classify_all needs the OpenCL path and an isovalue")
        self._check_cell_indices("classify_all")
        q = self._device.queue
        ctx = self._device.context
        iso = np.float32(self._isovalue)
        ncell = int(np.prod(self._cells))
        flags = cla.empty(q, ncell, np.int32)
        get_kernel(ctx, "classify", "candidates", self._cls_defines)(
            q, self._cells[::-1], None, *self._cell_args(), iso, flags.data)
        listed = cla.empty(q, ncell, np.int32)
        count = cla.empty(q, 1, np.int32)
        _compaction_kernel(ctx)(flags, listed, count, queue=q)
        del flags
        n = int(count.get(queue=q)[0])
        cells = listed[:n].get(queue=q) if n else np.zeros(0, np.int32)
        relevant, codes = self.family.classify(self, listed, cells, iso)
        if relevant is None:
            self.stats.update(active_cells=n, active_tets=None)
        else:
            self.stats.update(active_cells=int(np.count_nonzero(relevant)),
                              active_tets=int(relevant.sum()))
        self.stats["classified"] = "all"
        return Classification(cells, relevant, codes)

    def _check_cell_indices(self, what: str) -> None:
        """Refuse a whole-grid pass whose flat cell indices do not fit 32 bits (the frames,
        which need no such pass, cast any volume the device holds)."""
        if int(np.prod(self._cells)) > MAX_CELLS:
            raise RayCastError(f"{what} numbers the {'x'.join(map(str, self._cells))} cells "
                               f"with 32-bit indices; render frames instead, which classify "
                               f"the cells they reach")

    def active_cells(self) -> np.ndarray:
        """Flat indices (cell (i, j, k) -> (i*(ny-1) + j)*(nz-1) + k) of the candidate cells."""
        if self._isovalue is None:
            raise RayCastError("set an isovalue before asking for active cells")
        if self._device is None:
            vmin, vmax = numpy_cell_bounds(self._volume.data)
            iso = np.float32(self._isovalue)
            return np.flatnonzero(((vmin <= iso) & (iso <= vmax)).ravel()).astype(np.int32)
        return self.classify_all().cells

    @property
    def negative_mass(self) -> float:
        """Largest sum of negative weights of a B-coefficient as an affine combination of
        samples (0 for trilinear; OpenCL path): the widening of the octree's value bounds."""
        if self._device is None:
            raise RayCastError("the negative weight mass is known on the OpenCL path")
        return float(self._negmass)

    def value_bounds(self) -> tuple[float, float]:
        """Conservative (min, max) of the spline over the whole data box: the root of the
        min-max octree (OpenCL path), e.g. to skip a brick of a bigger volume at another
        isovalue without reading it again."""
        if self._device is None:
            raise RayCastError("value bounds come from the octree of the OpenCL path")
        root = self._levels[-1][0]
        lo, hi = self._bounds[2 * root:2 * root + 2].get(queue=self._device.queue)
        return float(lo), float(hi)

    def skip_volume(self) -> np.ndarray:
        """(cx, cy, cz) uint8 skip codes (255 = candidate, else the empty macro level) that the
        ray kernel derives from the min-max octree at the current isovalue; OpenCL path."""
        import pyopencl.array as cla

        if self._device is None or self._isovalue is None:
            raise RayCastError("the skip volume exists on the OpenCL path after set_isovalue")
        self._check_cell_indices("the skip volume")
        q = self._device.queue
        skip = cla.empty(q, int(np.prod(self._cells)), np.uint8)
        cx, cy, cz = self._cells
        self._ray_kernel("skip_codes")(
            q, (cz, cy, cx), None, self._bounds.data, self._levels_buf.data,
            np.int32(len(self._levels)), np.int32(cx), np.int32(cy), np.int32(cz),
            np.float32(self._isovalue), skip.data)
        return skip.get(queue=q).reshape(self._cells)

    # -- rendering -----------------------------------------------------------------------

    def render(self, camera: Camera, size=(640, 480), clip_planes=(),
               hessian: bool = False, window=None, placement: Placement | None = None
               ) -> ref.Frame:
        """Ray cast one frame.

        Parameters
        ----------
        camera : Camera
        size : (width, height) or "WxH"
        clip_planes : sequence of (origin, normal); each keeps the side its normal points to
        hessian : bool
            Also return the spline's Hessian and gradient norm at every hit
            (``Frame.hessian``, ``Frame.gradient_norm``), computed in the kernel from the hit
            piece's B-coefficients (colour by curvature). The NumPy path leaves them None.
        window : (r0, r1, c0, c1), optional
            Cast only the pixels of these half-open rows and columns of the ``size`` frame
            (e.g. the screen footprint of a brick); the same rays as in the whole frame.
        placement : Placement, optional
            This caster's volume is a brick of a bigger volume
            (:class:`splineviz.core.bricks.Placement`): the rays are those of the whole
            volume (its index space, data box, clipping range and clip planes) restricted to
            the brick's cells, so a hit is the hit of a single cast of the whole volume, bit
            for bit (OpenCL path; the NumPy path clips the brick's own rays to its box).

        Returns
        -------
        Frame
            Of the window's size when one is given; positions, normals and Hessians in
            world. A volume with a direction (an oblique scan) is cast in its own frame,
            camera and clip planes moved there rigidly (:mod:`splineviz.core.frame`).
        """
        if self._isovalue is None:
            raise RayCastError("set an isovalue before rendering")
        if not isinstance(camera, Camera):
            raise RayCastError("render needs a splineviz Camera")
        w, h = parse_size(size)
        r0, r1, c0, c1 = (0, h, 0, w) if window is None else (int(v) for v in window)
        if not (0 <= r0 <= r1 <= h and 0 <= c0 <= c1 <= w):
            raise RayCastError(f"the window {tuple(window)} (rows r0, r1, columns c0, c1) is "
                               f"not inside the {w}x{h} frame")
        planes = volume_frame.planes_to_volume(self._volume,
                                               ref.normalize_clip_planes(clip_planes))
        camera = volume_frame.camera_to_volume(self._volume, camera)
        if placement is not None:
            self._check_placement(placement)
        if self._device is not None:
            self._check_frame_memory(c1 - c0, r1 - r0)
        t = time.perf_counter()
        if self._device is None:
            if placement is not None:
                camera = self._whole_clipping(camera, placement)
                planes = np.concatenate([planes, ref.normalize_clip_planes(
                    placement.face_planes(self._volume.spacing))])
            frame = crop(ref.reference_raycast(self.spline, camera, (w, h), self._isovalue,
                                                planes), (r0, r1, c0, c1))
        else:
            frame = self._render_cl(camera, w, h, planes, hessian, (r0, r1, c0, c1), placement)
        self.stats["render_s"] = time.perf_counter() - t
        return volume_frame.frame_to_world(self._volume, frame)

    def _check_placement(self, placement: Placement) -> None:
        """Refuse a placement that does not fit this caster's volume and model."""
        if self.family is None or not self.family.bricks:
            raise RayCastError(f"the {self.model} model cannot be rendered in bricks (a "
                               f"brick's samples do not carry the whole volume's spline)")
        if placement.centred != self.family.centred:
            raise RayCastError(f"the brick's cells do not match the {self.model} model's "
                               f"({'centred' if placement.centred else 'unit'} cells)")
        for a in range(3):
            (lo, hi), off = placement.cells[a], placement.offset[a]
            if not (0 <= off and off + self._volume.shape[a] <= placement.shape[a]
                    and off <= lo < hi <= off + self._cells[a]):
                raise RayCastError(
                    f"the brick's cells {placement.cells} are not within its samples "
                    f"{self._volume.shape} at offset {placement.offset} of a volume of "
                    f"{placement.shape}")

    def _whole_clipping(self, camera: Camera, placement: Placement) -> Camera:
        """``camera`` with the clipping range of the whole volume (window depths agree)."""
        spacing = self._volume.spacing
        bounds = [(o, o + (n - 1) * s) for o, n, s in zip(
            placement.origin, placement.shape, spacing, strict=True)]
        return Camera(camera.position, camera.focal_point, camera.view_up, camera.view_angle,
                      camera.fit_clipping_range(bounds))

    def _cache_args(self) -> list:
        """Kernel arguments of the classification cache: slots, pool, capacity, epoch, the
        level-1 strides, counts and the negative weight mass of the cheap bounds."""
        _, _, by, bz = self._levels[0]
        return [self._slots.data, self._pool.data, np.int32(self._pool_cap),
                np.uint32(self._epoch), np.int32(by), np.int32(bz), self._counts.data,
                np.float32(self._negmass)]

    def _grow_pool(self, asked: int) -> None:
        """Make the pool hold ``asked`` entries, its cached entries kept (their indices stay
        valid); the bricks a full pool could not take are cached by the next frames."""
        import pyopencl as cl
        import pyopencl.array as cla

        q = self._device.queue
        old = self._pool_cap
        if asked <= old:
            return
        cap = min(MAX_POOL, max(2 * old, asked * 5 // 4))
        if cap > old:
            pool = cla.empty(q, cap * self._entry_words(), np.uint32)
            cl.enqueue_copy(q, pool.data, self._pool.data, byte_count=self._pool.nbytes)
            self._pool, self._pool_cap = pool, cap
        # entries asked for past the old end were never written: hand them out again
        used = int(self._counts[2:3].get(queue=q)[0])
        self._counts[2:3].set(np.array([min(used, old)], np.int32), queue=q)

    def _render_cl(self, camera, w, h, planes, hessian: bool = False, window=None,
                   placement: Placement | None = None) -> ref.Frame:
        import pyopencl.array as cla
        from pyopencl import cltypes

        dev = self._device
        q = dev.queue
        k_ray = self._ray_kernel("raycast", bricks=placement is not None)
        vol = self._volume
        r0, r1, c0, c1 = (0, h, 0, w) if window is None else window
        ww, wh = c1 - c0, r1 - r0
        if ww == 0 or wh == 0:
            return empty_frame(wh, ww, hessian)
        # a brick casts in the whole volume's index space (the same floats as a single cast)
        if placement is None:
            origin = np.asarray(vol.origin, dtype=np.float64)
            shape = vol.shape
            grid = hi = self._cells
            lo = off = (0, 0, 0)
        else:
            camera = self._whole_clipping(camera, placement)
            origin = np.asarray(placement.origin, dtype=np.float64)
            shape = placement.shape
            grid = self._grid(shape)
            lo, hi = zip(*placement.cells, strict=True)
            off = placement.offset
        spacing = np.asarray(vol.spacing, dtype=np.float64)
        right, up, dop = camera.basis()
        tan_half = np.tan(np.radians(camera.view_angle) / 2.0)
        eye = np.asarray(camera.position, dtype=np.float64)
        eye_u = (eye - origin) / spacing
        clip = camera.fit_clipping_range(vol.bounds)
        depth_a, depth_b = camera.projection_constants(clip)
        # planes to index space: dot(x - o, n) = dot(u, spacing n) + dot(origin - o, n)
        pl = np.zeros((max(len(planes), 1), 4), dtype=np.float32)
        for i, (po, pn) in enumerate(planes):
            pl[i, :3] = spacing * pn
            pl[i, 3] = np.dot(origin - po, pn)
        planes_buf = cla.to_device(q, pl)

        def f3(v):
            return cltypes.make_float3(*(float(x) for x in v))

        def i3(v):
            return cltypes.make_int3(*(int(x) for x in v))

        n = ww * wh
        hit = cla.empty(q, n, np.uint8)
        pos = cla.empty(q, (n, 4), np.float32)
        nor = cla.empty(q, (n, 4), np.float32)
        depth = cla.empty(q, n, np.float32)
        color = cla.empty(q, (n, 4), np.uint8)
        # one float8 per pixel only when asked for (32 bytes a pixel otherwise unused)
        hess = cla.empty(q, (n if hessian else 1, 8), np.float32)
        nx, ny, nz = shape
        model_args = [*self._cache_args()] if self._cached() else []
        model_args += self.family.ray_args(self)
        shift = 0.5 if self.family.centred else 0.0
        # a fixed work-group size, the launch padded to whole groups: PoCL compiles a kernel
        # per work-group size, and one chosen from each frame size made every new preview
        # size a 0.2-0.5 s compile in the middle of a drag
        gx, gy = RAY_GROUP
        k_ray(q, (-(-ww // gx) * gx, -(-wh // gy) * gy), RAY_GROUP, self._data.data,
              np.int32(nx), np.int32(ny), np.int32(nz),
              np.int32(self._strides[0]), np.int32(self._strides[1]),
              i3(grid), i3(lo), i3(hi), i3(off), np.float32(shift),
              self._bounds.data, self._levels_buf.data, np.int32(len(self._levels)),
              *model_args, np.float32(self._isovalue), f3(eye_u), f3(dop),
              f3(right * tan_half * w / h), f3(up * tan_half), f3(1.0 / spacing),
              planes_buf.data, np.int32(len(planes)), np.float32(depth_a),
              np.float32(depth_b), hit.data, pos.data, nor.data, depth.data, color.data,
              np.int32(bool(hessian)), hess.data, np.int32(w), np.int32(h), np.int32(c0),
              np.int32(r0), np.int32(ww), np.int32(wh))
        if self._cached():
            cells, tets, asked = (int(v) for v in self._counts.get(queue=q))
            if self.stats.get("classified") == "visible":
                self.stats.update(active_cells=cells, active_tets=tets)
            self._grow_pool(asked)
        hit_h = hit.get(queue=q).astype(bool).reshape(wh, ww)

        def position():
            pos_h = pos.get(queue=q).reshape(wh, ww, 4)
            return np.where(hit_h[..., None],
                            origin + spacing * pos_h[..., :3].astype(np.float64), np.nan)

        def normal():
            return nor.get(queue=q).reshape(wh, ww, 4)[..., :3].astype(np.float64)

        hess_w = grad_norm = None
        if hessian:
            hess_w, grad_norm = world_hessian(hess.get(queue=q).reshape(wh, ww, 8))
        return ref.Frame(hit_h, position, normal, depth.get(queue=q).reshape(wh, ww),
                         color.get(queue=q).reshape(wh, ww, 4), hess_w, grad_norm)



def _initial_pool(bricks: int) -> int:
    """Entries of a new pool: enough for a view of a typical surface; it grows on demand."""
    return int(min(MAX_POOL, max(4096, bricks // 32)))





_scan_cache: dict = {}


def _compaction_kernel(context):
    """Stream compaction by a prefix scan (thesis Fig. 6.3): flags -> indices of ones."""
    key = context.int_ptr
    knl = _scan_cache.get(key)
    if knl is None:
        from pyopencl.scan import GenericScanKernel

        knl = GenericScanKernel(
            context, np.int32,
            arguments="__global const int *flags, __global int *out, __global int *count",
            input_expr="flags[i]",
            scan_expr="a+b", neutral="0",
            output_statement="""
                if (prev_item != item) out[item - 1] = i;
                if (i + 1 == N) count[0] = item;
            """,
        )
        _scan_cache[key] = knl
    return knl

