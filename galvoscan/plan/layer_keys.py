"""A layer's keys, declared once: what a job file's ``[[layer]]`` tables, ``mark --layer
MATCH KEY=VALUE …`` and ``mark``'s own fill options (``--hatch``, ``--hatch-lines``,
``--contour``, ``--no-outline``) are read by.

Each key (:class:`LayerKey`) is a :class:`~galvoscan.settings.schema.Setting`: a job's
settings (:mod:`galvoscan.settings.laser`), the delay registers (:mod:`galvoscan.settings.
machine`, their ranges the register map's), and the fill settings declared here
(:data:`HATCH`, :data:`HATCH_LINES`, :data:`CONTOUR`, :data:`OUTLINE`). Those are here and
not in :mod:`galvoscan.settings` because their values are the geometry's objects
(:class:`~galvoscan.geometry.fill.HatchSet`, :class:`~galvoscan.geometry.fill.Contour`,
:class:`~galvoscan.geometry.fill.LineOrder`), which the settings, below the geometry, cannot
make.

Here, below the API and the command line, a program builds a layer from a table as a job file
gives it (:func:`layer_from_table`, :func:`galvoscan.api.layer_from_table`), and the command
line splits ``KEY=VALUE`` words into the same reader (:func:`layer_from_pairs`); a value is
refused in the same one line either way.
"""

from dataclasses import dataclass
import difflib

from ..gateware.host.regmap import BY_NAME
from ..geometry.field import PlanError
from ..geometry.fill import Contour, HatchSet, LineOrder
from ..settings.laser import (PASSES, POWER, PRR, PULSES, SPEED, WOBBLE, WOBBLE_ALONG, WOBBLE_HZ,
                              Z)
from ..settings.machine import DELAYS
from ..settings.schema import Setting, SettingError, range_text, value_text
from ..settings.sky import SKY, SKY_LIMIT, SKY_SETTINGS
from .layers import Layer


__all__ = ["HATCH", "HATCH_LINES", "CONTOUR", "OUTLINE", "LayerKey", "LAYER_KEYS",
           "layer_from_pairs", "layer_from_table", "check_layer", "markdown_table"]


HATCH = Setting("hatch", "numbers", "mm, degrees, degrees a pass, mm", what="--hatch",
                flag="--hatch", key="hatch", metavar="SPACING[,ANGLE[,STEP[,OFFSET]]]",
                parts=("number",) * 4, make=HatchSet, repeated=True,
                help="fill closed shapes with lines SPACING mm apart at ANGLE degrees (holes by "
                     "the even-odd rule), turned STEP degrees more each pass, moved OFFSET mm "
                     "across; repeat it for more sets (0.05,0 and 0.05,90: a cross-hatch)")
HATCH_LINES = Setting("hatch_lines", "choice", flag="--hatch-lines", key="hatch_lines",
                      choices=tuple(order.value for order in LineOrder), make=LineOrder,
                      default=LineOrder.SERPENTINE.value,
                      help="the hatch's lines each the other way from the last (serpentine, "
                           "the default), all the same way (oneway), or serpentine and joined "
                           "inside the shape where they can be (joined: fewer jumps)")
CONTOUR = Setting("contour", "numbers", "mm, rings", what="--contour", flag="--contour",
                  key="contour", metavar="SPACING[,COUNT]", parts=("number", "integer"),
                  make=Contour,
                  help="fill closed shapes with rings inward from their edges, SPACING mm "
                       "apart (COUNT of them at most; default: until filled)")
#: ``mark``'s option is its opposite, ``--no-outline``.
OUTLINE = Setting("outline", "bool", key="outline", default=True,
                  help="mark the outlines of filled shapes (no: the fill only)")


@dataclass(frozen=True)
class LayerKey:
    """A layer's key: the ``setting`` its value is read by; ``none``: a word that gives none
    of it (``hatch=none``: no hatch in this layer, whatever the job's); ``said``: what
    ``--layer``'s help says of its value (None: the setting's unit, else its help, else its
    form)."""
    setting: Setting
    none: str = None
    said: str = None

    def __post_init__(self):
        if self.said is None:
            s = self.setting
            said = (s.unit or s.help) if s.ranged else \
                s.metavar if s.kind == "numbers" else value_text(s)
            object.__setattr__(self, "said", said)

    @property
    def key(self):
        return self.setting.key

    @property
    def field(self):
        """The :class:`~.layers.Layer`'s field it sets (a delay: a pair of ``delays_us``)."""
        return "delays_us" if self.setting in DELAYS else self.setting.name


#: key → :class:`LayerKey`, in ``--layer``'s help's order.
LAYER_KEYS = {one.key: one for one in (
    *(LayerKey(setting) for setting in (SPEED, POWER, PRR, PASSES, PULSES)),
    LayerKey(HATCH, none="none",
             said=f"{HATCH.metavar}, repeated for more sets; none: no hatch"),
    LayerKey(HATCH_LINES), LayerKey(CONTOUR), LayerKey(OUTLINE),
    *(LayerKey(setting) for setting in (WOBBLE, WOBBLE_ALONG, WOBBLE_HZ)),
    LayerKey(Z),
    # The jump delay (else the job's longest jump's) and the laser, mark and polygon delays
    # (else the profile's), said in their registers' units.
    *(LayerKey(setting, said=BY_NAME[setting.name].unit) for setting in DELAYS),
    # SkyWriting (else the job's): its mode, Timelag, LaserOnShift, Nprev, Npost, Limit.
    *(LayerKey(setting, said={SKY: "0 (off) … 3", SKY_LIMIT: "cos φ"}.get(setting))
      for setting in SKY_SETTINGS))}
assert {one.field for one in LAYER_KEYS.values()} <= set(Layer.__dataclass_fields__)


def layer_from_pairs(match, pairs, where):
    """A :class:`~.layers.Layer` matching ``match`` from ``(key, value)`` pairs (values as
    text or TOML gives them; a repeated key's values one pair each); ValueError, one line
    naming ``where`` and the key."""
    fields, repeated, delays = {}, {}, []
    for key, value in pairs:
        if key not in LAYER_KEYS:
            near = difflib.get_close_matches(key, LAYER_KEYS, n=1)
            raise ValueError(f"{where}: {key!r} is not a layer setting"
                             f"{f' (did you mean {near[0]!r}?)' if near else ''}; the "
                             f"settings: {', '.join(LAYER_KEYS)}")
        one = LAYER_KEYS[key]
        setting = one.setting
        if isinstance(value, bool) and setting.kind != "bool" or \
                isinstance(value, (list, dict)):
            raise ValueError(f"{where}: {key} must be one value, not {value!r}")
        text = str(value).lower() if isinstance(value, bool) else str(value)
        if one.none is not None and text.strip().lower() == one.none:
            parsed = None
        else:
            try:
                parsed = setting.parse(text)
            except SettingError as error:
                raise ValueError(f"{where}: {key}: {error}") from None
        if setting.repeated:
            repeated.setdefault(one.field, []).append(parsed)
        elif one.field == "delays_us":
            delays.append((setting.name, parsed))
        elif one.field in fields:
            raise ValueError(f"{where}: {key} is given twice")
        else:
            fields[one.field] = parsed
    for field, values in repeated.items():
        fields[field] = tuple(v for v in values if v is not None)
    try:
        return Layer(match, delays_us=tuple(delays), **fields)
    except PlanError as error:
        raise ValueError(f"{where}: {error}") from None


def layer_from_table(table, where="[[layer]]"):
    """A ``[[layer]]`` table of a job file (a dict, as TOML reads it) as a
    :class:`~.layers.Layer`: ``match`` and the keys of :data:`LAYER_KEYS`, a repeated key's
    values as a list (``hatch = ["0.05,0", "0.05,90"]``); ValueError, one line naming
    ``where``."""
    if not isinstance(table, dict) or not isinstance(table.get("match"), str):
        raise ValueError(f"{where}: a layer needs match = \"#rrggbb\" or a layer's name")
    pairs = []
    for key, value in table.items():
        if key == "match":
            continue
        one = LAYER_KEYS.get(key)
        values = value if one is not None and one.setting.repeated and \
            isinstance(value, list) else [value]
        pairs += [(key, v) for v in values]
    return layer_from_pairs(table["match"], pairs, f"{where} ({table['match']!r})")


_DELAY_SETTINGS = {setting.name: setting for setting in DELAYS}


def check_layer(layer, where):
    """``layer`` as a program made it (:class:`~.layers.Layer`'s fields, not a table's text)
    held to the same declarations as a table's: each value set is one its setting can take
    (a number in range, a HatchSet, a LineOrder, a bool), and each delay one of the delay
    registers, in its range; ValueError, one line naming ``where`` and the key. Without it a
    program's ``delays_us=(("laser_on_delay", 5000),)`` reached the plan's registers, and
    ``outline="no"`` (a true string) marked the outlines."""
    if not isinstance(layer, Layer):
        raise ValueError(f"{where}: a layer must be a Layer, not {type(layer).__name__}")
    for one in LAYER_KEYS.values():
        if one.field == "delays_us":
            continue
        value = getattr(layer, one.field)
        if value is None:
            continue
        values = value if one.setting.repeated else (value,)
        if one.setting.repeated and not isinstance(value, (tuple, list)):
            raise ValueError(f"{where}: {one.key} must be a tuple of its sets, not {value!r}")
        for item in values:
            try:
                one.setting.check(item)
            except SettingError as error:
                raise ValueError(f"{where}: {one.key}: {error}") from None
    if not isinstance(layer.delays_us, (tuple, list)):
        raise ValueError(f"{where}: delays_us must be (register, µs) pairs, not "
                         f"{layer.delays_us!r}")
    for pair in layer.delays_us:
        if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
            raise ValueError(f"{where}: delays_us must be (register, µs) pairs, not {pair!r}")
        name, value = pair
        setting = _DELAY_SETTINGS.get(name)
        if setting is None:
            raise ValueError(f"{where}: {name!r} is not a delay a layer may set (the delays: "
                             f"{', '.join(_DELAY_SETTINGS)})")
        try:
            setting.check(value)
        except SettingError as error:
            raise ValueError(f"{where}: {name}: {error}") from None


def markdown_table():
    """The layer keys as a Markdown table: the key, what its value is, its unit, range and
    what it is (the docs' table, generated, never written by hand)."""
    rows = ["| key | value | unit | range | what |", "|---|---|---|---|---|"]
    for key, one in LAYER_KEYS.items():
        s = one.setting
        value = value_text(s) + (", repeated for more" if s.repeated else "") + \
            (f"; `{one.none}`: no {key}" if one.none else "")
        rows.append(f"| `{key}` | {value} | {s.unit or '—'} | {range_text(s)} | {s.help} |")
    return "\n".join(rows)
