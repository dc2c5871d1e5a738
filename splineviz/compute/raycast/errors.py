"""The ray caster's error for bad input."""

from __future__ import annotations

from splineviz.core.errors import SplinevizError


class RayCastError(SplinevizError, ValueError):
    """Bad ray-casting input (unknown model, volume too small or too big, no isovalue set)."""
