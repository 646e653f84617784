"""The keys of a machine profile and the checks on their values.

This module holds what :mod:`galvoscan.profile.machine` reads a file with, below the profile itself:

* the ranges that the board's registers fix (``laser_prr``, ``laser_power``, ``jump_delay`` and
  the other delays), taken from the register map so that a profile can never ask for what a
  register cannot hold: :data:`FRAME_US`, :data:`PRR_RANGE_KHZ`, :data:`JUMP_DELAY_RANGE_US`,
  :data:`DELAY_KEYS`, :data:`POWER_REGISTER_MAX`;
* :class:`ProfileError`, the one error a profile that cannot be used raises;
* the key table: :data:`SECTIONS`, every section and its keys in the template's order, each a
  :class:`~galvoscan.settings.schema.ProfileKey` (kind, range, unit, default) declared in
  :mod:`galvoscan.settings.machine`, none here;
* the value checks (``_check``) and the messages for a key or section that is not known, with
  the nearest known name suggested (``_unknown_key``, ``_unknown_section``), and the number
  formatting they and the template share (``_num``, ``_toml_num``, ``_shown``).

:mod:`galvoscan.profile.machine` re-exports the public names; import them from there.
"""

import difflib
import math
import re

from ..gateware.host.regmap import BY_NAME, FRAME_US
from ..settings import laser as settings
from ..settings.machine import JUMP_DELAY, LASER_DELAYS, PROFILE


__all__ = ["FRAME_US", "PRR_RANGE_KHZ", "JUMP_DELAY_RANGE_US", "POWER_REGISTER_MAX", "DELAY_KEYS",
           "ProfileError", "SECTIONS", "default"]


# --- what the registers fix ------------------------------------------------------------------

_PRR = BY_NAME["laser_prr"]
_POWER = BY_NAME["laser_power"]
_JUMP = BY_NAME[JUMP_DELAY.name]

#: Steps of ``laser_prr`` per kHz (its unit is 100 Hz): the setting's.
_PRR_STEPS_PER_KHZ = settings.PRR_STEPS_PER_KHZ
assert _JUMP.unit == "µs", "jump_delay's unit changed: update the profile"

#: The pulse repetition rates the board can make, in kHz (``laser_prr``'s range).
PRR_RANGE_KHZ = settings.PRR.range
#: The jump delays the board can wait, in µs (``jump_delay``'s range).
JUMP_DELAY_RANGE_US = JUMP_DELAY.range
#: ``laser_power`` at 100 %.
POWER_REGISTER_MAX = _POWER.high


class ProfileError(ValueError):
    """A machine profile that cannot be used: one line naming the file and the key."""


# --- the keys --------------------------------------------------------------------------------

#: Every section and its keys, in the template's order (:data:`galvoscan.settings.machine.
#: PROFILE`): the ranges checked, the units and the defaults.
SECTIONS = PROFILE

#: ``[galvo]`` keys that go to a delay register as they are, in µs: key → register.
DELAY_KEYS = {key.name: key.setting.name for key in SECTIONS["galvo"]
              if key.setting in LASER_DELAYS}


def default(section, name):
    """The value of ``[section] name`` when a profile leaves it out."""
    return next(key.default for key in SECTIONS[section] if key.name == name)


def _num(value):
    """A number as a person writes it: 110, 0.05, 12000000."""
    if isinstance(value, int):
        return str(value)
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    return format(value, ".15g")


def _toml_num(value):
    """A number as the template writes it: 1_000_000, 0.05."""
    text = _num(value)
    if text.lstrip("-").isdigit() and abs(int(text)) >= 10_000:
        return f"{int(text):_}"
    return text


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _shown(value, limit=40, *, bare=False):
    """What the file said, for a message: short, one line (``bare``: a key name, without
    quotes unless it needs them)."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, str) and bare and _BARE_KEY.fullmatch(value):
        text = value
    elif isinstance(value, float):
        text = "nan" if math.isnan(value) else "inf" if value == math.inf else \
            "-inf" if value == -math.inf else _num(value)
    elif isinstance(value, int):
        text = str(value) if abs(value) < 10 ** 30 else "a huge integer"
    elif isinstance(value, dict):
        text = "a table"
    elif isinstance(value, list):
        text = "[" + ", ".join(_shown(v, limit) for v in value[:4]) + \
               (", …" if len(value) > 4 else "") + "]"
    elif hasattr(value, "isoformat"):
        text = value.isoformat()
    else:
        text = repr(value)
    return text if len(text) <= limit else text[:limit - 1] + "…"


def _range(key):
    unit = f" ({key.unit})" if key.unit else ""
    return f"from {_num(key.low)} to {_num(key.high)}{unit}"


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _in_range(value, key):
    """Compared before any conversion: a 400-digit integer must not overflow a float."""
    if isinstance(value, float) and not math.isfinite(value):
        return False
    return key.low <= value <= key.high


def _check(value, key, where):
    """The value of ``key`` as the profile holds it, or a ProfileError."""
    def bad(what):
        raise ProfileError(f"{where} {key.name} must be {what}, not {_shown(value)}")

    if key.kind == "number":
        if not _is_number(value) or not _in_range(value, key):
            bad(f"a number {_range(key)}")
        return float(value)
    if key.kind == "integer":
        whole = _is_number(value) and (isinstance(value, int) or
                                       (math.isfinite(value) and value == int(value)))
        if not whole or not _in_range(value, key):
            bad(f"a whole number {_range(key)}")
        return int(value)
    if key.kind in ("text", "path"):
        if not isinstance(value, str) or not value.strip():
            bad('text in quotes (e.g. "/dev/ttyUSB1")' if key.kind == "text" else
                'a file name in quotes (e.g. "f160.cor")')
        return value
    if key.kind == "bool":
        if not isinstance(value, bool):
            bad("true or false")
        return value
    if key.kind == "choice":
        choices = key.setting.choices
        if value not in choices:
            bad(" or ".join(f'"{c}"' for c in choices))
        return value
    if key.kind == "pair":
        if not (isinstance(value, list) and len(value) == 2 and
                all(_is_number(v) and _in_range(v, key) for v in value)):
            bad(f"two numbers [lowest, highest], each {_range(key)}")
        if value[0] > value[1]:
            bad("[lowest, highest] with lowest ≤ highest")
        return (float(value[0]), float(value[1]))
    raise AssertionError(key.kind)


def _closest(name, known, cutoff=0.6):
    close = difflib.get_close_matches(name, known, n=1, cutoff=cutoff)
    return close[0] if close else None


#: Keys a profile once had, and what says the same now: an old file is refused with the way
#: to write it, not with a guess at a name.
_RETIRED = {
    ("galvo", "settle_us_per_mm"): "a jump's delay is RTC's variable jump delay now: "
                                   "min_jump_delay_us for a jump of length 0, jump_delay_us for "
                                   "one of jump_length_limit_mm or longer, in proportion between "
                                   "(settle_us_per_mm = 0: jump_length_limit_mm = 0)",
}


def _unknown_key(name, section, path):
    if (section, name) in _RETIRED:
        return ProfileError(f"{path}: [{section}] {name} is no longer a key: "
                            f"{_RETIRED[section, name]}")
    known = [k.name for k in SECTIONS[section]]
    near = _closest(name, known)
    hint = f"; did you mean {near}?" if near else ""
    if not near:                                   # the right name in the wrong section?
        for other, keys in SECTIONS.items():
            elsewhere = _closest(name, [k.name for k in keys], cutoff=0.8)
            if other != section and elsewhere:
                hint = f"; did you mean [{other}] {elsewhere}?"
                break
    return ProfileError(f"{path}: unknown key [{section}] {_shown(name, bare=True)}{hint} "
                        f"([{section}] keys: {', '.join(known)})")


def _homes(name):
    """The sections that have a key ``name``, as ``[laser] or [defaults]``."""
    return " or ".join(f"[{section}]" for section, keys in SECTIONS.items()
                       if name in (k.name for k in keys))


def _unknown_section(name, value, path):
    sections = ", ".join(f"[{s}]" for s in SECTIONS)
    if not isinstance(value, dict):                # a key above the first section
        if _homes(name):
            return ProfileError(f"{path}: {name} is outside any section: put it under "
                                f"{_homes(name)}")
        near = _closest(name, sorted({k.name for keys in SECTIONS.values() for k in keys}))
        hint = f"; did you mean {near}, under {_homes(near)}?" if near else ""
        return ProfileError(f"{path}: unknown key {_shown(name, bare=True)} outside any "
                            f"section{hint} (sections: {sections})")
    near = _closest(name, list(SECTIONS))
    hint = f"; did you mean [{near}]?" if near else ""
    return ProfileError(f"{path}: unknown section [{_shown(name, bare=True)}]{hint} "
                        f"(sections: {sections})")
