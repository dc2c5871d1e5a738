"""Surface materials: the one table of Phong constants and surface colours.

Every shading of a spline isosurface is the same two-sided headlight Phong model
(thesis §6.3): ``rgb = base * (ambient + diffuse * c) + specular * c ** shininess`` with
``c = |n . d|`` for the unit normal ``n`` and the unit ray direction ``d``, and ``base`` the
front colour where the gradient points away from the viewer and the back colour elsewhere.
The NumPy reference ray caster, the OpenCL kernels (as ``-D`` defines), the VTK quad that
shows frames, the scene's isosurface nodes and the session schema all read the constants
here; nothing else defines them.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass

from splineviz.core.errors import SplinevizError


class MaterialError(SplinevizError, ValueError):
    """A material name that is not in :data:`MATERIALS`."""


@dataclass(frozen=True)
class Material:
    """Phong constants of the headlight model (all >= 0; ``shininess`` >= 1)."""

    ambient: float
    diffuse: float
    specular: float
    shininess: float

    def astuple(self) -> tuple[float, float, float, float]:
        """``(ambient, diffuse, specular, shininess)``."""
        return astuple(self)


#: the material of a surface that names none (also the ray casters' own shading)
DEFAULT_MATERIAL = "default"

#: named materials offered to users, in the order menus list them
MATERIALS: dict[str, Material] = {
    DEFAULT_MATERIAL: Material(0.15, 0.75, 0.35, 24.0),
    "matte": Material(0.2, 0.8, 0.0, 1.0),
    "shiny": Material(0.1, 0.7, 0.7, 60.0),
    "metal": Material(0.25, 0.55, 0.9, 12.0),
}

#: colour (RGB in [0, 1]) of the side the gradient points away from the viewer (for CT: the
#: outside), where a surface has no colour of its own ...
FRONT_COLOR = (0.93, 0.78, 0.55)
#: ... and of the other side, seen through clip planes
BACK_COLOR = (0.45, 0.62, 0.92)


def material(name: str) -> Material:
    """The material called ``name``; :class:`MaterialError` names the valid ones."""
    try:
        return MATERIALS[name]
    except (KeyError, TypeError):
        raise MaterialError(f"unknown material {name!r}; choose one of "
                            f"{', '.join(MATERIALS)}") from None
