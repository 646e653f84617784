"""Wobble settings in user units (µm, Hz) made into the board's ``wob_*`` registers.

The gateware knows no millimetres: its amplitudes are galvo units, which the machine's field
size fixes (``units_per_mm = 65536 / field size``; on a 110 mm field one unit is ≈ 1.68 µm). The
frequency register is in Hz already.
"""

from dataclasses import dataclass

from ..gateware.host.regmap import (BY_NAME, WOBBLE_MAX_AMPLITUDE, WOBBLE_MAX_HZ, WobbleShape,
                                    WOBBLE_REGISTERS)
from ..geometry.field import PlanError


__all__ = ["WobbleSettings", "wobble_registers", "WOBBLE_REGISTERS", "WOBBLE_MAX_HZ"]

assert BY_NAME["wob_along"].unit == BY_NAME["wob_across"].unit == "galvo units"
assert BY_NAME["wob_freq"].unit == "Hz"


@dataclass(frozen=True)
class WobbleSettings:
    """An ellipse laid over every marked line: ``across_um`` to each side of the line,
    ``along_um`` forwards and back along it (equal: a circle), ``freq_hz`` turns a second."""
    across_um: float
    along_um: float
    freq_hz: float


def _units(um, what, profile):
    units = round(um / 1000 * profile.units_per_mm)
    most_um = WOBBLE_MAX_AMPLITUDE / profile.units_per_mm * 1000
    if not 0 <= units <= WOBBLE_MAX_AMPLITUDE:
        raise PlanError(f"wobble {what} {um:g} µm is more than the board's "
                        f"{WOBBLE_MAX_AMPLITUDE} galvo units ({most_um:.0f} µm on this "
                        f"{profile.field.size_mm:g} mm field)")
    return units


def wobble_registers(wobble, profile):
    """The ``wob_*`` register values for ``wobble`` on ``profile``'s machine (None: off), or a
    :class:`~galvoscan.geometry.field.PlanError` (one line)."""
    if wobble is None or (wobble.across_um == 0 and wobble.along_um == 0):
        return {}
    across = _units(wobble.across_um, "amplitude", profile)
    along = _units(wobble.along_um, "amplitude along the line", profile)
    if across == 0 and along == 0:
        raise PlanError(f"a wobble of {max(wobble.across_um, wobble.along_um):g} µm is less "
                        f"than one galvo unit ({1000 / profile.units_per_mm:.2f} µm on this "
                        f"field): nothing would move")
    hz = round(wobble.freq_hz)
    if not BY_NAME["wob_freq"].low <= hz <= WOBBLE_MAX_HZ:
        raise PlanError(f"wobble frequency {wobble.freq_hz:g} Hz is outside 1 … "
                        f"{WOBBLE_MAX_HZ} Hz (a quarter of the 100 kHz frame rate)")
    return {"wob_shape": WobbleShape.ELLIPSE.value, "wob_along": along, "wob_across": across,
            "wob_freq": hz}
