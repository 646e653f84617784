"""Layers on the command line (``--layer MATCH KEY=VALUE …``): the words split into the key
table's reader (:func:`galvoscan.plan.layer_keys.layer_from_pairs`, which job files'
``[[layer]]`` tables and the API read with too: one table, each value read by the setting
declared for it); each layer's wobble (the command line's, or the layer's own) into its
registers; and the layered job's plan said a layer a line."""

import argparse

from ..api import apply_wobble, apply_z, job_wobble
from ..geometry.field import PlanError
from ..plan.layer_keys import LAYER_KEYS, layer_from_pairs
from .args import fail
from .job_reports import z_mm


__all__ = ["LayerAction", "layer_from_words", "add_wobble", "add_z", "describe_layers"]


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
    return layer_from_pairs(match, pairs, f"--layer {match}")


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
            if key in LAYER_KEYS and LAYER_KEYS[key].setting.repeated:
                table.setdefault(key, []).append(value)
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


def add_z(job, args, profile):
    """Each layer's ``z`` register (the command line's ``--z``, a layer's own in its place),
    by the API (:func:`galvoscan.api.apply_z`); one line for a Z the profile cannot make."""
    try:
        return apply_z(job, args.z, profile)
    except PlanError as error:
        fail(error)


def _z_words(registers, profile):
    if "z" not in registers:
        return ""
    return f", Z {z_mm(registers, profile):+g} mm"


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
            (_z_words(part.registers, profile) if lj.layer is None or lj.layer.z_mm is None
             else "") +
            f"; {part.estimate_s:.3f} s")
    return lines
