"""The registry of spline models: one entry per model, read by every front end.

The GUI's model list, the CLI's ``--model`` choices, session files and
:class:`splineviz.RayCaster` all look models up here, so a model added by a plugin
(``api.add_model``) appears everywhere at once. An entry names the class that builds the
spline (``"module:Class"``, imported lazily) and what front ends need to know without
importing it: the label users see, the polynomial degree and smoothness, the name of the
kernel family that ray casts it (``None``: the NumPy reference ray caster; the families and
their OpenCL code live in :mod:`splineviz.compute.raycast`) and how many ghost layers of
extrapolated samples its stencils read beyond the data box (thesis Remark 1).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from splineviz.core.errors import SplinevizError
from splineviz.core.registry import Registry


class UnknownModelError(SplinevizError, ValueError):
    """A model name that no built-in model or installed plugin provides."""


class SplineOptionError(SplinevizError, ValueError):
    """A model option that the model does not have or whose value it cannot use
    (e.g. ``k <= 0`` for ``to-quadratic``)."""


@dataclass(frozen=True)
class ModelSpec:
    """One spline model.

    Attributes
    ----------
    name : str
        The key used in code, sessions and on the command line (``"cubic-c1"``).
    target : str
        ``"module:Class"`` of the :class:`~splineviz.core.splines.base.Spline` subclass.
    label : str
        The name users see.
    degree : int or None
        Polynomial degree of the pieces.
    smoothness : str
        ``"C0"``, ``"C1"``, ...
    family : str or None
        Name of the ray caster's kernel family (``"trilinear"``, ``"type6"``, ``"to"`` or one
        a plugin registered, see :data:`splineviz.compute.raycast.KERNEL_FAMILIES`), or None
        when only the NumPy reference renders it.
    ghost_layers : int
        Extrapolated sample layers the stencils reach beyond the data box.
    options : dict
        Default keyword arguments of the class (e.g. ``{"k": 2}``).
    lattice_period : int
        Grid steps after which the partition repeats (2 for truncated octahedra, centred at
        a BCC lattice: a sub-volume must start at even sample offsets to carry the same
        spline; 1 for the cube partitions).
    plugin : str or None
        The plugin that added it (None: built in).
    """

    name: str
    target: str
    label: str = ""
    degree: int | None = None
    smoothness: str = ""
    family: str | None = None
    ghost_layers: int = 0
    options: dict = field(default_factory=dict)
    plugin: str | None = None
    lattice_period: int = 1

    @property
    def centred_cells(self) -> bool:
        """Whether the ray caster's cells are cubes centred at the samples (type-6, thesis
        §4.4) rather than the unit cells between samples (trilinear, truncated octahedra)."""
        return self.family == "type6"

    @property
    def display_label(self) -> str:
        return self.label or self.name


def _builtin() -> dict[str, ModelSpec]:
    p = "splineviz.core.splines."
    specs = (
        ModelSpec("trilinear", p + "trilinear:TrilinearSpline", "Trilinear (C0)", 1, "C0",
                  "trilinear", 0),
        ModelSpec("super-quadratic", p + "super_quadratic:SuperQuadraticSpline",
                  "Quadratic super spline (type-6)", 2, "C0", "type6", 1),
        ModelSpec("cubic-c1", p + "cubic_c1:CubicC1Spline", "Cubic C1 (type-6)", 3, "C1",
                  "type6", 1),
        ModelSpec("to-quadratic", p + "to_quadratic:TOQuadraticSpline",
                  "Quadratic C1 (truncated octahedra)", 2, "C1", "to", 3, {"k": 2},
                  lattice_period=2),
    )
    return {s.name: s for s in specs}


#: model name -> :class:`ModelSpec` (plugins add to it through ``api.add_model``)
MODELS: Registry[ModelSpec] = Registry("spline model", _builtin(), error=UnknownModelError)


def model_spec(name: str) -> ModelSpec:
    """The :class:`ModelSpec` of ``name``, plugin models included: the one check of a model
    name that nodes, sessions, the render layer and the ray casters share.

    Raises
    ------
    UnknownModelError
        "unknown spline model 'x'; choose one of ..." naming the valid models.
    """
    return MODELS.lookup(name)
