"""Kernel families of the ray caster and their registry (docs/api.md ``RayCaster``).

A kernel family is the model-specific part of the OpenCL ray caster: which code of
``kernels/raycast.cl`` and ``kernels/classify.cl`` its ``-D`` define selects, what the device
samples are (ghost layers, sample type), the constant tables and per-data buffers its kernels
read, their kernel arguments and the words a cell takes in the classification cache.
:class:`~splineviz.compute.raycast.RayCaster` is a facade that owns what every family shares
(device, padded samples, min-max octree, cache slots, frame buffers) and asks its family for
the rest. A spline model names its family in the model registry
(:attr:`splineviz.core.splines.ModelSpec.family`); :data:`KERNEL_FAMILIES` maps that name to
the family class. Plugins add families with :func:`register_kernel_family` (through
``api.add_model(..., kernel_family=...)``, see :class:`CustomKernelFamily`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from splineviz.compute.raycast import samples as _samples
from splineviz.core.errors import SplinevizError

#: 32-bit words of a cell's bit set of relevant (TO, tet) pieces (<= 144 per cell)
TO_WORDS = 5
#: slack of the barycentric inside test of a tetrahedron (rays on shared faces)
TET_SLACK = 1e-6
#: skip code of a candidate cell (raycast.cl skip_codes)
SKIP_ACTIVE = 255


class KernelFamilyError(SplinevizError, ValueError):
    """A kernel family that cannot be registered (bad name, class or source)."""


class KernelFamily(ABC):
    """The model-specific part of the OpenCL ray caster (one instance per ray caster).

    Class attributes
    ----------------
    name : str
        Registry key (:attr:`ModelSpec.family` of the models it renders).
    define : str
        The ``-D`` name that selects its code in ``raycast.cl`` and ``classify.cl``.
    ghost_layers : int
        Extrapolated sample layers of the device samples beyond the data box.
    centred : bool
        Cells are cubes centred at the samples (type-6) rather than unit cells between them.
    cache_words : int
        32-bit words per cell in a pool entry of the classification cache; 0: the family
        caches nothing (its cells' test is cheap).
    counts_tets : bool
        Whether ``stats["active_tets"]`` counts pieces of its cells (tetrahedral models).
    bricks : bool
        Whether a brick's samples (with ``ghost_layers`` of halo) carry the same spline, so
        that :mod:`splineviz.compute.bricked` may render a bigger volume in bricks.

    Parameters
    ----------
    model : str
        The spline model it renders.
    model_kwargs : dict
        The model's options (e.g. ``k`` of ``"to-quadratic"``).
    """

    name = ""
    define = ""
    ghost_layers = 0
    centred = False
    cache_words = 0
    counts_tets = True
    bricks = True

    def __init__(self, model: str, model_kwargs: dict):
        self.model = model
        self.model_kwargs = dict(model_kwargs)
        #: generated OpenCL source prepended to raycast.cl and classify.cl (never volume-bound)
        self.prelude = ""

    def sample_type(self, data: np.ndarray) -> tuple[type, str]:
        """(numpy type, OpenCL C type) of the device samples of ``data``."""
        # looked up on its module at call time, where tests may replace it
        return _samples.sample_type_for(data, self.ghost_layers)

    def extra_bytes(self, bricks: int) -> dict:
        """Device bytes of its per-data buffers besides samples, octree and cache, for
        ``bricks`` level-1 nodes (per buffer name)."""
        return {}

    @abstractmethod
    def upload(self, rc) -> dict:
        """Put the samples and tables on the device for ``rc``'s volume.

        Sets ``rc._data`` (the device samples), ``rc._strides`` (their y, z strides) and
        ``rc._negmass`` (the widening of the value bounds of classify.cl), keeps its own
        tables, and returns the defines of classify.cl.
        """

    def upload_samples(self, rc) -> None:
        """Put new samples of ``rc``'s volume on the device: the same shape and device type as
        the last :meth:`upload` (the next step of a time series), so its tables, strides,
        negative mass and defines stay; only what depends on the samples is redone.

        The default uploads everything again; a family whose tables do not depend on the
        samples writes only the samples (into the buffer it has, ``rc._data``).
        """
        self.upload(rc)

    def allocate(self, rc) -> None:  # noqa: B027  (most families keep no per-data buffers)
        """Per-data buffers of its kernels, after the octree (``rc._levels``) exists; called
        after every :meth:`upload` and :meth:`upload_samples` (a buffer of the right size
        may be kept and cleared)."""

    def defines(self, rc) -> dict:
        """Extra ``-D`` options of raycast.cl (besides its define, DATA_T and shading)."""
        return {}

    def cell_args(self) -> list:
        """Extra trailing arguments of the per-cell kernels of classify.cl."""
        return []

    def node_args(self, rc) -> list:
        """Extra trailing arguments of classify.cl's ``brick_bounds`` (level 1 of the
        octree), after enqueueing any pass they need on ``rc``'s samples."""
        return []

    def ray_args(self, rc) -> list:
        """Its arguments of the ray kernel (after the cache's, before the isovalue)."""
        return []

    def classify(self, rc, listed, cells: np.ndarray, iso: np.float32):
        """(relevant, codes) of the candidate ``cells`` (flat indices, ascending; ``listed``
        holds them on the device) for :meth:`RayCaster.classify_all`; (None, None) when its
        cells have no pieces."""
        return None, None

    def numpy_candidates(self, volume, iso: float) -> int | None:
        """Candidate cells the NumPy path counts at ``iso``, or None."""
        return None


#: family name (:attr:`ModelSpec.family`) -> :class:`KernelFamily` subclass
KERNEL_FAMILIES: dict[str, type[KernelFamily]] = {}


def register_kernel_family(cls: type[KernelFamily]) -> type[KernelFamily]:
    """Add a kernel family under ``cls.name`` (usable as a class decorator).

    A plugin model brings its own kernel through ``api.add_model(..., kernel_family=cls)``
    (:meth:`splineviz.plugins.PluginAPI.add_model`), which calls this when the plugin's
    registrations are committed; ``cls`` is normally a :class:`CustomKernelFamily`.

    Raises
    ------
    KernelFamilyError
        When ``cls`` is not a KernelFamily subclass with a name and a define, or the name is
        taken by another class.
    """
    if not (isinstance(cls, type) and issubclass(cls, KernelFamily)):
        raise KernelFamilyError(f"{cls!r} is not a KernelFamily subclass")
    if not cls.name or not cls.define.isidentifier():
        raise KernelFamilyError(f"kernel family {cls.__name__} needs a name and a define")
    old = KERNEL_FAMILIES.get(cls.name)
    if old is not None and old is not cls:
        raise KernelFamilyError(f"the kernel family {cls.name!r} is already registered")
    KERNEL_FAMILIES[cls.name] = cls
    return cls


def family_class(model: str) -> type[KernelFamily] | None:
    """The kernel family class that ray casts ``model``, or None (NumPy reference only)."""
    from splineviz.core.splines.registry import MODELS

    spec = MODELS.get(model)
    if spec is None or spec.family is None:
        return None
    return KERNEL_FAMILIES.get(spec.family)


def kernel_define(model: str) -> str | None:
    """The ``-D`` define of the kernel family that ray casts ``model``, or None when only the
    NumPy reference renders it."""
    cls = family_class(model)
    return None if cls is None else cls.define


def renders_in_bricks(model: str) -> bool:
    """Whether ``model`` has a kernel family whose bricks carry the whole volume's spline."""
    cls = family_class(model)
    return cls is not None and cls.bricks


class CustomKernelFamily(KernelFamily):
    """Base of a kernel family brought by a plugin: a model's own OpenCL root finder.

    The ray caster does everything else (octree, empty-space leaping, cell traversal, clip
    planes, depth, shading, Hessian output); the family gives the device samples and one
    OpenCL function. How a plugin registers one:

    1. Write ``mykernel.cl`` beside the plugin's module, defining::

           float custom_cell_root(__global const DATA_T *data, offset_t base, int SY, int SZ,
                                  float3 p, float3 d, float len, float iso, float3 *grad,
                                  int want_hess, float *hess);

       the first root ``r`` in ``[0, len]`` (-1 if none) of ``s(cell + p + r d) = iso`` on
       the unit cell ``[i, i+1] x [j, j+1] x [k, k+1]`` of index space (``p``: the ray's
       point relative to the cell's corner, ``d``: its index-space direction). ``data`` holds
       the family's device samples (``DATA_T`` is ``float``); ``data[base]`` is device sample
       ``(i, j, k)`` (with ``ghost_layers`` g, the volume's sample ``(i, j, k)`` is device
       sample ``(i + g, j + g, k + g)``), ``data[base + (a * SY + b) * SZ + c]`` is device
       sample ``(i + a, j + b, k + c)``, and the cell may read ``a, b, c`` up to ``reach``.
       ``offset_t`` is ``int``, or ``long`` for volumes past 2^31 device samples (compute
       offsets in it). ``*grad`` receives the index-space gradient at the root and, when
       ``want_hess``, ``hess[0..5]`` the index-space Hessian (xx, yy, zz, xy, xz, yz). It
       must find the FIRST root exactly (e.g. Bernstein subdivision; no fixed-step sampling,
       which misses thin features). The source is prepended to ``kernels/raycast.cl``, which
       calls it from the ray kernel (``MODEL_CUSTOM``).
    2. Subclass this class: ``name`` (the family's registry key, usually the model's name),
       ``source = ("my_package", "mykernel.cl")``, ``ghost_layers`` and ``reach``,
       ``negmass`` if the spline on a cell is not within the min/max of the device samples
       the cell reads, ``bricks = False`` if a brick's samples do not carry the same spline
       (a global prefilter), and :meth:`device_samples`.
    3. In ``register(api)``: ``api.add_model(name, target, ..., kernel_family=MyFamily)``;
       :class:`~splineviz.RayCaster` then renders the model on the OpenCL device, and every
       front end (GUI, CLI, sessions) lists it as a kernel model.

    The value bounds of a cell (octree, empty-space leaping) are the min/max of the device
    samples ``base .. base + reach`` per axis, widened by ``negmass`` times their range: they
    must hold the spline on the cell. The cells are unit cells between samples; their
    classification is not cached (``stats["active_cells"]`` stays None).
    """

    define = "MODEL_CUSTOM"
    #: (package, file name) of the OpenCL source beside the plugin's module
    source: tuple[str, str] = ("", "")
    #: samples past a cell's first one that its function reads, per axis
    reach = 1
    #: widening of the cells' value bounds (0: the spline is a convex combination of them)
    negmass = 0.0
    cache_words = 0
    counts_tets = False

    @abstractmethod
    def device_samples(self, rc) -> np.ndarray:
        """The float32 ``(nx + 2 g, ny + 2 g, nz + 2 g)`` device samples of ``rc.volume``
        (``g`` = :attr:`ghost_layers`), e.g. the coefficients of the spline."""

    def sample_type(self, data: np.ndarray) -> tuple[type, str]:
        return np.float32, "float"

    def _source(self) -> str:
        from importlib import resources

        package, filename = self.source
        try:
            return resources.files(package).joinpath(filename).read_text()
        except (ModuleNotFoundError, FileNotFoundError, OSError):
            raise KernelFamilyError(f"the kernel family {self.name!r} has no OpenCL source "
                                    f"{filename!r} in {package!r}") from None

    def upload(self, rc) -> dict:
        import pyopencl.array as cla

        g = self.ghost_layers
        samples = np.ascontiguousarray(self.device_samples(rc), dtype=np.float32)
        want = tuple(n + 2 * g for n in rc.volume.shape)
        if samples.shape != want:
            raise KernelFamilyError(f"the kernel family {self.name!r} gave device samples of "
                                    f"shape {samples.shape}, not {want}")
        rc._data = cla.to_device(rc._device.queue, samples)
        rc._strides = samples.shape[1:]
        rc._negmass = float(self.negmass)
        self.prelude = self._source()
        return {self.define: 1, "GHOST": g, "CELL_REACH": int(self.reach)}

    def defines(self, rc) -> dict:
        return {"GHOST": self.ghost_layers, "CELL_REACH": int(self.reach)}
