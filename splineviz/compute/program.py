"""OpenCL programs: kernel sources are ``.cl`` files in ``kernels/`` beside this module,
specialised with ``-D`` build options (never by string formatting of kernel bodies) and built
once per (context, file, options, prelude); pyopencl additionally caches binaries on disk.

A prelude is source generated from a model's tables (functions the file calls, e.g.
:mod:`splineviz.compute.raycast.to_program`) or a plugin's kernel family, prepended to the
file; it never depends on a volume."""

from __future__ import annotations

from importlib import resources

from splineviz.core.errors import SplinevizError

_cache: dict = {}


class KernelBuildError(SplinevizError, RuntimeError):
    """An OpenCL program failed to build (the message carries the build log)."""


def kernel_source(name: str) -> str:
    """Text of ``kernels/<name>.cl``."""
    path = resources.files("splineviz.compute").joinpath("kernels", f"{name}.cl")
    if not path.is_file():
        raise KernelBuildError(f"there is no OpenCL kernel file {name}.cl")
    return path.read_text()


def build_options(defines: dict | None) -> tuple[str, ...]:
    """``-D NAME=value`` options in a stable order (part of the cache key).

    Floats are written with ``f`` suffix-free full precision; ``True`` becomes ``1``.
    """
    opts = []
    for key, value in sorted((defines or {}).items()):
        if not key.isidentifier():
            raise KernelBuildError(f"{key!r} is not a valid preprocessor name")
        if isinstance(value, bool):
            value = int(value)
        if isinstance(value, float):
            value = repr(value) + "f"
        opts.append(f"-D{key}={value}")
    return tuple(opts)


def get_program(context, name: str, defines: dict | None = None, prelude: str = ""):
    """Built program ``kernels/<name>.cl`` for ``context`` with ``defines``; cached.

    Parameters
    ----------
    context : pyopencl.Context
    name : str
        Kernel file stem, e.g. ``"raycast"``.
    defines : dict, optional
        Preprocessor definitions, e.g. ``{"MODEL_TRILINEAR": 1}``.
    prelude : str, optional
        Generated source prepended to the file (see the module docstring).
    """
    import pyopencl as cl

    opts = build_options(defines)
    key = (context.int_ptr, name, opts, prelude)
    prog = _cache.get(key)
    if prog is None:
        try:
            prog = cl.Program(context, prelude + kernel_source(name)).build(options=list(opts))
        except cl.RuntimeError as exc:
            raise KernelBuildError(f"OpenCL program {name}.cl failed to build: {exc}") from exc
        _cache[key] = prog
    return prog


_kernels: dict = {}


def get_kernel(context, name: str, kernel: str, defines: dict | None = None,
               prelude: str = ""):
    """Kernel object ``kernel`` of :func:`get_program`; cached, since every attribute access
    on a program creates a new kernel object."""
    import pyopencl as cl

    key = (context.int_ptr, name, build_options(defines), prelude, kernel)
    k = _kernels.get(key)
    if k is None:
        k = _kernels[key] = cl.Kernel(get_program(context, name, defines, prelude), kernel)
    return k


def cache_size() -> int:
    """Number of programs built in this process (for tests of the cache)."""
    return len(_cache)
