"""OpenCL ray casting of spline isosurfaces (thesis §6.1.1, §6.2; DESIGN.md ``RayCaster``).

Pipeline on the device, without a CPU round trip of the volume:

* on a data change (isovalue-independent, thesis §6.1.1, §6.2.1): the samples (padded with
  ghost layers where the model needs them, written straight into a device buffer) and a
  min-max octree of conservative value bounds, stored from level 1 (bricks of 2^3 cells);
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

Models with an OpenCL kernel:

* ``"trilinear"``: cells between samples; the restriction to the ray in a cell is an exact
  cubic (split at its critical points, so no root is missed).
* ``"cubic-c1"``, ``"super-quadratic"`` (type-6, §4.4): cubes centred at the samples. Cube
  bounds from the 27-point stencil (every coefficient is an affine combination of it, widened
  by the negative weight mass). A cube's tet code comes from its determining set and the
  averaging rules (§5.1-5.2). The ray part inside each relevant tet comes from the tet's four
  barycentric plane equations (§6.2.2), its coefficients from the stencil with the core
  model's masks, the Bernstein coefficients of the segment from blossoms (§6.1.2), the first
  root by the same monotone-piece cubic solver, the gradient from the last de Casteljau step.
  Deviation from Listing 6.2: tets of a cube are clipped independently instead of walked via
  the neighbour table (same result, no special cases at cube faces).
* ``"to-quadratic"`` (truncated octahedra, §5.2): unit cells of the grid with per-parity-class
  tables of the (TO, tet) pieces meeting a cell; a cell's relevance bit set computes each
  distinct B-net point of its pieces once, and the ray tests only the relevant pieces of the
  subcells (5^3 per cell) its segment crosses. Each classified cell's range (the min/max of
  its points, 2 bytes) is kept while the data stay, so a later isovalue outside it skips the
  cell without its sums (isovalue-independent work once per data change, thesis §6.1.1).

A brick of a bigger volume (:mod:`splineviz.compute.bricked`) is cast by the same kernel,
compiled with ``BRICKS``, in the whole volume's coordinates and over a window of the frame
(``RayCaster.render(placement=..., window=...)``): its hits are those of one cast of the
whole volume, bit for bit.

Other models render through the NumPy reference ray caster
(:mod:`splineviz.core.raycast_reference`); ``stats["path"]`` says which path made the frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from splineviz.compute.device import get_device, try_get_device
from splineviz.compute.program import get_kernel
from splineviz.core import raycast_reference as ref
from splineviz.core.bricks import Placement
from splineviz.core.camera import Camera, parse_size
from splineviz.core.errors import SplinevizError
from splineviz.core.splines.registry import KERNEL_FAMILIES, MODELS
from splineviz.core.volume import Volume

#: work-group size of the ray-casting kernel (pixels): fixed so the kernel is compiled once
RAY_GROUP = (8, 8)
#: most samples (ghost layers included) one ray caster's kernels address with 32-bit ints
MAX_SAMPLES = 2**31 - 1
#: ghost layers of the padded samples per kernel family (the registry's, per family define)
GHOSTS = {define: max((s.ghost_layers for s in MODELS.values() if s.kernel_define == define),
                      default=0) for define in KERNEL_FAMILIES.values()}


def kernel_define(model: str) -> str | None:
    """The ``-D`` define of the OpenCL kernel family that ray casts ``model`` (from the model
    registry), or None when only the NumPy reference renders it."""
    spec = MODELS.get(model)
    return None if spec is None else spec.kernel_define
#: 32-bit words of a cell's bit set of relevant (TO, tet) pieces (<= 144 per cell)
TO_WORDS = 5
#: slack of the barycentric inside test of a tetrahedron (rays on shared faces)
TET_SLACK = 1e-6
#: skip code of a candidate cell (raycast.cl skip_codes)
SKIP_ACTIVE = 255
#: epochs of the per-cell classification caches: 8 bits beside 24 bits of code or pool
#: index, 0 = never valid
MAX_EPOCH = 255
#: largest pool of the classification cache (24-bit entry indices beside the epoch; the
#: largest index marks a slot being allocated)
MAX_POOL = 2**24 - 2
#: families whose per-cell classification the rays cache
CACHED = ("MODEL_TYPE6", "MODEL_TO")


class RayCastError(SplinevizError, ValueError):
    """Bad ray-casting input (unknown model, volume too small or too big, no isovalue set)."""


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


def _octree_levels(cells: tuple[int, int, int]) -> list[tuple[int, int, int, int]]:
    """(offset, nx, ny, nz) of the stored min-max octree levels 1, 2, ... (nodes of 2^L
    cells; level 0, the cells, is not stored: see classify.cl)."""
    levels = []
    off = 0
    dims = tuple(cells)
    while True:
        dims = tuple((n + 1) // 2 for n in dims)
        levels.append((off, *dims))
        off += int(np.prod(dims))
        if max(dims) == 1:
            return levels


def _octree_nodes(levels) -> int:
    """Nodes of all stored octree levels."""
    return levels[-1][0] + int(np.prod(levels[-1][1:]))


#: device sample types tried in order (numpy type, OpenCL C type) for integer-valued data
SAMPLE_TYPES = ((np.uint8, "uchar"), (np.int16, "short"), (np.uint16, "ushort"))


def sample_type_for(data: np.ndarray, ghost: int) -> tuple[type, str]:
    """The device type of the samples: the smallest integer type that holds them exactly with
    ``ghost`` linearly extrapolated layers (uint8/uint16 data, which :class:`Volume` keeps as
    float32: 4x/2x less device memory and bandwidth), else float32.

    Parameters
    ----------
    data : (nx, ny, nz) float32
    ghost : ghost layers (each axis' extrapolation widens the value range by ``2 ghost``
        times its width, and integers stay integers)

    Returns
    -------
    (numpy type, OpenCL C type name)
    """
    flat = data.reshape(len(data), -1)
    step = max(1, 2**24 // flat.shape[1])  # slabs of about 16 M samples: no big temporaries
    lo, hi = np.inf, -np.inf
    for i in range(0, len(flat), step):
        s = flat[i:i + step]
        if not np.array_equal(s, np.rint(s)):  # fractions, NaN or inf
            return np.float32, "float"
        lo, hi = min(lo, float(s.min())), max(hi, float(s.max()))
    grow = (hi - lo) * ghost * sum((1 + 2 * ghost) ** a for a in range(3))
    for np_type, cl_type in SAMPLE_TYPES:
        info = np.iinfo(np_type)
        if info.min <= lo - grow and hi + grow <= info.max:
            return np_type, cl_type
    return np.float32, "float"


def pad_linear_into(data: np.ndarray, layers: int, out: np.ndarray) -> None:
    """:func:`splineviz.core.splines.boundary.pad_linear` written into a smaller array type.

    The ghost samples are computed one slab at a time in float64 (as the core does, up to a
    rounding of the ghosts of earlier axes), so no float64 copy of the volume is made.

    Parameters
    ----------
    data : (nx, ny, nz) array
    layers : int >= 1
    out : (nx + 2 layers, ny + 2 layers, nz + 2 layers), written; float32, or an integer
        type that holds the padded values exactly (:func:`sample_type_for`)
    """
    g = layers
    n = data.shape
    out[g:g + n[0], g:g + n[1], g:g + n[2]] = data
    for axis in range(3):
        # as the core: axes before `axis` are already padded, the later ones not yet
        region = [slice(None) if ax < axis else slice(g, g + n[ax]) for ax in range(3)]

        def at(i, region=region, axis=axis):
            r = list(region)
            r[axis] = i
            return tuple(r)

        lo = out[at(g)].astype(np.float64), out[at(g + min(1, n[axis] - 1))].astype(np.float64)
        hi = (out[at(g + n[axis] - 1)].astype(np.float64),
              out[at(g + max(n[axis] - 2, 0))].astype(np.float64))
        for m in range(1, g + 1):
            # a single sample is repeated (its "neighbour" is itself, so the slope is 0)
            out[at(g - m)] = (1 + m) * lo[0] - m * lo[1]
            out[at(g + n[axis] - 1 + m)] = (1 + m) * hi[0] - m * hi[1]


def numpy_cell_bounds(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-cell (min, max) of the 8 corner samples: the trilinear model's value bounds.

    Parameters
    ----------
    data : (nx, ny, nz) float

    Returns
    -------
    vmin, vmax : (nx-1, ny-1, nz-1) float32
    """
    d = np.asarray(data, dtype=np.float32)
    corners = [d[i:d.shape[0] - 1 + i, j:d.shape[1] - 1 + j, k:d.shape[2] - 1 + k]
               for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    return np.minimum.reduce(corners), np.maximum.reduce(corners)


class RayCaster:
    """Geometry-free ray caster of the isosurface of a spline model (DESIGN.md).

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
    A volume the device cannot hold raises :class:`RayCastError` before anything is allocated.

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
        if model not in MODELS:
            raise RayCastError(f"unknown spline model {model!r}; choose one of "
                               f"{', '.join(MODELS)}")
        self.model = model
        self._family = kernel_define(model)
        self._model_kwargs = model_kwargs
        self._device = None
        if self._family is not None:
            self._device = try_get_device(device)
        self._isovalue = None
        self._spline = None
        self.stats = {"active_cells": None, "active_tets": None, "classify_s": None,
                      "render_s": None, "device": "numpy", "path": "numpy", "classified": None}
        if self._device is not None:
            self.stats["device"] = self._device.name
            self.stats["path"] = "opencl"
        self.set_volume(volume)

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

        Raises
        ------
        RayCastError
            When the device cannot hold the volume and its octree.
        """
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        if min(volume.shape) < 2:
            raise RayCastError(f"ray casting needs at least 2 samples per axis, got {volume.shape}")
        # trilinear and TO: unit cells between samples; type-6: cubes centred at the samples
        shift = 1 if self._family == "MODEL_TYPE6" else 0
        cells = tuple(n - 1 + shift for n in volume.shape)
        if self._device is not None:
            sample_type = sample_type_for(volume.data, self._ghost())
            self._check_device_memory(volume.shape, cells, np.dtype(sample_type[0]).itemsize)
            self._sample_type = sample_type
        self._volume = volume
        self._spline = None
        self._cells = cells
        if self._device is not None:
            self._upload()
        if self._isovalue is not None:
            self._new_epoch()

    def _ghost(self) -> int:
        """Ghost layers of the device samples."""
        return GHOSTS.get(self._family, 0)

    def device_bytes(self, shape, cells, itemsize: int = 4) -> dict:
        """Bytes of the device buffers kept for a volume of ``shape`` (per buffer name).

        Parameters
        ----------
        shape : (3,) samples per axis
        cells : (3,) cells of the traversal grid per axis
        itemsize : bytes per device sample (see :func:`sample_type_for`)
        """
        ghost = self._ghost()
        levels = _octree_levels(cells)
        out = {"samples": itemsize * int(np.prod([n + 2 * ghost for n in shape])),
               "octree": 8 * _octree_nodes(levels)}
        if self._family in CACHED:
            bricks = int(np.prod(levels[0][1:]))
            out["classification cache"] = 4 * (bricks + self._entry_words()
                                               * _initial_pool(bricks))
        if self._family == "MODEL_TO":
            out["cell ranges"] = 2 * 8 * int(np.prod(levels[0][1:]))
        return out

    def _entry_words(self) -> int:
        """32-bit words of a pool entry of the classification cache (8 cells of a brick):
        type-6 one tet code per cell, TO a bit set and a written flag per cell."""
        return 8 * (1 if self._family == "MODEL_TYPE6" else TO_WORDS + 1)

    def _check_device_memory(self, shape, cells, itemsize: int = 4) -> None:
        """Refuse, before allocating anything, a volume the device cannot hold or the kernels
        cannot address."""
        dev = self._device.device
        need = self.device_bytes(shape, cells, itemsize)
        gib = 2.0**30
        total = sum(need.values())
        # the frame buffers and the compaction of classify_all need room beside the volume
        if total > 0.8 * dev.global_mem_size or max(need.values()) > dev.max_mem_alloc_size:
            big = max(need, key=need.get)
            raise RayCastError(
                f"a {'x'.join(map(str, shape))} volume with the {self.model} model needs "
                f"{total / gib:.2f} GiB of device memory ({big}: {need[big] / gib:.2f} GiB), "
                f"but {self._device.name} has {dev.global_mem_size / gib:.2f} GiB (at most "
                f"{dev.max_mem_alloc_size / gib:.2f} GiB per buffer); use a smaller or "
                f"downsampled volume")
        samples = int(np.prod([n + 2 * self._ghost() for n in shape]))
        if samples > MAX_SAMPLES:
            # the kernels index samples with 32-bit ints (64-bit index arithmetic costs every
            # sample fetch); past this the offsets wrap (seen on an H200 at 1536^3: a wrong
            # picture for trilinear, a kernel fault for super-quadratic)
            raise RayCastError(
                f"a {'x'.join(map(str, shape))} volume has {samples:,} device samples with the "
                f"{self.model} model, more than one ray caster addresses ({MAX_SAMPLES:,}); "
                f"open it as a chunked volume (Zarr, HDF5 or sv.Volume.from_dask), which is "
                f"rendered in bricks, or downsample it")

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
        """-D options of this model's programs."""
        d = {self._family: 1, "DATA_T": self._sample_type[1], **_shading_defines()}
        if self._family == "MODEL_TYPE6":
            d.update(DEGREE=self.spline.degree, TET_SLACK=TET_SLACK,
                     NPOINTS=len(self.spline.scheme.cube_points))
        elif self._family == "MODEL_TO":
            d.update(DEGREE=2, TET_SLACK=TET_SLACK, GHOST=GHOSTS["MODEL_TO"], NWORDS=TO_WORDS,
                     NUNION=self._nunion, TO_STENCIL=self._to_stencil)
        return d

    def _ray_kernel(self, kernel: str, bricks: bool = False):
        """Kernel ``kernel`` of raycast.cl for this model (its defines and generated prelude);
        ``bricks``: the variant that casts a brick of a bigger volume (``BRICKS``)."""
        defines = {**self._defines(), "BRICKS": 1} if bricks else self._defines()
        return get_kernel(self._device.context, "raycast", kernel, defines, self._prelude)

    def _upload(self):
        """Samples, min-max octree and the cleared classification cache on the device."""
        import pyopencl.array as cla

        dev = self._device
        self._prelude = ""
        q = dev.queue
        ctx = dev.context
        levels = _octree_levels(self._cells)
        self._levels = levels
        self._levels_buf = cla.to_device(q, np.array(levels, dtype=np.int32).reshape(-1, 4))
        # float2 (lo, hi) per node
        self._bounds = cla.empty(q, 2 * _octree_nodes(levels), np.float32)
        if self.model == "trilinear":
            tables = {}
            samples = self._volume.data.astype(self._sample_type[0], copy=False)
            self._data = cla.to_device(q, samples)
            self._strides = self._volume.shape[1:]
            self._negmass = 0.0
        elif self._family == "MODEL_TO":
            tables = self._to_tables()
        else:
            tables = self._type6_tables()
        self._cls_defines = {**tables, "DATA_T": self._sample_type[1]}
        get_kernel(ctx, "classify", "brick_bounds", self._cls_defines)(
            q, levels[0][:0:-1], None, *self._cell_args(), self._bounds.data)
        k_reduce = get_kernel(ctx, "classify", "reduce_level", self._cls_defines)
        for (so, sx, sy, sz), (do, dx, dy, dz) in zip(levels[:-1], levels[1:], strict=True):
            k_reduce(q, (dz, dy, dx), None, self._bounds.data,
                     *(np.int32(v) for v in (so, sx, sy, sz, do, dx, dy, dz)))
        self._epoch = 0
        if self._family in CACHED:
            # the classification cache (raycast.cl): per level-1 brick a slot, (epoch << 24) |
            # pool entry; counts: cells and tets classified at this epoch, entries asked for
            bricks = int(np.prod(levels[0][1:]))
            self._slots = cla.zeros(q, bricks, np.uint32)
            self._counts = cla.zeros(q, 3, np.int32)
            self._pool_cap = _initial_pool(bricks)
            self._pool = cla.empty(q, self._pool_cap * self._entry_words(), np.uint32)
        if self._family == "MODEL_TO":
            # isovalue-independent cell ranges (raycast.cl), all (0, 255): "not known yet"
            self._ranges = cla.empty(q, 8 * int(np.prod(levels[0][1:])), np.uint16)
            self._ranges.fill(np.uint16(0xFF00), queue=q)  # uchar2 (lo 0, hi 255)
        q.finish()

    def _cell_args(self) -> list:
        """Leading arguments of the per-cell kernels of classify.cl: data, strides, cells,
        negative mass (and the TO class tables)."""
        args = [self._data.data, *(np.int32(v) for v in self._strides),
                *(np.int32(c) for c in self._cells), np.float32(self._negmass)]
        if self._family == "MODEL_TO":
            args += [self._cls_start.data, self._cls_offsets.data]
        return args

    def _padded_samples(self, ghost: int):
        """The samples with ``ghost`` linearly extrapolated layers in their device type,
        written straight into a device buffer (no host copy of the padded volume).

        Returns
        -------
        pyopencl.array.Array of shape (nx + 2 ghost, ny + 2 ghost, nz + 2 ghost)
        """
        import pyopencl as cl
        import pyopencl.array as cla

        q = self._device.queue
        shape = tuple(n + 2 * ghost for n in self._volume.shape)
        dtype = np.dtype(self._sample_type[0])
        mf = cl.mem_flags
        buf = cl.Buffer(self._device.context, mf.READ_ONLY | mf.ALLOC_HOST_PTR,
                        dtype.itemsize * int(np.prod(shape)))
        host, _ = cl.enqueue_map_buffer(q, buf, cl.map_flags.WRITE_INVALIDATE_REGION, 0,
                                        shape, dtype)
        pad_linear_into(self._volume.data, ghost, host)
        host.base.release(q)
        return cla.Array(q, shape, dtype, data=buf)

    def _to_tables(self) -> dict:
        """Upload the padded samples and the tables of the truncated-octahedral model.

        From the core model: the 144 x 10 coefficient stencils of Q_k (dense: each tet's 28
        data offsets from its TO's base data point, flattened with the padded strides, and
        (144, 28, 16) weights, zero-padded), barycentric matrices
        (144, 4, 4); from :mod:`splineviz.compute.to_tables`: the (TO, tet) pieces per cell
        parity class and the union of the data each class reads (for the cell bounds).
        """
        import pyopencl.array as cla

        from splineviz.compute import to_program, to_tables
        from splineviz.compute.to_tables import cell_classes
        from splineviz.core.partitions import truncated_octahedra as to
        from splineviz.core.splines import to_quadratic

        q = self._device.queue
        k = _to_k(self._model_kwargs)  # the core spline itself is not built (a float64 copy)
        ghost = GHOSTS["MODEL_TO"]
        if ghost != to_quadratic.GHOST_LAYERS:
            raise AssertionError("TO ghost layers differ from the core model")  # a bug
        self._data = self._padded_samples(ghost)
        _, py, pz = self._data.shape
        strides = np.array([py * pz, pz, 1], dtype=np.int64)
        self._strides = (py, pz)
        tables = to_tables.stencils(k)
        self._to_stencil = tables[0][0].shape[0]
        if any(o.shape[0] != self._to_stencil for o, _ in tables):
            raise AssertionError("TO stencils of different sizes")  # a bug: all read 28
        # dense (144, K, 16): per tet, per data value, its weights in the 10 coefficients
        # (a float16 of the kernel)
        self._to_dense = [
            cla.to_device(q, np.stack([o @ strides for o, _ in tables]).astype(np.int32)),
            cla.to_device(q, _padded_rows(np.stack([w.T for _, w in tables]), 16))]
        self._negmass = float(max(np.sum(np.clip(-w, 0, None), axis=1).max()
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
        # copy the generated relevance test sums, see splineviz.compute.to_program)
        pts = to_tables.class_points(k, TO_WORDS)
        self._nunion = int(np.diff(pts["union_start"]).max())
        self._cls_start = cla.to_device(q, pts["union_start"].astype(np.int32))
        self._cls_offsets = cla.to_device(q, (pts["union"] @ strides).astype(np.int32))
        self._prelude = (to_program.relevance_source(k, TO_WORDS)
                         + to_program.subcell_source(TO_WORDS))
        self._bary = cla.to_device(q, np.ascontiguousarray(to.barycentric_matrices(), np.float32))
        self._red = cla.to_device(
            q, np.concatenate([_reduction_table(k).ravel() for k in (2, 1)]).astype(np.int32))
        return {"MODEL_TO": 1, "NCOEF": 10, "GHOST": ghost, "NWORDS": TO_WORDS,
                "NUNION": self._nunion, "SKIP_ACTIVE": SKIP_ACTIVE}

    def _type6_tables(self) -> dict:
        """Upload the padded samples and the constant tables of a type-6 model.

        All tables come from the core model (``self.spline.scheme``), so the kernel computes
        exactly the core spline: tet masks (24, n_d, 27), cube masks (P, 27), per cube point
        the tets whose B-net holds it (from ``tet_points``, (24, n_d)), barycentric matrices
        (24, 4, 4) and the de Casteljau reduction tables of :mod:`splineviz.core.bform`.
        """
        import pyopencl.array as cla

        from splineviz.core import bform
        from splineviz.core.partitions import type6
        from splineviz.core.splines import type6_rules

        q = self._device.queue
        spline = self.spline
        scheme = spline.scheme
        ghost = 1
        self._data = self._padded_samples(ghost)
        _, py, pz = self._data.shape
        self._strides = (py, pz)
        stencil = (type6_rules.OFFSETS @ np.array([py * pz, pz, 1])).astype(np.int32)
        self._stencil = cla.to_device(q, stencil)
        # dense tet masks (24, 27, NCHUNK * 8): per tet and stencil value, its weights in the
        # tet's coefficients (whole float8s of the kernel)
        self._tet_dense = cla.to_device(q, _padded_rows(scheme.tet_masks.transpose(0, 2, 1), 8))
        self._cube_program, order = _cube_program(scheme)
        self._cube_program = [cla.to_device(q, a) for a in self._cube_program]
        # per program row (cube point), the bit set of the tets whose B-net holds it
        point_tets = np.zeros(len(scheme.cube_points), np.uint32)
        for t, points in enumerate(scheme.tet_points):
            point_tets[points] |= np.uint32(1 << t)
        self._point_tets = cla.to_device(q, point_tets[order])
        self._bary = cla.to_device(
            q, np.ascontiguousarray(type6.barycentric_matrices(), np.float32))
        red = [_reduction_table(k) for k in range(scheme.degree, 0, -1)]
        self._red = cla.to_device(q, np.concatenate([r.ravel() for r in red]).astype(np.int32))
        # largest negative weight mass of any coefficient (bounds of stencil_bounds)
        self._negmass = float(np.max(np.sum(np.clip(-scheme.cube_masks, 0, None), axis=1)))
        return {"MODEL_TYPE6": 1, "NCOEF": bform.n_coefficients(scheme.degree),
                "NPOINTS": len(scheme.cube_points), "SKIP_ACTIVE": SKIP_ACTIVE}

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
        visible = 0 if self._family in CACHED else None
        if self._device is None:
            visible = None
            if self.model == "trilinear":
                vmin, vmax = numpy_cell_bounds(self._volume.data)
                iso = np.float32(self._isovalue)
                visible = int(np.count_nonzero((vmin <= iso) & (iso <= vmax)))
        elif self._family in CACHED:
            q = self._device.queue
            self._epoch += 1
            if self._epoch > MAX_EPOCH:
                # the 8-bit stamp wraps: clear once every MAX_EPOCH isovalues
                self._slots.fill(np.uint32(0), queue=q)
                self._epoch = 1
            self._counts.fill(np.int32(0), queue=q)  # the pool is refilled from entry 0
        self.stats.update(active_cells=visible, active_tets=visible, classified="visible")
        if self.model == "trilinear":
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
        relevant = codes = None
        if self._family == "MODEL_TYPE6":
            relevant, codes = np.zeros(n, np.int32), np.zeros(n, np.uint32)
            if n:
                nrel = cla.empty(q, n, np.int32)
                code_buf = cla.empty(q, n, np.uint32)
                _, ny, nz = self._volume.shape
                # room in the pool for every candidate brick, and their entries taken
                ijk = np.stack(np.unravel_index(cells, self._cells))
                bricks = np.unique(np.ravel_multi_index(ijk >> 1, self._levels[0][1:]))
                self._grow_pool(int(self._counts[2:3].get(queue=q)[0]) + len(bricks))
                self._ray_kernel("brick_entries")(
                    q, (len(bricks),), None, cla.to_device(q, bricks.astype(np.int32)).data,
                    *self._cache_args()[:-1])
                self._ray_kernel("tet_codes")(
                    q, (n,), None, self._data.data, np.int32(self._strides[0]),
                    np.int32(self._strides[1]), np.int32(ny), np.int32(nz), listed.data,
                    self._stencil.data, *(a.data for a in self._cube_program),
                    self._point_tets.data, np.float32(self._negmass), iso,
                    *self._cache_args()[:-1], code_buf.data, nrel.data)
                relevant, codes = nrel.get(queue=q), code_buf.get(queue=q)
            # the cache is complete: later frames count nothing new
            self._counts[:2].set(
                np.array([np.count_nonzero(relevant), relevant.sum()], np.int32), queue=q)
        elif self._family == "MODEL_TO":
            relevant, codes = np.zeros(n, np.int32), np.zeros((n, TO_WORDS), np.uint32)
            if n:
                nrel = cla.empty(q, n, np.int32)
                bits = cla.empty(q, n * TO_WORDS, np.uint32)
                _, cy, cz = self._cells
                self._ray_kernel("to_codes")(
                    q, (n,), None, self._data.data, np.int32(self._strides[0]),
                    np.int32(self._strides[1]), np.int32(cy), np.int32(cz), listed.data,
                    self._cls_start.data, self._cls_offsets.data, np.float32(self._negmass), iso,
                    bits.data, nrel.data)
                relevant, codes = nrel.get(queue=q), bits.get(queue=q).reshape(n, TO_WORDS)
        if relevant is None:
            self.stats.update(active_cells=n, active_tets=None)
        else:
            self.stats.update(active_cells=int(np.count_nonzero(relevant)),
                              active_tets=int(relevant.sum()))
        self.stats["classified"] = "all"
        return Classification(cells, relevant, codes)

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
            Of the window's size when one is given.
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
        planes = ref.normalize_clip_planes(clip_planes)
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
            frame = _crop(ref.reference_raycast(self.spline, camera, (w, h), self._isovalue,
                                                planes), (r0, r1, c0, c1))
        else:
            frame = self._render_cl(camera, w, h, planes, hessian, (r0, r1, c0, c1), placement)
        self.stats["render_s"] = time.perf_counter() - t
        return frame

    def _check_placement(self, placement: Placement) -> None:
        """Refuse a placement that does not fit this caster's volume and model."""
        if placement.centred != (self._family == "MODEL_TYPE6"):
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
            return _empty_frame(wh, ww, hessian)
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
            grid = tuple(n - 1 + (self._family == "MODEL_TYPE6") for n in shape)
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
        model_args = []
        if self._family == "MODEL_TYPE6":
            model_args = [*self._cache_args(), self._stencil.data, self._tet_dense.data,
                          *(a.data for a in self._cube_program), self._point_tets.data,
                          self._bary.data, self._red.data]
        elif self._family == "MODEL_TO":
            e = self._ent
            model_args = [*self._cache_args(), self._ranges.data, self._cls_start.data,
                          self._cls_offsets.data, e["start"].data, e["centre"].data,
                          e["base"].data, e["tet"].data,
                          *(a.data for a in self._to_dense), self._bary.data, self._red.data]
        shift = 0.5 if self._family == "MODEL_TYPE6" else 0.0
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
        if self._family in CACHED:
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
            hess_w, grad_norm = _world_hessian(hess.get(queue=q).reshape(wh, ww, 8))
        return ref.Frame(hit_h, position, normal, depth.get(queue=q).reshape(wh, ww),
                         color.get(queue=q).reshape(wh, ww, 4), hess_w, grad_norm)


def _world_hessian(hv: np.ndarray):
    """(H, W, 3, 3) symmetric Hessians and (H, W) gradient norms from the kernel's (H, W, 8)
    rows (xx, yy, zz, xy, xz, yz, |grad|, 0)."""
    hv = hv.astype(np.float64)
    i, j = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])
    hess_w = np.empty((*hv.shape[:2], 3, 3))
    hess_w[..., i, j] = hv[..., :6]
    hess_w[..., j, i] = hv[..., :6]
    return hess_w, hv[..., 6]


def _empty_frame(h: int, w: int, hessian: bool) -> ref.Frame:
    """A frame of ``h`` x ``w`` pixels without hits (an empty window has none)."""
    bg = [*(int(round(v * 255)) for v in ref.BACKGROUND), 255]
    return ref.Frame(np.zeros((h, w), bool), np.full((h, w, 3), np.nan),
                     np.full((h, w, 3), np.nan), np.ones((h, w), np.float32),
                     np.tile(np.asarray(bg, np.uint8), (h, w, 1)),
                     np.full((h, w, 3, 3), np.nan) if hessian else None,
                     np.full((h, w), np.nan) if hessian else None)


def _crop(frame: ref.Frame, window) -> ref.Frame:
    """The pixels of ``window`` (r0, r1, c0, c1) of a frame."""
    r0, r1, c0, c1 = window
    if (r0, c0) == (0, 0) and (r1, c1) == frame.hit.shape:
        return frame
    sl = (slice(r0, r1), slice(c0, c1))
    return ref.Frame(*(None if v is None else v[sl] for v in (
        frame.hit, frame.position, frame.normal, frame.depth, frame.color, frame.hessian,
        frame.gradient_norm)))


def _to_k(model_kwargs: dict) -> float:
    """The ``k`` of Q_k from the model options, with the core model's default and check."""
    import inspect

    from splineviz.core.splines.to_quadratic import TOQuadraticSpline

    default = inspect.signature(TOQuadraticSpline).parameters["k"].default
    k = float(model_kwargs.get("k", default))
    if not k >= 1:
        raise RayCastError(f"Q_k needs k >= 1, got {k}")
    return k


def _initial_pool(bricks: int) -> int:
    """Entries of a new pool: enough for a view of a typical surface; it grows on demand."""
    return int(min(MAX_POOL, max(4096, bricks // 32)))


def _reduction_table(degree: int) -> np.ndarray:
    """(n_{degree-1}, 4) positions of alpha + e_m among the degree-``degree`` multi-indices
    (the de Casteljau step of :mod:`splineviz.core.bform`, as a table for the kernel)."""
    from splineviz.core import bform

    pos = bform.index_map(degree)
    lower = bform.multi_indices(degree - 1)
    out = np.empty((len(lower), 4), dtype=np.int32)
    for a, alpha in enumerate(lower):
        for m in range(4):
            beta = [int(v) for v in alpha]
            beta[m] += 1
            out[a, m] = pos[tuple(beta)]
    return out


def _cube_program(scheme):
    """All cube coefficients of a type-6 scheme as one ordered sparse program (thesis §5.1-5.2).

    Row r computes cube point ``order[r]``: the determining set first, from the 27 stencil
    values (columns 0..26, weights of ``scheme.determining_masks``), then every other point by
    its averaging rule in application order, from points of earlier rows (column 27 + row);
    the same values as :func:`splineviz.core.splines.type6_rules.apply_rules`, with about
    40 % of the multiply-adds of the full cube masks for cubic-c1 (840 instead of 2061).

    Returns
    -------
    (row_ptr int32 (P+1,), cols int32, weights float32), order (P,) int
    """
    order = [int(p) for p in scheme.determining] + [int(t) for t, _, _ in scheme.rules]
    if sorted(order) != list(range(len(scheme.cube_points))):
        raise AssertionError("the rules do not give every cube point once")  # a bug
    row = {p: r for r, p in enumerate(order)}
    rows = [(np.flatnonzero(m), m[m != 0]) for m in scheme.determining_masks]
    for target, src, w in scheme.rules:
        if max(row[int(p)] for p in src) >= row[int(target)]:
            raise AssertionError("a rule reads a point computed after it")  # a bug
        rows.append((27 + np.array([row[int(p)] for p in src]), np.asarray(w, float)))
    row_ptr = np.concatenate([[0], np.cumsum([len(c) for c, _ in rows])]).astype(np.int32)
    cols = np.concatenate([c for c, _ in rows]).astype(np.int32)
    weights = np.concatenate([w for _, w in rows]).astype(np.float32)
    return (row_ptr, cols, weights), np.array(order)


def _padded_rows(weights: np.ndarray, width: int) -> np.ndarray:
    """Dense coefficient weights ``(T, K, C)`` as float32, the last axis zero-padded to a
    multiple of ``width`` (whole vectors of the ray kernel): ``(T, K, width * ceil(C /
    width))``."""
    t, k, c = weights.shape
    out = np.zeros((t, k, width * -(-c // width)), np.float32)
    out[..., :c] = weights
    return out


def cla_sum(arr, queue) -> float:
    import pyopencl.array as cla

    return cla.sum(arr, queue=queue).get()


def cla_count_nonzero(arr, queue) -> int:
    import pyopencl.array as cla

    return int(cla.sum((arr != 0).astype(np.int32), queue=queue).get())


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


def get_raycast_device(preference=None):
    """The device the ray caster would use (raises NoDeviceError when there is none)."""
    return get_device(preference)
