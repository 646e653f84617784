"""The machine profile: what a marking or cleaning job needs to know about the machine that the
board's registers do not hold (the lens's field and correction table, the laser's power and
pulse rates, how long the mirrors take to settle, the link, and the job settings to use when the
command line gives none).

It is a TOML file, ``galvoscan.toml`` by default, that ``galvoscan machine init`` writes with a
comment on every key (:func:`galvoscan.profile.template.profile_text`)::

    [field]     size_mm, correction
    [link]      port, baud, spi, timeout_s
    [laser]     max_power_w, prr_khz = [min, max], spot_mm, guide
    [galvo]     jump_delay_us, min_jump_delay_us, jump_length_limit_mm, max_speed_mm_s,
                laser_on_delay_us, laser_off_delay_us, mark_delay_us, polygon_delay_us,
                polygon_scaled, tracking_delay_us, head_check
    [defaults]  speed_mm_s, power_percent, prr_khz, passes
    [wobble]    across_um, along_um, freq_hz
    [fly]       counts_per_mm, direction, belt_speed_mm_s, board_clock_mhz
    [sky]       mode, timelag_us, laser_on_shift_us, nprev_us, npost_us, limit

Every key is optional (its default is safe near a laser: 10 % power, one pass). A key or section
that is not known is an error, with the nearest known name suggested: a typo must not pass
silently into a job. Every problem with a file is a :class:`ProfileError`, one line that names the
file and the key; nothing else escapes :func:`load_profile`.

Every key's kind, unit, range, default and help is declared once, in
:mod:`galvoscan.settings.machine` (the keys that are a job's or a run's settings hold
:mod:`galvoscan.settings.laser`'s): the checks, the section dataclasses' defaults below, the
template and the docs' table of the keys are read from there. Ranges that the board fixes are
taken from the register map (``laser_prr``, ``laser_power``, ``jump_delay`` and the other
delays), so a profile can never ask for what a register cannot hold.

This module holds the profile itself: :class:`ProfileError`, the section dataclasses
(:class:`FieldSection`, :class:`LinkSection`, :class:`LaserSection`, :class:`GalvoSection`,
:class:`JobDefaults`), :class:`MachineProfile` and its derived numbers, :func:`default_profile`,
:func:`parse_profile`, :func:`load_profile` and the public constants. The key table and the value
checks are in :mod:`galvoscan.profile.keys` (below this module: it defines :class:`ProfileError`
and the register ranges; its public names are re-exported here), and the commented template in
:mod:`galvoscan.profile.template` (above it: the template reads the defaults from here).
"""

from dataclasses import dataclass, field as _field, replace
import math
import os
from pathlib import Path
from typing import Optional, Tuple

try:
    import tomllib  # novermin: tomli below where it is missing
except ModuleNotFoundError:                      # Python < 3.11
    import tomli as tomllib

from ..correction.files import load_table
from ..gateware.host.regmap import BY_NAME
from ..gateware.points import FIELD_CENTRE, FIELD_MAX
from .keys import (DELAY_KEYS, FRAME_US, JUMP_DELAY_RANGE_US, POWER_REGISTER_MAX, PRR_RANGE_KHZ,
                   SECTIONS, ProfileError, _JUMP, _PRR, _PRR_STEPS_PER_KHZ, _check, _num, _shown,
                   _unknown_key, _unknown_section, default as _default)


__all__ = ["ProfileError", "MachineProfile", "FieldSection", "LinkSection", "LaserSection",
           "GalvoSection", "JobDefaults", "WobbleSection", "FlySection", "SkySection", "load_profile", "parse_profile",
           "read_profile_text", "default_profile",
           "DEFAULT_PROFILE_NAME", "SECTIONS", "FULL_RANGE", "FRAME_US",
           "PRR_RANGE_KHZ", "JUMP_DELAY_RANGE_US", "POWER_REGISTER_MAX"]


#: The file ``galvoscan machine init`` writes and the job commands read when not told otherwise.
DEFAULT_PROFILE_NAME = "galvoscan.toml"

#: Galvo units across the field, on each axis (positions 0 … 65535).
FULL_RANGE = FIELD_MAX + 1

# --- the profile -----------------------------------------------------------------------------

@dataclass(frozen=True)
class FieldSection:
    #: Side of the square field that galvo positions 0 … 65535 span (the lens's field), mm.
    size_mm: float = _default("field", "size_mm")
    #: The correction table file (absolute), or None for the board's identity table.
    correction: Optional[Path] = _default("field", "correction")
    #: The focus shifter's galvo units a mm of Z (0: none).
    z_units_per_mm: float = _default("field", "z_units_per_mm")


@dataclass(frozen=True)
class LinkSection:
    #: Serial port of the board, or None (the command line must give it).
    port: Optional[str] = _default("link", "port")
    #: Serial rate the bitstream was built with (a build's default unless told otherwise).
    baud: int = _default("link", "baud")
    #: pyftdi URL of an FTDI SPI adapter, or None.
    spi: Optional[str] = _default("link", "spi")
    #: Seconds to wait for an answer.
    timeout_s: float = _default("link", "timeout_s")


@dataclass(frozen=True)
class LaserSection:
    #: Average power at 100 % (``laser_power`` = 255), W.
    max_power_w: float = _default("laser", "max_power_w")
    #: Lowest and highest pulse repetition rate the laser accepts, kHz.
    prr_khz: Tuple[float, float] = _default("laser", "prr_khz")
    #: Spot diameter at focus, mm.
    spot_mm: float = _default("laser", "spot_mm")
    #: The machine has a guide (red pointer) laser on the board's guide output.
    guide: bool = _default("laser", "guide")


@dataclass(frozen=True)
class GalvoSection:
    """The head's delays as SCANLAB's RTC defines them (docs/design/modes.md): the
    defaults are what ``galvoscan analyze --delays`` finds for Wan et al.'s JD1403 galvo (a
    10 mm head lagging its set point by some 80 µs) at 1 m/s: a line's ends and corners within
    20 % of its mid-line dose."""
    #: Laser-off wait after a jump of ``jump_length_limit_mm`` or longer, µs (RTC's
    #: JumpDelay; the board rounds it up to whole 10 µs frames).
    jump_delay_us: float = _default("galvo", "jump_delay_us")
    #: Laser-off wait after a jump of length 0, µs (RTC's MinJumpDelay).
    min_jump_delay_us: float = _default("galvo", "min_jump_delay_us")
    #: Jumps this long or longer wait ``jump_delay_us``, mm (RTC's JumpLengthLimit; 0: every
    #: jump does).
    jump_length_limit_mm: float = _default("galvo", "jump_length_limit_mm")
    #: Fastest marking speed a job may ask for, mm/s.
    max_speed_mm_s: float = _default("galvo", "max_speed_mm_s")
    #: The laser switches on this long after a mark's first point (negative: before), µs.
    laser_on_delay_us: float = _default("galvo", "laser_on_delay_us")
    #: The laser stays on this long after a mark's last point, µs.
    laser_off_delay_us: float = _default("galvo", "laser_off_delay_us")
    #: The mirrors hold a mark's end this long before a jump, µs.
    mark_delay_us: float = _default("galvo", "mark_delay_us")
    #: The mirrors hold a corner between two marks this long, laser on, µs (0: the corner is
    #: rounded by the mirror's lag, but not over-dosed).
    polygon_delay_us: float = _default("galvo", "polygon_delay_us")
    #: Scale each corner's polygon delay by (1 - cos φ) (RTC's variable polygon delay).
    polygon_scaled: bool = _default("galvo", "polygon_scaled")
    #: The mirrors' lag behind their set point on a line at constant speed, µs (a critically
    #: damped servo's 2/ωn: some 80 µs for the JD1403 galvo of Wan et al.).
    tracking_delay_us: float = _default("galvo", "tracking_delay_us")
    #: The head answers on its STATUS line and the laser obeys it (``head_check``).
    head_check: bool = _default("galvo", "head_check")


@dataclass(frozen=True)
class JobDefaults:
    #: Marking speed, mm/s.
    speed_mm_s: float = _default("defaults", "speed_mm_s")
    #: Laser power, % of ``max_power_w``.
    power_percent: float = _default("defaults", "power_percent")
    #: Pulse repetition rate, kHz.
    prr_khz: float = _default("defaults", "prr_khz")
    #: Times a job is repeated.
    passes: int = _default("defaults", "passes")


@dataclass(frozen=True)
class WobbleSection:
    #: Wobble amplitude across marked lines (to each side), µm; 0 with along_um 0: no wobble.
    across_um: float = _default("wobble", "across_um")
    #: Wobble amplitude along marked lines, µm (equal to across_um: a circle).
    along_um: float = _default("wobble", "along_um")
    #: Turns of the wobble figure a second, Hz.
    freq_hz: float = _default("wobble", "freq_hz")


@dataclass(frozen=True)
class FlySection:
    #: The belt's encoder, counts a mm (every edge), or None: no encoder.
    counts_per_mm: Optional[float] = _default("fly", "counts_per_mm")
    #: Which way the belt carries the part along the fly's axis: ``"+"`` or ``"-"``.
    direction: str = _default("fly", "direction")
    #: The belt's top speed, mm/s, or None: not said (``mark --belt-speed`` then).
    belt_speed_mm_s: Optional[float] = _default("fly", "belt_speed_mm_s")
    #: The board's system clock, MHz: the simulated encoder's period is in its clocks.
    board_clock_mhz: float = _default("fly", "board_clock_mhz")


@dataclass(frozen=True)
class SkySection:
    #: SkyWriting's mode for jobs that do not give one: 0 off, 1 … 3.
    mode: int = _default("sky", "mode")
    #: Timelag, µs, or None: ``[galvo] tracking_delay_us``.
    timelag_us: Optional[float] = _default("sky", "timelag_us")
    #: LaserOnShift, µs (signed).
    laser_on_shift_us: float = _default("sky", "laser_on_shift_us")
    #: Nprev and Npost, µs, or None: 0.15 and 0.1 × Timelag.
    nprev_us: Optional[float] = _default("sky", "nprev_us")
    npost_us: Optional[float] = _default("sky", "npost_us")
    #: Mode 3's Limit: corners whose cos φ is below it are taken apart.
    limit: float = _default("sky", "limit")


@dataclass(frozen=True)
class MachineProfile:
    """A machine profile, checked. Two profiles are equal if their settings are (where they were
    read from is not compared)."""

    field: FieldSection = FieldSection()
    link: LinkSection = LinkSection()
    laser: LaserSection = LaserSection()
    galvo: GalvoSection = GalvoSection()
    defaults: JobDefaults = JobDefaults()
    wobble: WobbleSection = WobbleSection()
    fly: FlySection = FlySection()
    sky: SkySection = SkySection()
    #: The file it was read from, or None for the built-in defaults.
    source: Optional[Path] = _field(default=None, compare=False)
    _table: object = _field(default=None, compare=False, repr=False)

    # --- derived numbers -----------------------------------------------------------------

    @property
    def units_per_mm(self):
        """Galvo units per mm in the field (65536 / ``size_mm``)."""
        return FULL_RANGE / self.field.size_mm

    @property
    def mm_per_unit(self):
        return self.field.size_mm / FULL_RANGE

    @property
    def variable_jump_delay(self):
        """Jumps shorter than ``jump_length_limit_mm`` wait less than ``jump_delay_us``."""
        galvo = self.galvo
        return galvo.jump_length_limit_mm > 0 and galvo.min_jump_delay_us < galvo.jump_delay_us

    def jump_delay_register(self, jump_mm=None):
        """``jump_delay`` (µs) for a jump of ``jump_mm`` (None: across the whole field,
        corner to corner, as a jump from wherever the head was may be), as SCANLAB's RTC's
        variable jump delay has it: ``jump_delay_us`` for a jump of ``jump_length_limit_mm``
        or longer (or for every jump, the limit 0), and for a shorter one
        ``min_jump_delay_us`` and the difference in proportion to its length; rounded *up* to
        a whole µs, at most what the register holds (65 535 µs). The board rounds it up to
        whole 10 µs frames."""
        if jump_mm is None:
            jump_mm = self.field.size_mm * math.sqrt(2)
        if isinstance(jump_mm, bool) or not isinstance(jump_mm, (int, float)) or \
                not math.isfinite(jump_mm) or jump_mm < 0:
            raise ValueError(f"a jump length must be a number of mm from 0 up, not {jump_mm!r}")
        galvo = self.galvo
        us = galvo.jump_delay_us
        if self.variable_jump_delay and jump_mm < galvo.jump_length_limit_mm:
            us = galvo.min_jump_delay_us + (galvo.jump_delay_us - galvo.min_jump_delay_us) * \
                jump_mm / galvo.jump_length_limit_mm
        # 1e-9: 500 µs is 500, not 501 because of a rounding error in the sum.
        return max(_JUMP.low, min(_JUMP.high, math.ceil(us - 1e-9)))

    def delay_registers(self):
        """The laser, mark and polygon delay registers (µs to the nearest, half up) and
        ``polygon_scaled``, as ``galvoscan mark`` writes them before a job."""
        registers = {reg: math.floor(getattr(self.galvo, key) + 0.5)
                     for key, reg in DELAY_KEYS.items()}
        registers["polygon_scaled"] = int(self.galvo.polygon_scaled)
        return registers

    def z_register(self, z_mm):
        """``z`` for a focus shift of ``z_mm`` (0: the focus shifter's middle, 32768), to the
        nearest unit; a :class:`ValueError` (one line) without a focus shifter, or past its
        range."""
        per_mm = self.field.z_units_per_mm
        if not per_mm:
            raise ValueError(f"Z {z_mm:g} mm needs a focus shifter: set [field] "
                             f"z_units_per_mm in the profile (its galvo units a mm)")
        units = math.floor(FIELD_CENTRE + z_mm * per_mm + 0.5)
        if not 0 <= units <= FIELD_MAX:
            low, high = -FIELD_CENTRE / per_mm, (FIELD_MAX - FIELD_CENTRE) / per_mm
            raise ValueError(f"Z {z_mm:g} mm is past the focus shifter's range "
                             f"({low:.3g} … {high:.3g} mm at {per_mm:g} units/mm)")
        return units

    def head_registers(self):
        """``head_check``, as a job writes it before it arms (a board that cannot read the
        head takes a job only with it 0)."""
        return {"head_check": int(self.galvo.head_check)}

    def power_register(self, percent):
        """``laser_power`` for ``percent`` of full power (0 … 100 → 0 … 255, to the nearest
        step, half up)."""
        if isinstance(percent, bool) or not isinstance(percent, (int, float)) or \
                not (0 <= percent <= 100):
            raise ValueError(f"laser power must be a number from 0 to 100 %, not {percent!r}")
        return min(POWER_REGISTER_MAX, math.floor(percent * POWER_REGISTER_MAX / 100 + 0.5))

    def power_w(self, percent):
        """The average power ``percent`` gives, in W (as the board will set it, register
        rounding included)."""
        return self.power_register(percent) / POWER_REGISTER_MAX * self.laser.max_power_w

    def prr_register(self, khz):
        """``laser_prr`` (100 Hz steps) for a pulse repetition rate of ``khz``; a rate outside
        the laser's ``prr_khz`` is refused (ValueError, one line)."""
        low, high = self.laser.prr_khz
        if isinstance(khz, bool) or not isinstance(khz, (int, float)) or \
                not (low <= khz <= high):
            where = f" ({self.source})" if self.source else ""
            raise ValueError(f"pulse repetition rate {_shown(khz)} kHz is outside this laser's "
                             f"{_num(low)} … {_num(high)} kHz ([laser] prr_khz{where})")
        steps = math.floor(khz * _PRR_STEPS_PER_KHZ + 0.5)
        # Rounding must not leave the laser's range (nor the register's).
        first = max(_PRR.low, math.ceil(low * _PRR_STEPS_PER_KHZ - 1e-9))
        last = min(_PRR.high, math.floor(high * _PRR_STEPS_PER_KHZ + 1e-9))
        if first <= last:
            steps = max(first, min(last, steps))
        return max(_PRR.low, min(_PRR.high, steps))

    def correction_table(self):
        """The :class:`~galvoscan.gateware.field.correction_table.CorrectionTable` that
        ``[field] correction`` names (read when the profile was), or None: the board's
        identity table."""
        return self._table

    def as_dict(self):
        """The settings as plain data, keyed as in the file (``galvoscan machine show --json``),
        with the derived numbers under ``"derived"``."""
        table = self._table
        return {
            "source": None if self.source is None else str(self.source),
            "field": {"size_mm": self.field.size_mm,
                      "correction": None if self.field.correction is None
                      else str(self.field.correction),
                      "correction_nodes": None if table is None else table.n,
                      "z_units_per_mm": self.field.z_units_per_mm},
            "link": {"port": self.link.port, "baud": self.link.baud, "spi": self.link.spi,
                     "timeout_s": self.link.timeout_s},
            "laser": {"max_power_w": self.laser.max_power_w,
                      "prr_khz": list(self.laser.prr_khz), "spot_mm": self.laser.spot_mm,
                      "guide": self.laser.guide},
            "galvo": {"jump_delay_us": self.galvo.jump_delay_us,
                      "min_jump_delay_us": self.galvo.min_jump_delay_us,
                      "jump_length_limit_mm": self.galvo.jump_length_limit_mm,
                      "max_speed_mm_s": self.galvo.max_speed_mm_s,
                      **{key: getattr(self.galvo, key) for key in DELAY_KEYS},
                      "polygon_scaled": self.galvo.polygon_scaled,
                      "tracking_delay_us": self.galvo.tracking_delay_us,
                      "head_check": self.galvo.head_check},
            "defaults": {"speed_mm_s": self.defaults.speed_mm_s,
                         "power_percent": self.defaults.power_percent,
                         "prr_khz": self.defaults.prr_khz, "passes": self.defaults.passes},
            "wobble": {"across_um": self.wobble.across_um, "along_um": self.wobble.along_um,
                       "freq_hz": self.wobble.freq_hz},
            "fly": {"counts_per_mm": self.fly.counts_per_mm, "direction": self.fly.direction,
                    "belt_speed_mm_s": self.fly.belt_speed_mm_s,
                    "board_clock_mhz": self.fly.board_clock_mhz},
            "sky": {"mode": self.sky.mode, "timelag_us": self.sky.timelag_us,
                    "laser_on_shift_us": self.sky.laser_on_shift_us,
                    "nprev_us": self.sky.nprev_us, "npost_us": self.sky.npost_us,
                    "limit": self.sky.limit},
            "derived": {
                "units_per_mm": self.units_per_mm,
                "mm_per_unit": self.mm_per_unit,
                "jump_delay_us_0mm": self.jump_delay_register(0),
                "jump_delay_us_1mm": self.jump_delay_register(1),
                "jump_delay_us_10mm": self.jump_delay_register(10),
                "delay_registers": self.delay_registers(),
                "default_power_register": self.power_register(self.defaults.power_percent),
                "default_power_w": self.power_w(self.defaults.power_percent),
                "default_prr_register": self.prr_register(self.defaults.prr_khz),
            },
        }


#: SkyWriting's laser-on (Timelag + LaserOnShift) is the ``laser_on_delay`` register.
_LASER_ON_HIGH_US = BY_NAME["laser_on_delay"].high
#: And Timelag the ``laser_off_delay`` register.
_LASER_OFF_HIGH_US = BY_NAME["laser_off_delay"].high


def default_profile():
    """The built-in profile: what ``galvoscan machine init`` writes."""
    return MachineProfile()


# --- reading ---------------------------------------------------------------------------------

_SECTION_CLASSES = {"field": FieldSection, "link": LinkSection, "laser": LaserSection,
                    "galvo": GalvoSection, "defaults": JobDefaults, "wobble": WobbleSection,
                    "fly": FlySection, "sky": SkySection}
assert all(tuple(k.name for k in keys) == tuple(_SECTION_CLASSES[name].__dataclass_fields__)
           for name, keys in SECTIONS.items())


def _resolve(text, folder):
    path = Path(text).expanduser()
    if not path.is_absolute():
        path = folder / path
    return Path(os.path.abspath(path))


def _load_correction(path, where):
    # A name with control characters in it is shown escaped: the message stays one line.
    shown = str(path) if str(path).isprintable() else repr(str(path))
    if not path.exists():
        raise ProfileError(f"{where} correction: no file {shown} (a relative path is relative "
                           f"to the profile's folder)")
    if path.is_dir():
        raise ProfileError(f"{where} correction: {shown} is a folder, not a table file")
    try:
        return load_table(path)
    except (ValueError, OSError) as error:       # TableFileError is a ValueError
        raise ProfileError(f"{where} correction: {_one_line(error)}") from None


def _one_line(error):
    return " ".join(str(error).split())


def parse_profile(text, *, path=DEFAULT_PROFILE_NAME):
    """The profile in TOML ``text``. ``path`` names it in messages, and a relative ``[field]
    correction`` is relative to its folder."""
    path = Path(path)
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProfileError(f"{path}: not valid TOML: {_one_line(error)}") from None
    except RecursionError:
        raise ProfileError(f"{path}: not valid TOML: arrays or tables nested too deeply") \
            from None

    sections = {}
    for name, value in document.items():
        if name not in SECTIONS:
            raise _unknown_section(name, value, path)
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            raise ProfileError(f"{path}: [{name}] must be one section [{name}], not [[{name}]]")
        if not isinstance(value, dict):
            raise ProfileError(f"{path}: [{name}] must be a section (a line [{name}] and its "
                               f"keys below it), not {name} = {_shown(value)}")
        keys = {k.name: k for k in SECTIONS[name]}
        checked = {}
        for key, item in value.items():
            if key not in keys:
                raise _unknown_key(key, name, path)
            checked[key] = _check(item, keys[key], f"{path}: [{name}]")
        sections[name] = checked

    link = sections.get("link", {})
    if link.get("port") is not None and link.get("spi") is not None:
        raise ProfileError(f"{path}: [link] port and spi are both set: the board is reached one "
                           f"way, leave one of them out")
    built = {name: cls(**sections.get(name, {})) for name, cls in _SECTION_CLASSES.items()}
    laser, galvo, defaults = built["laser"], built["galvo"], built["defaults"]
    low, high = laser.prr_khz
    if not low <= defaults.prr_khz <= high:
        raise ProfileError(f"{path}: [defaults] prr_khz must lie within the laser's "
                           f"{_num(low)} … {_num(high)} kHz ([laser] prr_khz), not "
                           f"{_num(defaults.prr_khz)}")
    if galvo.min_jump_delay_us > galvo.jump_delay_us:
        if "min_jump_delay_us" in sections.get("galvo", {}):
            raise ProfileError(f"{path}: [galvo] min_jump_delay_us must be at most jump_delay_us "
                               f"({_num(galvo.jump_delay_us)} µs; a short jump waits no longer "
                               f"than a long one), not {_num(galvo.min_jump_delay_us)}")
        # Its default, above a jump delay the file gives: that delay after every jump, as the
        # file says.
        built["galvo"] = galvo = replace(galvo, min_jump_delay_us=galvo.jump_delay_us)
    sky = built["sky"]
    timelag = sky.timelag_us if sky.timelag_us is not None else galvo.tracking_delay_us
    if sky.mode and not 0 <= timelag <= _LASER_OFF_HIGH_US:
        raise ProfileError(f"{path}: [sky] mode {sky.mode} needs a Timelag (timelag_us, else "
                           f"[galvo] tracking_delay_us) from 0 to {_LASER_OFF_HIGH_US} µs, not "
                           f"{_num(timelag)}")
    if sky.mode and not 0 <= timelag + sky.laser_on_shift_us <= _LASER_ON_HIGH_US:
        raise ProfileError(f"{path}: [sky] laser_on_shift_us must keep Timelag + it within "
                           f"0 … {_LASER_ON_HIGH_US} µs (Timelag {_num(timelag)} µs), not "
                           f"{_num(sky.laser_on_shift_us)}")
    if defaults.speed_mm_s > galvo.max_speed_mm_s:
        raise ProfileError(f"{path}: [defaults] speed_mm_s must be at most [galvo] "
                           f"max_speed_mm_s ({_num(galvo.max_speed_mm_s)} mm/s), not "
                           f"{_num(defaults.speed_mm_s)}")

    table = None
    correction = built["field"].correction
    if correction is not None:
        resolved = _resolve(correction, path.parent)
        table = _load_correction(resolved, f"{path}: [field]")
        built["field"] = FieldSection(size_mm=built["field"].size_mm, correction=resolved)
    return MachineProfile(**built, source=path, _table=table)


def read_profile_text(path):
    """The text of the profile file ``path``; :class:`ProfileError` (one line) if it cannot be
    read."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except IsADirectoryError:
        raise ProfileError(f"{path}: is a folder, not a profile file") from None
    except FileNotFoundError:
        raise ProfileError(f"{path}: no such file (`galvoscan machine init` writes one)") \
            from None
    except OSError as error:
        if path.is_dir():                     # Windows says "permission denied" for a folder
            raise ProfileError(f"{path}: is a folder, not a profile file") from None
        raise ProfileError(f"{path}: cannot read it: {error.strerror or error}") from None
    try:
        return data.decode("utf-8-sig")      # a byte-order mark, as Windows editors write
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise ProfileError(f"{path}, line {line}: not UTF-8 text (save it as UTF-8)") from None


def load_profile(path):
    """The profile in the TOML file ``path``; :class:`ProfileError` (one line) if it cannot be
    read or is not a valid profile."""
    return parse_profile(read_profile_text(path), path=Path(path))
