"""OpenCL device choice: a GPU if present, else the PoCL CPU device (docs/architecture.md,
"Device choice").

The choice is made once per preference and cached. ``SPLINEVIZ_DEVICE`` overrides it:
``gpu``, ``cpu``, ``numpy`` (no OpenCL at all), or a substring of a device name. When no
OpenCL device works, :func:`get_device` raises :class:`NoDeviceError`; callers that have a
NumPy path catch it through :func:`try_get_device`, which warns once and returns ``None``.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from functools import cache

from splineviz.core.errors import SplinevizError

#: environment variable that overrides the device choice
ENV_VAR = "SPLINEVIZ_DEVICE"

#: preferences with a fixed meaning; anything else is a device-name substring
KEYWORDS = ("auto", "gpu", "cpu", "numpy")


class NoDeviceError(SplinevizError, RuntimeError):
    """No OpenCL device matches the request (or OpenCL is not usable at all)."""


class DeviceFallbackWarning(UserWarning):
    """Issued once when the NumPy path replaces OpenCL because no device works."""


@dataclass(frozen=True)
class Device:
    """A chosen OpenCL device with its context and in-order queue.

    Attributes
    ----------
    context, queue : pyopencl.Context, pyopencl.CommandQueue
    device : pyopencl.Device
    name : str
        ``"<platform>: <device>"``, for stats and messages.
    kind : str
        ``"gpu"``, ``"cpu"`` or ``"other"``.
    has_fp64 : bool
        Whether the device supports double precision.
    """

    context: object
    queue: object
    device: object
    name: str
    kind: str
    has_fp64: bool


#: the smallest program every working OpenCL compiler builds
_PROBE_KERNEL = "__kernel void probe(__global float *a) { a[0] = sqrt(a[1]); }"


def _kind(cl, dev) -> str:
    if dev.type & cl.device_type.GPU:
        return "gpu"
    if dev.type & cl.device_type.CPU:
        return "cpu"
    return "other"


def _score(kind: str) -> int:
    # GPU over CPU over anything else (accelerators of unknown kind)
    return {"gpu": 2, "cpu": 1}.get(kind, 0)


def resolve_preference(preference: str | None) -> str:
    """Effective preference: the argument, else ``$SPLINEVIZ_DEVICE``, else ``"auto"``."""
    if preference is None or preference == "":
        preference = os.environ.get(ENV_VAR, "") or "auto"
    return preference.strip().lower()


@cache
def _select(preference: str) -> Device:
    if preference == "numpy":
        raise NoDeviceError("OpenCL was switched off (device 'numpy')")
    try:
        import pyopencl as cl
    except ImportError as exc:  # pragma: no cover - pyopencl is a hard dependency
        raise NoDeviceError(f"pyopencl cannot be imported ({exc})") from exc
    try:
        platforms = cl.get_platforms()
    except cl.Error as exc:
        raise NoDeviceError(f"no OpenCL platform is installed ({exc})") from exc
    candidates = []
    for platform in platforms:
        try:
            devices = platform.get_devices()
        except cl.Error:
            continue  # a broken ICD must not hide the working ones
        for dev in devices:
            kind = _kind(cl, dev)
            name = f"{platform.name.strip()}: {dev.name.strip()}"
            if preference in ("gpu", "cpu") and kind != preference:
                continue
            if preference not in KEYWORDS and preference not in name.lower():
                continue
            candidates.append((_score(kind), name, dev, kind))
    if not candidates:
        what = "any" if preference == "auto" else repr(preference)
        raise NoDeviceError(f"no OpenCL device matches {what}")
    # stable: the first platform's device wins among equal scores
    candidates.sort(key=lambda c: -c[0])
    errors = []
    for _, name, dev, kind in candidates:
        try:
            ctx = cl.Context([dev])
            queue = cl.CommandQueue(ctx)
            # a device whose compiler cannot build for this processor (PoCL 3.0's LLVM on a
            # CPU newer than it knows: "unknown target CPU 'generic'") must not hide a
            # working one, such as Debian's PoCL beside the pip wheel's
            cl.Program(ctx, _PROBE_KERNEL).build()
        except (cl.Error, RuntimeError) as exc:
            errors.append(f"{name}: {str(exc).strip().splitlines()[0]}")
            continue
        fp64 = bool(getattr(dev, "double_fp_config", 0))
        return Device(ctx, queue, dev, name, kind, fp64)
    raise NoDeviceError("no OpenCL device could be opened (" + "; ".join(errors) + ")")


def get_device(preference: str | None = None) -> Device:
    """The OpenCL device for ``preference`` (see module docstring); cached.

    Raises
    ------
    NoDeviceError
        If no device matches or none can be opened.
    """
    return _select(resolve_preference(preference))


_warned: set[str] = set()


def try_get_device(preference: str | None = None) -> Device | None:
    """Like :func:`get_device`, but warn once and return ``None`` when no device works.

    An explicit ``"numpy"`` preference returns ``None`` silently: nothing went wrong.
    """
    pref = resolve_preference(preference)
    try:
        return _select(pref)
    except NoDeviceError as exc:
        if pref != "numpy" and pref not in _warned:
            _warned.add(pref)
            warnings.warn(
                f"{exc}; using the NumPy reference path (slow, but correct)",
                DeviceFallbackWarning,
                stacklevel=2,
            )
        return None


#: resolved preference -> whether a device of it works (:func:`opencl_works`)
_works: dict[str, bool] = {}


def opencl_works(preference: str | None = None) -> bool:
    """Whether an OpenCL device for ``preference`` can be opened (``"numpy"``: False);
    probed once per preference, without the warning of :func:`try_get_device`."""
    pref = resolve_preference(preference)
    if pref not in _works:
        try:
            _select(pref)
            _works[pref] = True
        except NoDeviceError:
            _works[pref] = False
    return _works[pref]


def opencl_known(preference: str | None = None) -> bool | None:
    """What :func:`opencl_works` found for ``preference``, None when it was not asked yet
    (a caller that must not wait for the probe: it opens a context and builds a kernel)."""
    pref = resolve_preference(preference)
    return False if pref == "numpy" else _works.get(pref)
