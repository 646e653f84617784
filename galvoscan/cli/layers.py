"""Layers on the command line (``--layer MATCH KEY=VALUE …``) and in job files (``[[layer]]``
tables): one key table for both, each value read by the same type as the ``mark`` option it
stands for (so its range and its words are the option's); each layer's wobble (the command
line's, or the layer's own) into its registers; and the layered job's plan said a layer a
line."""

import argparse
import difflib

from ..api import apply_wobble, job_wobble
from ..gateware.host.regmap import BY_NAME
from ..geometry.fill import LineOrder
from ..plan.layers import Layer
from ..geometry.field import PlanError
from ..profile.keys import DELAY_KEYS
from ..settings.laser import JOB_SETTINGS
from .args import contour_fill, fail, hatch_set, register_int, setting_type


__all__ = ["LayerAction", "layer_from_words", "layer_from_table", "LAYER_KEYS", "add_wobble",
           "describe_layers"]


def _yes_no(text):
    word = str(text).strip().lower()
    if word in ("yes", "true", "1", "on"):
        return True
    if word in ("no", "false", "0", "off"):
        return False
    raise argparse.ArgumentTypeError(f"must be yes or no, not {text!r}")


def _hatch_lines(text):
    try:
        return LineOrder(str(text))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be {', '.join(o.value for o in LineOrder)}, not {text!r}") from None


def _hatch(text):
    """A hatch set, or ``none`` (no hatch in this layer)."""
    return None if str(text).strip().lower() == "none" else hatch_set(str(text))


#: The delay registers a layer may set, µs: the jump delay (else the job's longest jump's) and
#: the laser, mark and polygon delays (else the profile's).
_DELAYS = ("jump_delay", *DELAY_KEYS.values())

#: key → (Layer field, the type that reads it, what it is). The job's settings are
#: :mod:`galvoscan.settings.laser`'s (their ranges and refusals); delays are registers, their
#: ranges the register map's.
LAYER_KEYS = {
    **{key: (setting.name, setting_type(setting), setting.unit or setting.help)
       for key, setting in JOB_SETTINGS.items() if key in ("speed", "power", "prr", "passes")},
    "pulses": ("pulses_per_point", register_int("pulses_per_point", "pulses per point"),
               "laser pulses a point (the pitch then follows the speed)"),
    "hatch": ("hatch", _hatch, "SPACING[,ANGLE[,STEP[,OFFSET]]], repeated for more sets; "
                               "none: no hatch"),
    "hatch_lines": ("hatch_lines", _hatch_lines, "serpentine, oneway or joined"),
    "contour": ("contour", contour_fill, "SPACING[,COUNT]"),
    "outline": ("outline", _yes_no, "yes or no"),
    **{key: (setting.name, setting_type(setting), setting.unit)
       for key, setting in JOB_SETTINGS.items() if key.startswith("wobble")},
    **{register: (register, register_int(register, register.replace("_", " ")),
                  BY_NAME[register].unit) for register in _DELAYS},
}


def _layer(match, pairs, where):
    """A :class:`~galvoscan.plan.layers.Layer` from ``(key, value)`` pairs (values as text or
    TOML gives them); ValueError, one line naming ``where`` and the key."""
    fields, hatch, delays = {}, [], []
    for key, value in pairs:
        if key not in LAYER_KEYS:
            near = difflib.get_close_matches(key, LAYER_KEYS, n=1)
            raise ValueError(f"{where}: {key!r} is not a layer setting"
                             f"{f' (did you mean {near[0]!r}?)' if near else ''}; the "
                             f"settings: {', '.join(LAYER_KEYS)}")
        name, read, _ = LAYER_KEYS[key]
        if isinstance(value, bool) and key != "outline" or isinstance(value, (list, dict)):
            raise ValueError(f"{where}: {key} must be one value, not {value!r}")
        try:
            parsed = read(str(value).lower() if isinstance(value, bool) else str(value))
        except argparse.ArgumentTypeError as error:
            raise ValueError(f"{where}: {key}: {error}") from None
        if key == "hatch":
            hatch.append(parsed)
        elif name in _DELAYS:
            delays.append((name, parsed))
        elif name in fields:
            raise ValueError(f"{where}: {key} is given twice")
        else:
            fields[name] = parsed
    if hatch:
        fields["hatch"] = tuple(h for h in hatch if h is not None)
    try:
        return Layer(match, delays_us=tuple(delays), **fields)
    except PlanError as error:
        raise ValueError(f"{where}: {error}") from None


def layer_from_words(words):
    """``MATCH KEY=VALUE …`` (the words of one ``--layer``) as a Layer; ValueError."""
    match, *rest = words
    pairs = []
    for word in rest:
        key, equals, value = word.partition("=")
        if not equals or not key:
            raise ValueError(f"--layer {match}: {word!r} is not KEY=VALUE (a drawing goes "
                             f"before --layer, or after --)")
        pairs.append((key.strip().lower().replace("-", "_"), value.strip()))
    return _layer(match, pairs, f"--layer {match}")


def layer_from_table(table, where):
    """A ``[[layer]]`` table of a job file as a Layer (``match`` and the keys above; a list
    of hatch sets as ``hatch = ["0.05,0", "0.05,90"]``); ValueError naming ``where``."""
    if not isinstance(table, dict) or not isinstance(table.get("match"), str):
        raise ValueError(f"{where}: a layer needs match = \"#rrggbb\" or a layer's name")
    pairs = []
    for key, value in table.items():
        if key == "match":
            continue
        values = value if key == "hatch" and isinstance(value, list) else [value]
        pairs += [(key, v) for v in values]
    return _layer(table["match"], pairs, f"{where} ({table['match']!r})")


def _number_or_text(text):
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return {"yes": True, "no": False}.get(text.lower(), text)


class LayerAction(argparse.Action):
    """``--layer MATCH KEY=VALUE …``: a :class:`~galvoscan.plan.layers.Layer` appended to
    ``layers``, and its words as a job file's ``[[layer]]`` table (for ``--save``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            layer = layer_from_words(values)
        except ValueError as error:
            parser.error(str(error))
        getattr(namespace, self.dest).append(layer)
        # As a job file's [[layer]] table, for --save: numbers as numbers.
        table = {"match": values[0]}
        for word in values[1:]:
            key, _, value = word.partition("=")
            key = key.strip().lower().replace("-", "_")
            value = _number_or_text(value.strip())
            if key == "hatch":
                table.setdefault("hatch", []).append(value)
            else:
                table[key] = value
        if getattr(namespace, "layer_tables", None) is None:
            namespace.layer_tables = []
        namespace.layer_tables.append(table)


def _wobble_words(registers, profile):
    if not registers.get("wob_shape"):
        return ""
    um = profile.mm_per_unit * 1000
    return (f", wobble ±{registers['wob_across'] * um:.0f} × ±{registers['wob_along'] * um:.0f} "
            f"µm at {registers['wob_freq']} Hz")


def add_wobble(job, args, profile):
    """Each layer's ``wob_*`` registers (the command line's wobble, a layer's own in its
    place, else the profile's) into its registers, by the API (:func:`galvoscan.api.
    apply_wobble`); one line for a wobble that reaches past the field. Returns whether
    anything wobbles."""
    try:
        return apply_wobble(job, job_wobble(args.wobble, args.wobble_along, args.wobble_hz,
                                            profile), profile)
    except PlanError as error:
        fail(error)


def describe_layers(job, profile):
    """A line a layer: what it matches, its settings, its plan and time."""
    lines = []
    for number, lj in enumerate(job.layers, 1):
        s, part = lj.settings, lj.job
        pitch = part.pitch
        sets = lj.layer.changes() if lj.layer else "the job's settings"
        lines.append(
            f"layer {number} {lj.label!r} ({sets}): "
            f"{len(part.segments)} segments, {part.mark_mm:.1f} mm marked at "
            f"{pitch.speed_mm_s:.1f} mm/s (pitch {pitch.pitch_mm * 1000:.1f} µm × "
            f"{pitch.pulses_per_point} pulse{'s' if pitch.pulses_per_point > 1 else ''}), "
            f"{s.power_percent:g} % ({profile.power_w(s.power_percent):.3g} W), "
            f"{s.prr_khz:g} kHz, {s.passes} pass(es)" + _wobble_words(part.registers, profile) +
            f"; {part.estimate_s:.3f} s")
    return lines
