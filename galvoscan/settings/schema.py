"""What a setting is: :class:`Setting` (its name, kind, unit, range, default and help, and the
words the command line, a job file, a layer and the machine profile know it by), and how a
value of it is read from text (:meth:`Setting.parse`) and shown (:func:`number_text`).

Written on :mod:`dataclasses`, not pydantic, attrs or cattrs. There are a few dozen settings,
each a number or a word with a range; what matters is the one line a wrong value gets, and
those lines are galvoscan's own (``speed must be from 0.1 to 100e3, not 1e9``, and the
profile's ``[defaults] speed_mm_s must be a number from 0.1 to 100000 (mm/s), not …``), which
pydantic's ``ValidationError`` texts (``Input should be less than or equal to …``) would
have to be translated back into, one error type at a time. A runtime dependency for a range
check and a help text is not worth that.

This module imports nothing of galvoscan's: the command line (:mod:`galvoscan.cli`), job
files, layers and the profile import it.
"""

import math
from dataclasses import dataclass


__all__ = ["Setting", "SettingError", "number_text", "markdown_table"]


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


@dataclass(frozen=True)
class Setting:
    """One setting, declared once.

    ``name``: its Python name, with its unit (``speed_mm_s``); ``kind``: ``"number"`` (a
    finite float) or ``"integer"`` (decimal, ``0x…`` or ``0b…``); ``unit``: as a person
    writes it (``mm/s``; empty: none); ``low``, ``high``: the range, both ends allowed;
    ``default``: the value when none is given (None: another source's, said in ``help``);
    ``help``: what it is, for ``--help`` and the docs; ``what``: the word a refusal starts
    with (``speed``); ``flag``: the command line's option (``--speed``); ``key``: a job
    file's and a layer's key (``speed``); ``metavar``: the option's placeholder;
    ``default_said``: where the value comes from when ``default`` is None (``the profile's``).
    """
    name: str
    kind: str
    unit: str
    low: float
    high: float
    help: str
    what: str
    default: object = None
    flag: str = None
    key: str = None
    metavar: str = None
    default_said: str = None

    def __post_init__(self):
        if self.kind not in ("number", "integer"):
            raise ValueError(f"{self.name}: kind must be number or integer, not {self.kind!r}")
        if not self.low <= self.high:
            raise ValueError(f"{self.name}: range {self.low} … {self.high} is empty")
        if self.default is not None and not self.low <= self.default <= self.high:
            raise ValueError(f"{self.name}: default {self.default} outside its range")

    @property
    def range(self):
        """``(low, high)``, in the setting's unit."""
        return self.low, self.high

    def parse(self, text):
        """The value ``text`` (as typed: ``1e6``, ``0x10``) stands for, or a
        :class:`SettingError` saying why not."""
        if self.kind == "integer":
            try:
                value = int(str(text), 0)
            except ValueError:
                raise SettingError(f"{self.what} must be an integer, not {text!r}") from None
            if not self.low <= value <= self.high:
                raise SettingError(f"{self.what} must be from {self.low} to {self.high}, not "
                                   f"{value}")
            return value
        try:
            value = float(text)
        except ValueError:
            raise SettingError(f"{self.what} must be a number, not {text!r}") from None
        if not math.isfinite(value) or not self.low <= value <= self.high:
            raise SettingError(f"{self.what} must be from {number_text(self.low)} to "
                               f"{number_text(self.high)}, not {text}")
        return value

    def check(self, value):
        """``value`` (a number a program gives) if it is in range, else the same
        :class:`SettingError` as :meth:`parse` gives its text."""
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                (self.kind == "integer" and not isinstance(value, int)):
            kind = "an integer" if self.kind == "integer" else "a number"
            raise SettingError(f"{self.what} must be {kind}, not {value!r}")
        return self.parse(repr(value))

    def described(self, default=None, default_text=None):
        """The help with the unit, range and default: ``marking speed (mm/s, 0.1 … 100e3;
        default: the profile's)``. ``default``: a command's own, in place of the setting's;
        ``default_text``: where the value comes from when there is no default."""
        default = self.default if default is None else default
        unit = f"{self.unit}, " if self.unit else ""
        default_text = default_text or self.default_said
        said = f"; default: {number_text(default)}" if default is not None else \
            (f"; default: {default_text}" if default_text else "")
        return f"{self.help} ({unit}{number_text(self.low)} … {number_text(self.high)}{said})"


def markdown_table(settings):
    """``settings`` as a Markdown table: the option, the job file's key, the unit, the range,
    the default and what it is (the docs' table of them, generated, never written by hand)."""
    rows = ["| option | job file key | unit | range | default | what |",
            "|---|---|---|---|---|---|"]
    for s in settings:
        default = number_text(s.default) if s.default is not None else s.default_said
        rows.append(f"| `{s.flag}` | {f'`{s.key}`' if s.key else '—'} | {s.unit or '—'} | "
                    f"{number_text(s.low)} … {number_text(s.high)} | {default} | {s.help} |")
    return "\n".join(rows)
