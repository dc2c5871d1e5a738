"""Tick labels of the axes grid: round values, engineering notation, the data's unit.

A grid labelled at its data bounds showed what the numbers of a file hold: "6.24e-29" where
an origin is 6e-29 (float noise for 0), "0 / -0" on a bunny in metres (ticks printed as
integers). Here each axis is labelled at multiples of a round step (1, 2 or 5 times a power
of ten), the range padded outwards to whole steps, every label printed with as many decimals
as the step needs (so no noise, no "-0") in engineering notation: the values of one axis are
scaled by a power of 1000 shown once in its title, as an SI prefix of the unit when the unit
is known ("X (mm)") and as a factor otherwise ("X (x 1e-3)").

The step follows the rule of VTK's ``vtkCubeAxesActor`` (ticks at the decade of the span over
5, 2 or 1), so the labels given to that actor land on the ticks it draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: SI prefixes of the powers of 1000 an axis title may use with a known unit ("u" for micro:
#: VTK's built-in fonts draw ASCII only, "µ" and "×" came out blank)
SI_PREFIXES = {-15: "f", -12: "p", -9: "n", -6: "u", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}


@dataclass(frozen=True)
class AxisTicks:
    """The labelling of one axis.

    Attributes
    ----------
    lo, hi : float
        The labelled range in world units: the data range padded to whole steps.
    step : float
        World units between two labels.
    exponent : int
        A multiple of 3: labels show ``value / 10**exponent``.
    labels : tuple of str
        One per tick from ``lo`` to ``hi``.
    title : str
    """

    lo: float
    hi: float
    step: float
    exponent: int
    labels: tuple[str, ...]
    title: str

    @property
    def shown_range(self) -> tuple[float, float]:
        """``(lo, hi)`` in the units the labels show."""
        scale = 10.0 ** -self.exponent
        return self.lo * scale, self.hi * scale


def vtk_step(span: float) -> float:
    """The major tick step ``vtkCubeAxesActor`` uses on a range of ``span`` (> 0): the
    span's decade divided by 5, 2 or 1 as the span holds 1-2, 2-4 or more decades."""
    power = math.log10(span)
    if power != 0.0:
        power = math.copysign(abs(power) + 1e-9, power)
    if power < 0.0:
        power -= 1.0
    decade = 10.0 ** int(power)
    ticks = int(span / decade) + 1
    return decade / (5.0 if ticks <= 2 else 2.0 if ticks < 5 else 1.0)


def _padded(lo: float, hi: float, step: float) -> tuple[int, int]:
    """Whole steps ``(k0, k1)`` with ``k0 * step <= lo`` and ``k1 * step >= hi`` (a relative
    slack keeps a bound that is a step up to rounding from growing by a whole step)."""
    slack = 1e-9
    return math.floor(lo / step + slack), math.ceil(hi / step - slack)


def engineering_exponent(magnitude: float) -> int:
    """The multiple of 3 at or below ``log10(magnitude)`` (0 for 0)."""
    if not magnitude > 0.0 or not math.isfinite(magnitude):
        return 0
    return 3 * math.floor(math.log10(magnitude) / 3.0 + 1e-9)


def format_tick(count: int, step: float, exponent: int) -> str:
    """The label of the tick ``count * step``, shown in units of ``10**exponent`` with the
    decimals the step needs: never "-0", never float noise."""
    if count == 0:
        return "0"
    shown_step = step * 10.0 ** -exponent
    decimals = max(0, -math.floor(math.log10(shown_step) + 1e-9))
    return f"{count * shown_step:.{decimals}f}"


def axis_title(name: str, exponent: int, unit: str = "") -> str:
    """``name`` with the unit the labels are in: "X (mm)", "X (x 1e-3)", "X (A)", "X".

    A metre-family unit takes the SI prefix of the scaled labels (labels of thousands of
    millimetres are metres: "X (m)"); the unit is written in ASCII (see
    :data:`SI_PREFIXES`)."""
    from splineviz.core.units import ascii_unit, metre_exponent

    unit = ascii_unit(unit)
    if unit:
        if exponent == 0:
            return f"{name} ({unit})"
        base = metre_exponent(unit)
        if base is not None and exponent + base in SI_PREFIXES:
            return f"{name} ({SI_PREFIXES[exponent + base]}m)"
        if exponent in SI_PREFIXES and len(unit) == 1 and unit.islower():
            return f"{name} ({SI_PREFIXES[exponent]}{unit})"
        return f"{name} (x 1e{exponent} {unit})"
    return name if exponent == 0 else f"{name} (x 1e{exponent})"


#: the most labels one axis shows, however wide the view
MAX_LABELS = 6

#: width of one character of the grid's labels (VTK's 10-point font) in pixels
LABEL_CHAR_PX = 7.0


def label_stride(labels: tuple[str, ...] | list[str], axis_px: float,
                 char_px: float = LABEL_CHAR_PX) -> int:
    """Every how many ticks a label fits along an axis ``axis_px`` pixels long on screen.

    A label takes its characters plus two of space; the stride is 1, 2 or 5 times a power
    of ten (labels at multiples of it keep 0 labelled and stay round) and leaves at most
    :data:`MAX_LABELS`, and at least the two ends' worth, on the axis.
    """
    n = len(labels)
    width = (max((len(t) for t in labels), default=1) + 2) * char_px
    fits = max(2, min(MAX_LABELS, int(max(axis_px, 0.0) // width)))
    stride = 1
    for decade in (1, 10, 100, 1000):
        for m in (1, 2, 5):
            stride = m * decade
            if math.ceil(n / stride) <= fits:
                return stride
    return stride


def axis_ticks(lo: float, hi: float, name: str = "", unit: str = "") -> AxisTicks:
    """Labels of an axis over the data range ``[lo, hi]`` (see the module docstring).

    A range of zero width (a flat data set) is labelled around its value.
    """
    lo, hi = float(min(lo, hi)), float(max(lo, hi))
    span = hi - lo
    if not span > 0.0 or span < 1e-9 * max(abs(lo), abs(hi)):
        # no width (or less than float noise of the position): a unit step around it
        half = 0.5 * (10.0 ** math.floor(math.log10(abs(lo)))) if lo else 0.5
        lo, hi = lo - half, hi + half
        span = hi - lo
    step = vtk_step(span)
    for _ in range(4):  # padding widens the span; the step follows until it settles
        k0, k1 = _padded(lo, hi, step)
        again = vtk_step((k1 - k0) * step)
        if again == step:
            break
        step = again
    k0, k1 = _padded(lo, hi, step)
    exponent = engineering_exponent(max(abs(k0), abs(k1)) * step)
    labels = tuple(format_tick(k, step, exponent) for k in range(k0, k1 + 1))
    return AxisTicks(k0 * step, k1 * step, step, exponent, labels,
                     axis_title(name, exponent, unit))
