"""What a setting is: :class:`Setting` (its name, kind, unit, range, default and help, and the
words the command line, a job file, a layer and the machine profile know it by), how a value
of it is read from text (:meth:`Setting.parse`) and shown (:func:`number_text`), and
:class:`ProfileKey`, a setting as the machine profile holds it (under a section, with the
profile's own default).

Written on :mod:`dataclasses`, not pydantic, attrs or cattrs. There are a few dozen settings,
each a number or a word with a range; what matters is the one line a wrong value gets, and
those lines are galvoscan's own (``speed must be from 0.1 to 100e3, not 1e9``, and the
profile's ``[defaults] speed_mm_s must be a number from 0.1 to 100000 (mm/s), not …``), which
pydantic's ``ValidationError`` texts (``Input should be less than or equal to …``) would
have to be translated back into, one error type at a time. A runtime dependency for a range
check and a help text is not worth that.

This module imports nothing of galvoscan's: the command line (:mod:`galvoscan.cli`), job
files, layers and the profile import it. A setting whose value is an object of a layer above
(a hatch set, a contour) is declared there, its object made by ``make``.
"""

import math
from dataclasses import dataclass


__all__ = ["Setting", "ProfileKey", "SettingError", "KINDS", "number_text", "range_text",
           "value_text", "markdown_table", "profile_table"]


#: What a setting's value can be. ``number``: a finite float; ``integer``: decimal, ``0x…`` or
#: ``0b…``; ``text``: a word or more (a port's name, a URL); ``path``: a file's name; ``bool``:
#: yes or no; ``choice``: one of ``choices``; ``pair``: ``[lowest, highest]``, each in range;
#: ``numbers``: up to ``len(parts)`` numbers separated by commas, the first needed (a hatch
#: set: ``SPACING[,ANGLE[,STEP[,OFFSET]]]``), made into one value by ``make``.
KINDS = ("number", "integer", "text", "path", "bool", "choice", "pair", "numbers")

#: The words a yes-or-no setting takes as text (a layer's ``outline=no``).
_YES = ("yes", "true", "1", "on")
_NO = ("no", "false", "0", "off")


class SettingError(ValueError):
    """A value a setting cannot take: its one line (``speed must be from 0.1 to 100e3, not
    x``)."""


def number_text(value):
    """A bound as a person writes it: 16e6 rather than 1.6e+07."""
    if abs(value) >= 1e5 and value == int(value):
        for exponent in (9, 6, 3):
            if value % 10 ** exponent == 0:
                return f"{value / 10 ** exponent:g}e{exponent}"
    return f"{value:g}"


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class Setting:
    """One setting, declared once.

    ``name``: its Python name, with its unit (``speed_mm_s``); ``kind``: one of
    :data:`KINDS`; ``unit``: as a person writes it (``mm/s``; empty: none); ``low``,
    ``high``: the range of a ``number``, ``integer`` or ``pair``, both ends allowed;
    ``default``: the value when none is given (None: another source's, said in ``help``);
    ``help``: what it is, for ``--help`` and the docs; ``what``: the word a refusal starts
    with (``speed``; None: the refusal says only what the value must be, its reader naming
    the key); ``flag``: the command line's option (``--speed``); ``key``: a job file's and a
    layer's key (``speed``); ``metavar``: the option's placeholder (a ``numbers`` setting's
    form, as its refusal says it); ``default_said``: where the value comes from when
    ``default`` is None (``the profile's``); ``choices``: a ``choice``'s words; ``parts``: a
    ``numbers`` setting's parts, each ``"number"`` or ``"integer"``; ``make``: what builds
    the value of a ``choice`` or ``numbers`` setting from its word or numbers (its
    :class:`ValueError` the refusal's reason); ``repeated``: given more than once, each adds
    a value (hatch sets).
    """
    name: str
    kind: str
    unit: str = ""
    low: float = None
    high: float = None
    help: str = ""
    what: str = None
    default: object = None
    flag: str = None
    key: str = None
    metavar: str = None
    default_said: str = None
    choices: tuple = ()
    parts: tuple = ()
    make: object = None
    repeated: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"{self.name}: kind must be one of {', '.join(KINDS)}, not "
                             f"{self.kind!r}")
        if self.ranged:
            if self.low is None or self.high is None or not self.low <= self.high:
                raise ValueError(f"{self.name}: range {self.low} … {self.high} is empty")
        elif (self.low, self.high) != (None, None):
            raise ValueError(f"{self.name}: a {self.kind} has no range")
        if self.kind == "choice" and not self.choices:
            raise ValueError(f"{self.name}: a choice needs its choices")
        if self.kind == "numbers" and not (self.parts and self.metavar and self.make):
            raise ValueError(f"{self.name}: numbers need their parts, form (metavar) and make")
        if self.default is not None:
            try:
                self.check(self.default)
            except SettingError:
                raise ValueError(f"{self.name}: default {self.default} outside its range") \
                    from None

    @property
    def ranged(self):
        """Whether the setting has a range (``low`` … ``high``)."""
        return self.kind in ("number", "integer", "pair")

    @property
    def range(self):
        """``(low, high)``, in the setting's unit."""
        return self.low, self.high

    def _refusal(self, rest):
        return SettingError(f"{self.what} must be {rest}" if self.what else f"must be {rest}")

    def parse(self, text):
        """The value ``text`` (as typed: ``1e6``, ``0x10``, ``0.05,45``, ``no``) stands for,
        or a :class:`SettingError` saying why not."""
        if self.kind == "integer":
            try:
                value = int(str(text), 0)
            except ValueError:
                raise self._refusal(f"an integer, not {text!r}") from None
            if not self.low <= value <= self.high:
                raise self._refusal(f"from {self.low} to {self.high}, not {value}")
            return value
        if self.kind == "number":
            try:
                value = float(text)
            except ValueError:
                raise self._refusal(f"a number, not {text!r}") from None
            if not math.isfinite(value) or not self.low <= value <= self.high:
                raise self._refusal(f"from {number_text(self.low)} to "
                                    f"{number_text(self.high)}, not {text}")
            return value
        if self.kind == "bool":
            word = str(text).strip().lower()
            if word in _YES or word in _NO:
                return word in _YES
            raise self._refusal(f"yes or no, not {text!r}")
        if self.kind == "choice":
            if str(text) not in self.choices:
                raise self._refusal(f"{', '.join(self.choices)}, not {text!r}")
            return self.make(str(text)) if self.make else str(text)
        if self.kind in ("text", "path"):
            if not str(text).strip():
                raise self._refusal(f"{'a file name' if self.kind == 'path' else 'text'}, "
                                    f"not {text!r}")
            return str(text)
        if self.kind == "pair":
            return self._pair(text)
        return self._numbers(text)

    def _pair(self, text):
        parts = str(text).replace(" ", "").strip("[]").split(",")
        try:
            if len(parts) != 2:
                raise ValueError
            low, high = (float(part) for part in parts)
        except ValueError:
            raise self._refusal(f"LOWEST,HIGHEST, not {text!r}") from None
        if not all(math.isfinite(v) and self.low <= v <= self.high for v in (low, high)):
            raise self._refusal(f"two numbers each from {number_text(self.low)} to "
                                f"{number_text(self.high)}, not {text}")
        if low > high:
            raise self._refusal(f"LOWEST,HIGHEST with lowest ≤ highest, not {text}")
        return low, high

    def _numbers(self, text):
        parts = str(text).replace(" ", "").split(",")
        try:
            if not 1 <= len(parts) <= len(self.parts):
                raise ValueError
            values = [float(part) if kind == "number" else int(part)
                      for part, kind in zip(parts, self.parts)]
        except ValueError:
            raise self._refusal(f"{self.metavar} ({self.unit}), not {text!r}") from None
        try:
            return self.make(*values)
        except ValueError as error:
            raise SettingError(f"{self.what} {text}: {error}") from None

    def check(self, value):
        """``value`` (a value a program gives) if the setting can take it, else the same
        :class:`SettingError` as :meth:`parse` gives its text."""
        if self.kind in ("number", "integer"):
            if not _is_number(value) or (self.kind == "integer" and not isinstance(value, int)):
                kind = "an integer" if self.kind == "integer" else "a number"
                raise self._refusal(f"{kind}, not {value!r}")
            return self.parse(repr(value))
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise self._refusal(f"yes or no, not {value!r}")
            return value
        if self.kind == "pair":
            if not (isinstance(value, (tuple, list)) and len(value) == 2 and
                    all(_is_number(v) for v in value)):
                raise self._refusal(f"two numbers, not {value!r}")
            return self._pair(",".join(repr(float(v)) for v in value))
        if isinstance(self.make, type) and isinstance(value, self.make):
            return value                        # made already (a HatchSet, a LineOrder)
        if not isinstance(value, str):
            raise self._refusal(f"text, not {value!r}")
        return self.parse(value)

    def described(self, default=None, default_text=None):
        """The help with the unit, range and default: ``marking speed (mm/s, 0.1 … 100e3;
        default: the profile's)``. ``default``: a command's own, in place of the setting's;
        ``default_text``: where the value comes from when there is no default."""
        if not self.ranged:
            return self.help
        default = self.default if default is None else default
        unit = f"{self.unit}, " if self.unit else ""
        default_text = default_text or self.default_said
        said = f"; default: {number_text(default)}" if default is not None else \
            (f"; default: {default_text}" if default_text else "")
        return f"{self.help} ({unit}{number_text(self.low)} … {number_text(self.high)}{said})"


def range_text(setting):
    """``setting``'s range as the docs' tables write it: ``0.1 … 100e3``; ``—`` for none."""
    if not setting.ranged:
        return "—"
    return f"{number_text(setting.low)} … {number_text(setting.high)}"


def value_text(setting, kind=None, *, toml=False):
    """What a value of ``setting`` (read as ``kind``, when not its own) is, as the docs'
    tables say it: ``a number``, ``yes or no``, ``serpentine, oneway or joined``, a
    ``numbers`` setting's form; ``toml``: as a TOML file writes it (``true or false``)."""
    kind = kind or setting.kind
    if toml and kind == "bool":
        return "true or false"
    if kind == "choice":
        return f"{', '.join(setting.choices[:-1])} or {setting.choices[-1]}"
    if kind == "numbers":
        return f"`{setting.metavar}`"
    return {"number": "a number", "integer": "a whole number", "text": "text",
            "path": "a file name", "bool": "yes or no",
            "pair": "[lowest, highest]"}[kind]


def markdown_table(settings):
    """``settings`` as a Markdown table: the option, the job file's key, the unit, the range,
    the default and what it is (the docs' table of them, generated, never written by hand)."""
    rows = ["| option | job file key | unit | range | default | what |",
            "|---|---|---|---|---|---|"]
    for s in settings:
        default = number_text(s.default) if s.default is not None else s.default_said
        # (A choice's range is its words.)
        span = f"{number_text(s.low)} … {number_text(s.high)}" if s.ranged else \
            ", ".join(s.choices) if s.kind == "choice" else "—"
        rows.append(f"| `{s.flag}` | {f'`{s.key}`' if s.key else '—'} | {s.unit or '—'} | "
                    f"{span} | {default or '—'} | {s.help} |")
    return "\n".join(rows)


@dataclass(frozen=True)
class ProfileKey:
    """A key of the machine profile, ``[section] name``: the :class:`Setting` it holds (its
    unit and range, and its help unless ``help`` is given), ``default`` the value a profile
    that leaves it out has (None: the setting's), and ``kind`` how a file writes it when not
    as the setting is read from text (``[link] baud``, a ``number`` on the command line, is
    a whole number here; ``[laser] prr_khz`` is a ``pair``, the PRRs the laser takes; a delay
    register's ``integer`` µs is a ``number``, rounded when written).

    :mod:`galvoscan.profile` checks a file's values by these; their ``kind``, ``low``,
    ``high`` and ``unit`` are what its checks and its template read."""
    section: str
    name: str
    setting: Setting
    default: object = None
    kind: str = None
    help: str = None

    def __post_init__(self):
        for name in ("default", "kind", "help"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, getattr(self.setting, name))
        if self.kind not in KINDS:
            raise ValueError(f"[{self.section}] {self.name}: kind {self.kind!r} is not one of "
                             f"{', '.join(KINDS)}")
        if (self.kind in ("number", "integer", "pair")) != self.setting.ranged:
            raise ValueError(f"[{self.section}] {self.name}: a {self.kind} of a "
                             f"{self.setting.kind} setting")
        if self.default is None:
            return
        values = self.default if self.kind == "pair" else (self.default,)
        if self.kind in ("number", "integer", "pair"):
            if len(values) != (2 if self.kind == "pair" else 1) or not all(
                    _is_number(v) and self.low <= v <= self.high for v in values):
                raise ValueError(f"[{self.section}] {self.name}: default {self.default} "
                                 f"outside its range")
        else:
            self.setting.check(self.default)

    @property
    def low(self):
        return self.setting.low

    @property
    def high(self):
        return self.setting.high

    @property
    def unit(self):
        return self.setting.unit


def _default_text(key):
    value = key.default
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, tuple):
        return "[" + ", ".join(number_text(v) for v in value) + "]"
    if _is_number(value):
        return number_text(value)
    return str(value)


def profile_table(sections):
    """The machine profile's keys (``sections``: section → its :class:`ProfileKey` s) as a
    Markdown table: the key, what its value is, its unit, range and default and what it is
    (the docs' table, generated, never written by hand)."""
    rows = ["| key | value | unit | range | default | what |", "|---|---|---|---|---|---|"]
    for section, keys in sections.items():
        for key in keys:
            rows.append(f"| `[{section}] {key.name}` | {value_text(key.setting, key.kind, toml=True)} | "
                        f"{key.unit or '—'} | {range_text(key.setting)} | "
                        f"{_default_text(key)} | {key.help} |")
    return "\n".join(rows)
