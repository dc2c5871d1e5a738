"""The spatial unit of a volume's world coordinates, and lengths, areas and volumes in it.

Readers record the unit the file states (NIfTI ``xyzt_units``, NRRD ``space units``, ImageJ
and OME metadata; DICOM positions are millimetres, MRC/CCP4 maps Ångström) as
:attr:`splineviz.Volume.unit`, spelled by :func:`canonical_unit`; a file that does not say
gets ``""`` and its figures are shown without a unit, never with a guessed one.

:func:`format_quantity` writes a figure the way an engineer reads it: three significant
digits, and for lengths in the metre family the SI prefix that puts them between 1 and 1000
("12.3 mm", "4.56 mm²", "1.2 µm³"); other units (Å, inch...) are kept as the file gave them.
"""

from __future__ import annotations

import math

#: the spelling of unit names files use, by their lower-case form
_SPELLINGS = {
    "m": "m", "meter": "m", "metre": "m", "meters": "m", "metres": "m",
    "cm": "cm", "centimeter": "cm", "centimetre": "cm", "centimeters": "cm",
    "mm": "mm", "millimeter": "mm", "millimetre": "mm", "millimeters": "mm",
    "millimetres": "mm",
    "um": "µm", "µm": "µm", "μm": "µm", "micron": "µm", "microns": "µm",
    "micrometer": "µm", "micrometre": "µm", "micrometers": "µm", "micrometres": "µm",
    "nm": "nm", "nanometer": "nm", "nanometre": "nm", "nanometers": "nm",
    "pm": "pm", "picometer": "pm", "picometre": "pm",
    "km": "km", "kilometer": "km", "kilometre": "km",
    "a": "Å", "å": "Å", "Å": "Å", "angstrom": "Å", "angstroms": "Å", "ångström": "Å",
    "in": "in", "inch": "in", "inches": "in", "ft": "ft", "foot": "ft", "feet": "ft",
}
#: names that say no unit
_NONE = {"", "none", "???", "unknown", "pixel", "pixels", "px", "voxel", "voxels"}
#: metres per unit of the metre family (what :func:`format_quantity` rescales)
_METRES = {"km": 1e3, "m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6, "nm": 1e-9,
           "pm": 1e-12}
#: the prefixed metres a rescaled figure may use, largest first
_LADDER = ("km", "m", "mm", "µm", "nm", "pm")
_POWERS = {1: "", 2: "²", 3: "³"}


def canonical_unit(name) -> str:
    """The spelling used here of a unit name a file gives ("micron" -> "µm",
    "angstrom" -> "Å"), ``""`` for none or an unknown placeholder; a name not known is kept
    as it is (stripped)."""
    if name is None:
        return ""
    if isinstance(name, bytes):
        name = name.decode("latin-1")
    text = str(name).strip()
    if text.lower() in _NONE:
        return ""
    return _SPELLINGS.get(text.lower(), _SPELLINGS.get(text, text))


def _significant(value: float, digits: int = 3) -> str:
    """``value`` with ``digits`` significant digits, no exponent for ordinary magnitudes,
    no "-0"."""
    if value == 0.0 or not math.isfinite(value):
        return "0" if value == 0.0 else str(value)
    text = f"{value:.{digits}g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        if -5 <= int(exponent) < 7:
            decimals = max(0, digits - 1 - int(exponent))
            text = f"{value:.{decimals}f}"
    return text


def format_quantity(value: float, unit: str = "", power: int = 1, *, digits: int = 3,
                    ascii: bool = False) -> str:
    """A length (``power`` 1), area (2) or volume (3) in ``unit`` as an engineer writes it.

    Parameters
    ----------
    value : float
        The figure in ``unit ** power`` (world units of the volume).
    unit : str
        A :func:`canonical_unit`; ``""`` writes the bare number.
    power : {1, 2, 3}
    digits : int
        Significant digits (3 for a label; a status line may give more).
    ascii : bool
        Write the unit in the characters VTK's built-in fonts draw ("um^2", see
        :func:`ascii_unit`), for labels in a render window.

    Examples
    --------
    >>> format_quantity(0.0123, "m"), format_quantity(4.56, "mm", 2)
    ('12.3 mm', '4.56 mm²')
    >>> format_quantity(1.2e9, "nm", 3), format_quantity(12.5, ""), format_quantity(3.0, "Å")
    ('1.2 µm³', '12.5', '3 Å')
    """
    value = float(value)
    unit = canonical_unit(unit)
    if not unit:
        return _significant(value, digits)
    if unit in _METRES and value != 0.0 and math.isfinite(value):
        metres = value * _METRES[unit] ** power
        for prefixed in _LADDER:
            if abs(metres) >= 0.9995 * _METRES[prefixed] ** power or prefixed == _LADDER[-1]:
                break
        value, unit = metres / _METRES[prefixed] ** power, prefixed
    if ascii:
        exponent = "" if power == 1 else f"^{power}"
        return f"{_significant(value, digits)} {ascii_unit(unit)}{exponent}"
    return f"{_significant(value, digits)} {unit}{_POWERS[power]}"


def common_unit(units) -> str:
    """The unit shared by all of ``units`` (an iterable of str), ``""`` when they differ or
    none is known: a scene's figures carry a unit only if every volume in it agrees."""
    found = {canonical_unit(u) for u in units}
    return found.pop() if len(found) == 1 else ""


def ascii_unit(unit: str) -> str:
    """``unit`` in the characters VTK's built-in fonts draw ("µm" -> "um", "Å" -> "A")."""
    return canonical_unit(unit).replace("µ", "u").replace("Å", "A")


def metre_exponent(unit: str) -> int | None:
    """The power of ten of a metre-family ``unit`` in metres ("mm" -> -3), None otherwise."""
    factor = _METRES.get(canonical_unit(unit))
    return None if factor is None else round(math.log10(factor))
