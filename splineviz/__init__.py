"""splineviz: smooth trivariate spline isosurfaces and high-quality meshes from point clouds.

The public API is imported lazily so that ``import splineviz`` stays cheap and never pulls in
Qt, VTK or OpenCL before they are needed.

This package also installs the registries' loader hook (models, formats, sources, session
object types: :mod:`splineviz.core.registry`): a registry that misses a name, or lists its
entries, first declares the session object types from the scene nodes
(:mod:`splineviz.model.schema`) and loads the plugins, so that ``core``, ``io`` and ``model``
find those entries without importing upwards (import-linter contracts forbid it).
"""

import sys
from importlib import import_module

from splineviz.core import pictures as _pictures
from splineviz.core import registry as _registry

__version__ = "0.1.0"


def _load_extensions() -> None:
    # imported by name, like the lazy public API below: plugin discovery starts on the first
    # registry miss, not on ``import splineviz``
    import_module("splineviz.model.schema")
    import_module("splineviz.plugins").ensure_loaded()


_registry.set_loader(_load_extensions)


def _show(scene, **options):
    # imported by name on first use: ``import splineviz`` pulls in no VTK, and the model
    # reaches the renderer through this hook, not by importing it
    return import_module("splineviz.notebook").show(scene, **options)


_pictures.set_show(_show)


def _register_notebook_formatters() -> None:
    # in a running IPython kernel, meshes (pyvista.PolyData) display as their pictures too;
    # the formatters are registered by type name, so this imports neither VTK nor IPython
    ipython = sys.modules.get("IPython")
    shell = None if ipython is None else getattr(ipython, "get_ipython", lambda: None)()
    if shell is not None and hasattr(shell, "display_formatter"):
        _pictures.register_formatters(shell.display_formatter)


_register_notebook_formatters()

# public name -> "module:attribute"
_LAZY = {
    "Volume": "splineviz.core.volume:Volume",
    "SplinevizError": "splineviz.core.errors:SplinevizError",
    "SplinevizWarning": "splineviz.core.errors:SplinevizWarning",
    "VolumeError": "splineviz.core.volume:VolumeError",
    "PointCloud": "splineviz.core.points:PointCloud",
    "PointCloudError": "splineviz.core.points:PointCloudError",
    "build_spline": "splineviz.core.splines:build_spline",  # plugin models through the hook
    "testfunctions": "splineviz.core.testfunctions:",
    "Camera": "splineviz.core.camera:Camera",
    "RayCaster": "splineviz.compute.raycast:RayCaster",
    "Frame": "splineviz.core.raycast_reference:Frame",
    "read_volume": "splineviz.io.volumes:read_volume",
    "read_volume_sequence": "splineviz.io.sequence:read_volume_sequence",
    "open_time_series": "splineviz.io.time_series:open_time_series",
    "TimeSeries": "splineviz.io.time_series:TimeSeries",
    "measure_isosurface": "splineviz.core.surface_measures:measure_isosurface",
    "write_volume": "splineviz.io.volumes:write_volume",
    "read_points": "splineviz.io.points:read_points",
    "read_mesh": "splineviz.io.meshes:read_mesh",
    "write_mesh": "splineviz.io.meshes:write_mesh",
    "write_screenshot": "splineviz.io.meshes:write_screenshot",
    "load_session": "splineviz.io.session:load_session",
    "save_session": "splineviz.io.session:save_session",
    "Session": "splineviz.io.session:Session",
    "register_format": "splineviz.io.registry:register_format",
    "open_path": "splineviz.io.opening:open_path",
    "Projector": "splineviz.pointcloud.projection:Projector",
    "remesh": "splineviz.pointcloud.remesh:remesh",
    "mesh_quality": "splineviz.pointcloud.quality:mesh_quality",
    "movie": "splineviz.render.movie:movie",
    "Animation": "splineviz.model.animation:Animation",
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    try:
        target = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'splineviz' has no attribute {name!r}") from None
    module_name, _, attr = target.partition(":")
    module = import_module(module_name)
    value = getattr(module, attr) if attr else module
    globals()[name] = value
    return value


def __dir__():
    return __all__
