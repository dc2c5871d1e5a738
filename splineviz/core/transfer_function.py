"""Transfer functions of direct volume rendering: value -> (RGB, opacity).

A transfer function is a colour map (RGB points, as ParaView's ``RGBPoints``) and a
piecewise-linear opacity (``Points``), both over data values. The renderers read it as a
table of :data:`TABLE_SIZE` RGBA entries over ``[lo, hi]`` (values outside clamp to the
ends), interpolated linearly between entries. Opacities are per :data:`UNIT_STEP` of ray
length in voxels (the table's opacity at a sample of a step ``dt`` voxels long is
``1 - (1 - a) ** (dt / UNIT_STEP)``, see :func:`corrected_alpha`).

Presets are given in fractions of the data range (CT and MRI presets in Hounsfield units are
meaningless for data in other units, so every preset is placed on the volume's own range);
ParaView's JSON colour-map preset format is read and written (a list of objects with
``Name``, ``RGBPoints`` (x, r, g, b, ...), optionally ``Points`` (x, alpha, 0.5, 0, ...)).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizError

#: entries of the RGBA table the renderers sample
TABLE_SIZE = 1024
#: ray length (voxels of the smallest spacing) the table's opacities are given for
UNIT_STEP = 1.0
#: entries per axis of the pre-integrated table (front value x back value)
PREINT_SIZE = 256
#: sub-samples of a ray segment integrated into the pre-integrated table
PREINT_SUBSTEPS = 64


class TransferFunctionError(SplinevizError, ValueError):
    """A transfer function that cannot be built or read."""


def _points(values, width: int, what: str) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64).ravel()
    if a.size == 0 or a.size % width:
        raise TransferFunctionError(f"{what} needs groups of {width} numbers, got {a.size}")
    a = a.reshape(-1, width)
    if not np.all(np.isfinite(a)) or np.any(np.diff(a[:, 0]) < 0):
        raise TransferFunctionError(f"{what} must be finite with non-decreasing values")
    return a


@dataclass
class TransferFunction:
    """Colour points and opacity points over data values.

    Attributes
    ----------
    rgb_points : (n, 4) float64
        (value, r, g, b), values non-decreasing, colours in [0, 1].
    opacity_points : (m, 2) float64
        (value, opacity), values non-decreasing, opacity in [0, 1] per :data:`UNIT_STEP`.
    name : str
    """

    rgb_points: np.ndarray
    opacity_points: np.ndarray
    name: str = "custom"
    _table: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        self.rgb_points = _points(self.rgb_points, 4, "RGBPoints")
        self.opacity_points = _points(self.opacity_points, 2, "opacity points")
        if np.any((self.rgb_points[:, 1:] < 0) | (self.rgb_points[:, 1:] > 1)) or np.any(
                (self.opacity_points[:, 1] < 0) | (self.opacity_points[:, 1] > 1)):
            raise TransferFunctionError("transfer function colours and opacities must be "
                                        "in [0, 1]")

    @property
    def range(self) -> tuple[float, float]:
        """(lo, hi): the values the table spans (all points' values)."""
        lo = min(self.rgb_points[0, 0], self.opacity_points[0, 0])
        hi = max(self.rgb_points[-1, 0], self.opacity_points[-1, 0])
        return float(lo), float(hi) if hi > lo else float(lo) + 1.0

    def evaluate(self, values) -> np.ndarray:
        """Exact RGBA of the points (no table): (...) values -> (..., 4) float64."""
        v = np.asarray(values, dtype=np.float64)
        out = np.empty(v.shape + (4,))
        for c in range(3):
            out[..., c] = np.interp(v, self.rgb_points[:, 0], self.rgb_points[:, 1 + c])
        out[..., 3] = np.interp(v, self.opacity_points[:, 0], self.opacity_points[:, 1])
        return out

    def table(self) -> np.ndarray:
        """``(TABLE_SIZE, 4)`` float32 RGBA at ``lo + i (hi - lo) / (TABLE_SIZE - 1)``."""
        if self._table is None:
            lo, hi = self.range
            self._table = self.evaluate(np.linspace(lo, hi, TABLE_SIZE)).astype(np.float32)
        return self._table

    def lookup(self, values) -> np.ndarray:
        """RGBA from the table, interpolated linearly between entries as the kernel does:
        (...) values -> (..., 4) float64."""
        lo, hi = self.range
        tab = self.table().astype(np.float64)
        x = np.clip((np.asarray(values, dtype=np.float64) - lo) / (hi - lo), 0.0, 1.0)
        x = x * (TABLE_SIZE - 1)
        i = np.minimum(np.floor(x).astype(np.int64), TABLE_SIZE - 2)
        f = (x - i)[..., None]
        return tab[i] * (1.0 - f) + tab[i + 1] * f

    def preintegrated(self, alpha_exp: float) -> np.ndarray:
        """Pre-integrated table (Engel et al. 2001) for ray segments whose opacity exponent
        (length / unit) is ``alpha_exp``: entry ``[i, j]`` is the segment's colour
        (premultiplied) and opacity when the value goes linearly from ``x_i`` at its front
        to ``x_j`` at its back (``x`` the :data:`PREINT_SIZE` values spanning
        :attr:`range`), composited front to back over :data:`PREINT_SUBSTEPS` sub-samples
        of the exact points. Thin opacity peaks crossed between two samples count.

        Returns
        -------
        (PREINT_SIZE, PREINT_SIZE, 4) float32, [front, back, rgba]
        """
        key = float(alpha_exp)
        cached = getattr(self, "_preint", None)
        if cached is not None and cached[0] == key:
            return cached[1]
        lo, hi = self.range
        x = np.linspace(lo, hi, PREINT_SIZE)
        m = PREINT_SUBSTEPS
        f = (np.arange(m) + 0.5) / m
        acc = np.zeros((PREINT_SIZE, PREINT_SIZE, 3))
        alpha = np.zeros((PREINT_SIZE, PREINT_SIZE))
        for s in f:
            c = self.evaluate(x[:, None] * (1.0 - s) + x[None, :] * s)
            a = 1.0 - np.power(1.0 - c[..., 3], key / m)
            w = (1.0 - alpha) * a
            acc += w[..., None] * c[..., :3]
            alpha += w
        table = np.concatenate([acc, alpha[..., None]], axis=-1).astype(np.float32)
        self._preint = (key, table)
        return table

    def preintegrated_lookup(self, front, back, alpha_exp: float) -> np.ndarray:
        """Bilinear lookup in :meth:`preintegrated` as the kernel does: (...) values at the
        segments' fronts and backs -> (..., 4) float64 (premultiplied rgb, alpha)."""
        lo, hi = self.range
        tab = self.preintegrated(alpha_exp).astype(np.float64)
        n = PREINT_SIZE

        def coord(v):
            x = np.clip((np.asarray(v, np.float64) - lo) / (hi - lo), 0.0, 1.0) * (n - 1)
            i = np.minimum(np.floor(x).astype(np.int64), n - 2)
            return i, (x - i)[..., None]

        i, fi = coord(front)
        j, fj = coord(back)
        return ((tab[i, j] * (1 - fj) + tab[i, j + 1] * fj) * (1 - fi)
                + (tab[i + 1, j] * (1 - fj) + tab[i + 1, j + 1] * fj) * fi)

    def transparent_between(self, lo, hi) -> np.ndarray:
        """Whether the table's opacity is zero on all of ``[lo, hi]`` (elementwise): cells
        whose value range passes are skipped by the renderers.

        Parameters
        ----------
        lo, hi : (...) float arrays of value bounds
        """
        tlo, thi = self.range
        alpha = self.table()[:, 3]
        # prefix count of opaque entries: any entry touched by [lo, hi] (its neighbours too,
        # since lookups interpolate between two entries) is read
        opaque = np.concatenate([[0], np.cumsum(alpha > 0)])
        scale = (TABLE_SIZE - 1) / (thi - tlo)
        a = np.clip(np.floor((np.asarray(lo, np.float64) - tlo) * scale), 0, TABLE_SIZE - 1)
        b = np.clip(np.ceil((np.asarray(hi, np.float64) - tlo) * scale), 0, TABLE_SIZE - 1)
        a, b = a.astype(np.int64), b.astype(np.int64)
        return opaque[b + 1] - opaque[a] == 0

    def to_paraview(self) -> dict:
        """This function as one ParaView JSON preset object."""
        pts = np.column_stack([self.opacity_points, np.full(len(self.opacity_points), 0.5),
                               np.zeros(len(self.opacity_points))])
        return {"Name": self.name, "ColorSpace": "RGB",
                "RGBPoints": [float(v) for v in self.rgb_points.ravel()],
                "Points": [float(v) for v in pts.ravel()]}

    def to_state(self) -> dict:
        """JSON-able state kept in sessions (:meth:`from_state` reads it back)."""
        return {"name": self.name, "rgb_points": self.rgb_points.ravel().tolist(),
                "opacity_points": self.opacity_points.ravel().tolist()}

    @classmethod
    def from_state(cls, state: dict) -> TransferFunction:
        try:
            return cls(state["rgb_points"], state["opacity_points"], str(state.get("name", "")))
        except (KeyError, TypeError):
            raise TransferFunctionError("a transfer function needs rgb_points and "
                                        "opacity_points") from None

    @classmethod
    def from_paraview(cls, preset: dict, value_range=None) -> TransferFunction:
        """A ParaView preset object; without ``Points`` the opacity ramps linearly over the
        colour points' range. ``value_range`` (lo, hi), when given, rescales both to it."""
        if not isinstance(preset, dict) or "RGBPoints" not in preset:
            raise TransferFunctionError("a ParaView colour-map preset needs RGBPoints")
        rgb = _points(preset["RGBPoints"], 4, "RGBPoints")
        if preset.get("Points"):
            op = _points(preset["Points"], 4, "Points")[:, :2]
        else:
            op = np.array([[rgb[0, 0], 0.0], [rgb[-1, 0], 1.0]])
        if value_range is not None:
            lo = min(rgb[0, 0], op[0, 0])
            hi = max(rgb[-1, 0], op[-1, 0])
            new_lo, new_hi = (float(v) for v in value_range)
            s = (new_hi - new_lo) / (hi - lo) if hi > lo else 0.0
            rgb[:, 0] = new_lo + (rgb[:, 0] - lo) * s
            op[:, 0] = new_lo + (op[:, 0] - lo) * s
        return cls(rgb, op, str(preset.get("Name", "custom")))


def corrected_alpha(alpha, step):
    """Opacity of a sample ``step`` voxels long from the table's opacity per
    :data:`UNIT_STEP` (the same formula in the kernel)."""
    return 1.0 - np.power(1.0 - np.asarray(alpha, dtype=np.float64), step / UNIT_STEP)


def read_paraview_json(path, value_range=None) -> TransferFunction:
    """The first preset of a ParaView JSON colour-map file (a list or one object)."""
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TransferFunctionError(f"cannot read the transfer function {path}: {exc}") from None
    if isinstance(doc, list):
        if not doc:
            raise TransferFunctionError(f"{path} holds no colour-map preset")
        doc = doc[0]
    return TransferFunction.from_paraview(doc, value_range)


def write_paraview_json(tf: TransferFunction, path) -> None:
    """Write ``tf`` as a ParaView JSON colour-map preset file (a list of one preset)."""
    Path(path).write_text(json.dumps([tf.to_paraview()], indent=1))


# presets: (value fraction of the data range, r, g, b) and (value fraction, opacity)
_PRESETS = {
    # bone: white above ~60 % of the range, soft tissue invisible
    "ct-bone": ([0.0, 0.30, 0.15, 0.10, 0.45, 0.75, 0.45, 0.30, 0.6, 0.95, 0.9, 0.8,
                 1.0, 1.0, 1.0, 1.0],
                [0.0, 0.0, 0.45, 0.0, 0.6, 0.6, 1.0, 0.9]),
    # soft tissue: a reddish band in the middle of the range, bone faint
    "ct-soft-tissue": ([0.0, 0.2, 0.05, 0.02, 0.35, 0.75, 0.35, 0.25, 0.5, 0.95, 0.75, 0.6,
                        1.0, 1.0, 1.0, 0.95],
                       [0.0, 0.0, 0.25, 0.0, 0.4, 0.15, 0.55, 0.05, 0.8, 0.3, 1.0, 0.3]),
    # lungs: the air-filled low values shown, the rest transparent
    "ct-lungs": ([0.0, 0.3, 0.55, 0.85, 0.2, 0.7, 0.8, 0.95, 0.35, 1.0, 0.95, 0.9,
                  1.0, 1.0, 1.0, 1.0],
                 [0.0, 0.0, 0.08, 0.0, 0.15, 0.2, 0.3, 0.0, 1.0, 0.0]),
    # MRI: grey scale ramp above a noise floor
    "mri": ([0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
            [0.0, 0.0, 0.15, 0.0, 0.5, 0.3, 1.0, 0.8]),
    # cryo-EM density maps: the high-density tail, gold
    "cryo-em": ([0.0, 0.4, 0.2, 0.05, 0.6, 0.9, 0.6, 0.2, 1.0, 1.0, 0.95, 0.7],
                [0.0, 0.0, 0.55, 0.0, 0.7, 0.5, 1.0, 0.9]),
}

#: names of the presets
PRESETS = tuple(_PRESETS)


def preset(name: str, value_range) -> TransferFunction:
    """The preset ``name`` placed on ``value_range`` (lo, hi) of the data."""
    if name not in _PRESETS:
        raise TransferFunctionError(f"unknown transfer function preset {name!r}; choose one "
                                    f"of {', '.join(PRESETS)}")
    rgb, op = _PRESETS[name]
    lo, hi = (float(v) for v in value_range)
    rgb = np.asarray(rgb, np.float64).reshape(-1, 4)
    op = np.asarray(op, np.float64).reshape(-1, 2)
    rgb[:, 0] = lo + rgb[:, 0] * (hi - lo)
    op[:, 0] = lo + op[:, 0] * (hi - lo)
    return TransferFunction(rgb, op, name)


def resolve(spec: str, value_range) -> TransferFunction:
    """A preset name (placed on ``value_range``) or a ParaView JSON file (its own values)."""
    if spec in _PRESETS:
        return preset(spec, value_range)
    if Path(spec).suffix.lower() == ".json":
        return read_paraview_json(spec)
    raise TransferFunctionError(f"{spec!r} is neither a transfer function preset "
                                f"({', '.join(PRESETS)}) nor a ParaView .json file")
