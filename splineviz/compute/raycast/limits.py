"""What a volume needs of the ray caster's device and what the device offers."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Limits:
    """What a volume needs of the device and what the device offers
    (:meth:`RayCaster.limits`).

    Attributes
    ----------
    shape : (3,) samples per axis
    samples : int
        Device samples of the volume, ghost layers included.
    need : dict
        Device bytes of the kept buffers, per buffer name (:meth:`RayCaster.device_bytes`).
    max_samples_32 : int
        Most samples the kernels address with 32-bit offsets (:data:`MAX_SAMPLES`).
    device_bytes : int
        Bytes the kept buffers may take on the device (:data:`MEMORY_SHARE` of its memory).
    max_buffer_bytes : int
        Largest single buffer the device allocates.
    """

    shape: tuple
    samples: int
    need: dict
    max_samples_32: int
    device_bytes: int
    max_buffer_bytes: int

    @property
    def total(self) -> int:
        """Device bytes of all kept buffers."""
        return int(sum(self.need.values()))

    @property
    def fits(self) -> bool:
        """Whether the device holds the kept buffers."""
        return (self.total <= self.device_bytes
                and max(self.need.values()) <= self.max_buffer_bytes)

    @property
    def offsets_64(self) -> bool:
        """Whether the kernels need 64-bit sample offsets (``OFFSET64``) for this volume."""
        return self.samples > self.max_samples_32
