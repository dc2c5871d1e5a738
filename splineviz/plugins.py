"""Plugin discovery through entry points (group ``splineviz.plugins``).

A plugin is any installed distribution that declares, in its ``pyproject.toml``::

    [project.entry-points."splineviz.plugins"]
    myplugin = "my_package:register"

``register(api)`` receives a :class:`PluginAPI` and adds readers/writers, synthetic data
sources and spline models through it, into the registries of :mod:`splineviz.io.registry`,
:mod:`splineviz.core.sources` and :mod:`splineviz.core.splines.registry`. Discovery
(:func:`discover`) only reads installed metadata; plugin code is imported on the first
:func:`ensure_loaded` call, never on ``import splineviz``. ``import splineviz`` installs
:func:`ensure_loaded` as the registries' loader hook (:func:`splineviz.core.registry.set_loader`),
so the first lookup that misses or lists a registry (the first file read, an unknown model name,
the GUI's Sources menu) loads the plugins, whichever layer asks: ``io``, ``core`` and ``model``
never import this module. A plugin that fails to import, raises in ``register`` or registers
something invalid is recorded in :func:`failures`, logged, and skipped: what it registered is
rolled back, and start-up goes on.

Plugins are code the user chose to install; session files never name or load plugins.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import metadata

from splineviz.core.sources import SOURCES, Source, source_volume, sources  # noqa: F401
from splineviz.core.splines import build_spline  # noqa: F401  (finds plugin models too)
from splineviz.io.errors import PluginError

GROUP = "splineviz.plugins"
#: comma-separated plugin names to skip, or "all"
DISABLE_ENV = "SPLINEVIZ_DISABLE_PLUGINS"

log = logging.getLogger(__name__)


@dataclass
class PluginRecord:
    """What is known about one entry point."""

    name: str
    value: str
    distribution: str = ""
    state: str = "available"  # available | loaded | failed | disabled
    error: str | None = None
    registered: list[str] = field(default_factory=list)


class PluginAPI:
    """The object handed to a plugin's ``register(api)``.

    Registrations are staged and committed only when ``register`` returns without error, so
    a failing plugin leaves no half-registered state.
    """

    def __init__(self, plugin: str):
        self.plugin = plugin
        self._staged: list[tuple[str, Callable[[], None], Callable[[], None]]] = []

    # -- formats
    def add_volume_format(self, name, extensions, reader=None, writer=None, *, sniff=None,
                          folder=False, description=""):
        """Add a volume format; ``reader(path) -> splineviz.io.volumes.VolumeData``."""
        self._add_format("volume", name, extensions, reader, writer, sniff, folder, description)

    def add_points_format(self, name, extensions, reader=None, writer=None, *, sniff=None,
                          description=""):
        """Add a point format; ``reader(path) -> splineviz.io.points.PointData``."""
        self._add_format("points", name, extensions, reader, writer, sniff, False, description)

    def add_mesh_format(self, name, extensions, reader=None, writer=None, *, description=""):
        """Add a mesh format; ``writer(path, polydata)``."""
        self._add_format("mesh", name, extensions, reader, writer, None, False, description)

    def _add_format(self, kind, name, extensions, reader, writer, sniff, folder, description):
        from splineviz.io import registry

        if (kind, name) in registry.FORMATS:
            raise PluginError(f"plugin {self.plugin!r} redefines the {kind} format {name!r}")
        for fn in (reader, writer, sniff):
            if fn is not None and not callable(fn):
                raise PluginError(f"plugin {self.plugin!r} gave a non-callable for {name!r}")

        def do():
            registry.register_format(name, extensions, reader, writer, kind=kind, sniff=sniff,
                                     folder=folder, description=description,
                                     plugin=self.plugin)

        def undo():
            registry.FORMATS.unregister((kind, name))

        self._staged.append((f"{kind} format {name}", do, undo))

    # -- sources
    def add_source(self, name, function, bounds, *, title=None, shape=(64, 64, 64),
                   isovalue=None, description=""):
        """Add a synthetic data source (see :class:`Source`)."""
        if not callable(function):
            raise PluginError(f"source {name!r} of plugin {self.plugin!r} is not callable")
        if name in SOURCES:
            raise PluginError(f"plugin {self.plugin!r} redefines the source {name!r}")
        try:
            b = tuple((float(lo), float(hi)) for lo, hi in bounds)
            shp = tuple(int(n) for n in shape)
        except (TypeError, ValueError):
            raise PluginError(f"source {name!r} has malformed bounds or shape") from None
        if len(b) != 3 or any(not lo < hi for lo, hi in b) or len(shp) != 3:
            raise PluginError(f"source {name!r} needs three increasing bounds and three sizes")
        src = Source(name, title or name, function, b, shp, isovalue, self.plugin, description)

        def do():
            SOURCES.register(name, src)

        def undo():
            SOURCES.unregister(name)

        self._staged.append((f"source {name}", do, undo))

    # -- spline models
    def add_model(self, name, target, *, label=None, degree=None, smoothness="",
                  ghost_layers=0, options=None, kernel_family=None):
        """Add a spline model to the registry :data:`splineviz.core.splines.MODELS`.

        ``target`` is ``"module:Class"`` or the class itself (a
        :class:`~splineviz.core.splines.base.Spline` subclass taking the volume). The other
        arguments describe it to front ends (the GUI's model list shows ``label``). Without
        ``kernel_family`` the model renders through the NumPy reference ray caster; with a
        :class:`splineviz.compute.raycast.CustomKernelFamily` subclass (its OpenCL root
        finder in a ``.cl`` file beside the plugin's module; the class docstring says how to
        write one) :class:`splineviz.RayCaster` renders it on the OpenCL device like the
        built-in models, and the family is registered under its ``name``.
        """
        from splineviz.core.splines import MODELS, ModelSpec

        if name in MODELS:
            raise PluginError(f"plugin {self.plugin!r} redefines the spline model {name!r}")
        if isinstance(target, type):
            target = f"{target.__module__}:{target.__qualname__}"
        if not isinstance(target, str) or ":" not in target:
            raise PluginError(f"model {name!r} must be given as 'module:Class' or a class")
        family = None
        if kernel_family is not None:
            from splineviz.compute.raycast import KERNEL_FAMILIES, CustomKernelFamily

            if not (isinstance(kernel_family, type)
                    and issubclass(kernel_family, CustomKernelFamily)
                    and kernel_family.name):
                raise PluginError(f"the kernel family of model {name!r} must be a named "
                                  "CustomKernelFamily subclass")
            family = kernel_family.name
            if KERNEL_FAMILIES.get(family, kernel_family) is not kernel_family:
                raise PluginError(f"plugin {self.plugin!r} redefines the kernel family "
                                  f"{family!r}")
        spec = ModelSpec(name, target, label or name, degree, smoothness, family,
                         int(ghost_layers), dict(options or {}), self.plugin)
        added_family = []

        def do():
            if kernel_family is not None:
                from splineviz.compute.raycast import KERNEL_FAMILIES, register_kernel_family

                if family not in KERNEL_FAMILIES:
                    register_kernel_family(kernel_family)
                    added_family.append(family)
            MODELS[name] = spec

        def undo():
            MODELS.pop(name, None)
            if added_family:
                from splineviz.compute.raycast import KERNEL_FAMILIES

                KERNEL_FAMILIES.pop(added_family.pop(), None)

        self._staged.append((f"model {name}", do, undo))

    def _commit(self) -> list[str]:
        done = []
        try:
            for label, do, undo in self._staged:
                do()
                done.append((label, undo))
        except Exception:
            for _, undo in reversed(done):
                undo()
            raise
        return [label for label, _ in done]


_RECORDS: dict[str, PluginRecord] = {}
_LOADED = False
# set while load_plugins runs: a registry lookup made by a plugin's register() on the loading
# thread (the lock is reentrant) must not start loading again
_LOADING = False
_LOCK = threading.RLock()


def _disabled() -> set[str]:
    return {s.strip() for s in os.environ.get(DISABLE_ENV, "").split(",") if s.strip()}


def discover() -> list[PluginRecord]:
    """Entry points of group ``splineviz.plugins``, without importing them."""
    out = []
    for ep in metadata.entry_points(group=GROUP):
        dist = getattr(getattr(ep, "dist", None), "name", "") or ""
        out.append(PluginRecord(ep.name, ep.value, dist))
    return out


def load_plugins(*, reload: bool = False) -> list[PluginRecord]:
    """Import and register every discovered plugin once; return the records.

    Failures never propagate: a plugin whose import or ``register`` raises is marked
    ``"failed"`` with a one-line reason, logged, and skipped.
    """
    global _LOADED, _LOADING
    with _LOCK:
        if _LOADING or (_LOADED and not reload):
            return list(_RECORDS.values())
        _LOADING = True
        try:
            _load_entry_points()
        finally:
            _LOADING = False
        _LOADED = True
        return list(_RECORDS.values())


def _load_entry_points() -> None:
    """Import and register each entry point not loaded yet (the caller holds ``_LOCK``)."""
    disabled = _disabled()
    for ep in metadata.entry_points(group=GROUP):
        if ep.name in _RECORDS and _RECORDS[ep.name].state == "loaded":
            continue
        dist = getattr(getattr(ep, "dist", None), "name", "") or ""
        rec = PluginRecord(ep.name, ep.value, dist)
        _RECORDS[ep.name] = rec
        if "all" in disabled or ep.name in disabled:
            rec.state = "disabled"
            continue
        try:
            register = ep.load()
            if not callable(register):
                raise PluginError(f"entry point {ep.value} is not callable")
            api = PluginAPI(ep.name)
            register(api)
            rec.registered = api._commit()
            rec.state = "loaded"
        except BaseException as exc:  # noqa: BLE001 - a plugin must never break start-up
            if isinstance(exc, KeyboardInterrupt):
                raise
            rec.state = "failed"
            rec.error = f"{type(exc).__name__}: {exc}".splitlines()[0]
            log.warning("plugin %s (%s) failed and was skipped: %s", ep.name, ep.value,
                        rec.error)


def ensure_loaded() -> None:
    """Load plugins on first use (cheap afterwards)."""
    if not _LOADED:
        load_plugins()


def failures() -> list[PluginRecord]:
    """Plugins that failed to load, with their reasons (for an "About plugins" dialog)."""
    return [r for r in _RECORDS.values() if r.state == "failed"]
