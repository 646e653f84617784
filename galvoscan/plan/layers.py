"""Layers: settings of their own for parts of a job, picked by an SVG stroke or fill colour,
an SVG layer (an Inkscape ``<g inkscape:groupmode="layer">``, by its label) or a DXF layer (by
its name). EzCad calls them pens, LightBurn layers, meerk40t operations.

A :class:`Layer` names what it matches and the settings it changes (speed, power, PRR,
passes, pulses per point, hatch sets, contour, outline, wobble, delays); what it leaves
unset is the job's. Each path of a drawing goes to the first layer that matches it (its
colour, else its layer's name); what no layer matches is marked last, at the job's own
settings. The layers run in the order given, each as a job of its own (the board holds one
speed, power and set of delays at a time).
"""

import re
from dataclasses import dataclass, replace

import numpy as np
from matplotlib.colors import CSS4_COLORS

from ..geometry.drawing import Drawing
from ..geometry.field import place, Placement, PlanError
from ..geometry.order import jump_length
from ..geometry.speed import jump_mark_lengths
from .sky import LAYER_FIELDS as _SKY_FIELDS, layer_sky
from .vector_job import check_clear, plan_objects, VectorJob

from ..settings.laser import JOB_SETTINGS


__all__ = ["Layer", "split_by_layer", "preview_colour", "with_file_layers"]


#: The unit of each of a layer's settings that is a job's (:mod:`galvoscan.settings.laser`).
_UNITS = {setting.name: setting.unit for setting in JOB_SETTINGS.values()}

_HEX = re.compile(r"#([0-9a-f]{3}|[0-9a-f]{6})")


def colour_key(text):
    """``#rgb`` or ``#rrggbb`` as ``#rrggbb``, lower case; None when ``text`` is not one."""
    text = text.strip().lower()
    match = _HEX.fullmatch(text)
    if not match:
        return None
    digits = match.group(1)
    return "#" + ("".join(d * 2 for d in digits) if len(digits) == 3 else digits)


@dataclass(frozen=True)
class Layer:
    """A layer: what it matches, and the settings it gives (None: the job's).

    ``match`` is a colour (``#rrggbb``; ``#rgb`` is taken as it) or a layer's name (an
    Inkscape layer's label, a DXF layer's, compared without regard to case). Wobble is in µm
    (``wobble_um`` across, ``wobble_along_um`` along, ``wobble_hz``); ``delays_us`` are
    ``(register, µs)`` pairs.
    """
    match: str
    speed_mm_s: float = None
    power_percent: float = None
    prr_khz: float = None
    passes: int = None
    pulses_per_point: int = None
    hatch: tuple = None
    hatch_lines: object = None
    contour: object = None
    outline: bool = None
    wobble_um: float = None
    wobble_along_um: float = None
    wobble_hz: float = None
    z_mm: float = None
    delays_us: tuple = ()
    sky_mode: int = None
    timelag_us: float = None
    laser_on_shift_us: float = None
    nprev_us: float = None
    npost_us: float = None
    sky_limit: float = None

    def __post_init__(self):
        if not str(self.match).strip():
            raise PlanError("a layer needs something to match: a colour (#rrggbb) or a "
                            "layer's name")
        object.__setattr__(self, "match", colour_key(self.match) or str(self.match).strip())

    @property
    def is_colour(self):
        return colour_key(self.match) is not None

    @property
    def colour_name(self):
        """The colour a CSS colour name stands for (``red``: ``#ff0000``), else None: a name
        such as ``red`` matches paths of that colour as well as a layer of that name."""
        found = CSS4_COLORS.get(self.match.lower())
        return found.lower() if found else None

    def matches(self, style):
        if style is None:
            return False
        if self.is_colour:
            return style.colour == self.match
        named = self.colour_name
        return (style.layer is not None and style.layer.casefold() == self.match.casefold()) \
            or (named is not None and style.colour == named)

    def settings(self, base):
        """``base`` (a :class:`~.objects.JobSettings`) with this layer's settings in it."""
        given = {name: getattr(self, name) for name in
                 ("speed_mm_s", "power_percent", "prr_khz", "passes", "pulses_per_point",
                  "hatch", "hatch_lines", "contour", "outline")
                 if getattr(self, name) is not None}
        if self.delays_us:
            given["delays_us"] = tuple({**dict(base.delays_us), **dict(self.delays_us)}.items())
        if any(getattr(self, name) is not None for name in _SKY_FIELDS):
            given["sky"] = layer_sky(self, base.sky)
        return replace(base, **given)

    def changes(self):
        """What the layer sets, as a person reads it: ``"speed 500 mm/s, power 80 %"``."""
        out = []
        words = {"speed_mm_s": "speed", "power_percent": "power", "prr_khz": "PRR",
                 "passes": "passes", "pulses_per_point": "pulses per point",
                 "wobble_um": "wobble", "wobble_along_um": "wobble along", "wobble_hz": "wobble",
                 "z_mm": "Z"}
        for name, what in words.items():
            value = getattr(self, name)
            unit = _UNITS.get(name, "")             # the setting's (pulses: none)
            if value is not None:
                out.append(f"{what} {value:g}{' ' + unit if unit else ''}")
        if self.hatch is not None:
            out.append("hatch " + (" + ".join(f"{h.spacing_mm:g} mm at {h.angle_deg:g}°"
                                              for h in self.hatch) or "none"))
        if self.hatch_lines is not None:
            out.append(f"hatch lines {self.hatch_lines.value}")
        if self.contour is not None:
            out.append(f"contour {self.contour.spacing_mm:g} mm")
        if self.outline is not None:
            out.append("outline" if self.outline else "no outline")
        out += [f"{register.replace('_', ' ')} {value} µs" for register, value in self.delays_us]
        sky_words = {"sky_mode": "sky", "timelag_us": "timelag", "laser_on_shift_us":
                     "laser-on shift", "nprev_us": "nprev", "npost_us": "npost",
                     "sky_limit": "sky limit"}
        out += [f"{what} {getattr(self, name):g}{'' if name in ('sky_mode', 'sky_limit') else ' µs'}"
                for name, what in sky_words.items() if getattr(self, name) is not None]
        return ", ".join(out) or "the job's settings"


def with_file_layers(layers, drawings):
    """``layers`` (a job's, given) and the layers the drawings' files set (a G-code file's S
    and F, :attr:`~galvoscan.geometry.drawing.Drawing.layers`), each a :class:`Layer` of
    that speed and power after the given ones, in the order the files first use them. A given
    layer of the same name is the file's with the given settings in place of the file's
    (``--layer "S500 F6000" passes=2``: that layer's speed and power, twice), where the given
    one stands."""
    layers = list(layers)
    by_name = {layer.match.casefold(): k for k, layer in enumerate(layers)}
    files = {}                              # name → the file layer first made of it
    for drawing in drawings:
        for own in drawing.layers:
            made = Layer(own.name, speed_mm_s=own.speed_mm_s, power_percent=own.power_percent)
            name = made.match.casefold()
            if name in files:
                if files[name] != made:
                    raise PlanError(f"{drawing.name}: its layer {own.name!r} is at "
                                    f"{own.power_percent:g} %, another drawing's at "
                                    f"{files[name].power_percent:g} %: give both the same "
                                    f"S maximum")
                continue
            files[name] = made
            k = by_name.get(name)
            if k is None:
                by_name[name] = len(layers)
                layers.append(made)
                continue
            given = layers[k]
            if given.is_colour:
                continue
            changed = {field: getattr(given, field) for field in Layer.__dataclass_fields__
                       if field != "match" and getattr(given, field) is not None}
            layers[k] = replace(made, match=given.match, **changed)
    return layers


def split_by_layer(placed, layers):
    """``placed`` (a placed :class:`~galvoscan.geometry.drawing.Drawing` with styles) as one
    drawing per layer (None where the layer holds none of its paths) and the rest (None: nothing
    left), each path in the first layer that matches it."""
    styles = placed.styles or (None,) * len(placed.paths)
    owner = []
    for style in styles:
        owner.append(next((k for k, layer in enumerate(layers) if layer.matches(style)),
                          len(layers)))
    owner = np.array(owner, dtype=int)
    parts = []
    for k in range(len(layers) + 1):
        chosen = np.flatnonzero(owner == k)
        if not len(chosen):
            parts.append(None)
            continue
        label = layers[k].match if k < len(layers) else "the rest"
        first = not any(part is not None for part in parts)      # notes said once
        parts.append(Drawing(
            name=f"{placed.name} [{label}]", paths=tuple(placed.paths[i] for i in chosen),
            closed=tuple(placed.closed[i] for i in chosen),
            styles=tuple(styles[i] for i in chosen) if placed.styles else (),
            skipped=placed.skipped if first else (), notes=placed.notes if first else ()))
    return parts[:-1], parts[-1]


def styles_found(drawings):
    """``(colours, layer names)`` the drawings' paths hold, sorted, for a message."""
    colours, names = set(), set()
    for drawing in drawings:
        for style in drawing.styles or ():
            if style.colour:
                colours.add(style.colour)
            if style.layer:
                names.add(style.layer)
    return sorted(colours), sorted(names)


#: Preview colours of layers matched by name, and of the rest (black, as with no layers).
_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
            "#17becf", "#bcbd22")


def preview_colour(layer, index):
    """The colour a layer's marks are drawn in: its own, when it is matched by one (white
    drawn as light grey), else one of a palette; the rest (``layer`` None) black."""
    if layer is None:
        return "black"
    colour = layer.match if layer.is_colour else layer.colour_name
    if colour is not None:
        return "#cccccc" if colour == "#ffffff" else colour
    return _PALETTE[index % len(_PALETTE)]


@dataclass
class LayerJob:
    """A layer planned: the :class:`Layer` (None: the rest, at the job's settings), its
    settings (a :class:`~.objects.JobSettings`), its :class:`~.vector_job.VectorJob` and
    its preview colour."""
    layer: Layer
    settings: object
    job: object
    colour: str

    @property
    def label(self):
        return self.layer.match if self.layer is not None else "the rest"


def plan_layers(objects, layers, settings, profile):
    """Plan :class:`~.objects.MarkObject` s in ``layers`` (each path of a drawing in the
    first layer that matches it; an object with a ``layer`` in the layer of that name; the
    rest at ``settings``): one :class:`LayerJob` a layer that holds something, in the
    layers' order, the rest last. A layer that matches nothing is refused (a typo, most
    likely), naming what the drawings hold."""
    if layers:
        # Across every object: the layers' own plans check only the objects each holds.
        check_clear(objects)
    seen = set()
    for layer in layers:
        if layer.match.casefold() in seen:
            raise PlanError(f"layer {layer.match!r} is given twice: give its settings once")
        seen.add(layer.match.casefold())
    by_layer, rest = [[] for _ in layers], []
    for o in objects:
        if o.layer is not None:
            k = next((k for k, layer in enumerate(layers)
                      if not layer.is_colour and layer.match.casefold() == o.layer.casefold()),
                     None)
            if k is None:
                raise PlanError(f"{o.drawing.name} is put on layer {o.layer!r}, which is not "
                                f"one of the job's layers")
            by_layer[k].append(o)
        elif not layers or not o.drawing.styles:
            rest.append(o)
        else:
            parts, left = split_by_layer(place(o.drawing, o.placement), layers)
            here = Placement(origin="page")             # placed already
            for k, part in enumerate(parts):
                if part is not None:
                    by_layer[k].append(replace(o, drawing=part, placement=here))
            if left is not None:
                rest.append(replace(o, drawing=left, placement=here))
    empty = [layer.match for layer, held in zip(layers, by_layer) if not held]
    if empty:
        colours, names = styles_found(o.drawing for o in objects)
        raise PlanError(f"layer {empty[0]!r} matches nothing in the job (its colours: "
                        f"{', '.join(colours) or 'none'}; its layers: "
                        f"{', '.join(repr(n) for n in names) or 'none'})")
    planned = []
    for k, (layer, held) in enumerate([*zip(layers, by_layer), (None, rest)]):
        if not held:
            continue
        if layer is None:
            job = plan_objects(held, settings, profile)
            if layers:
                job = _named(job, held, len(planned) + 1, "the rest")
            planned.append(LayerJob(None, settings, job, preview_colour(None, k)))
            continue
        held = [replace(o, fill=_layer_fill(layer, o)) for o in held]
        layer_settings = layer.settings(settings)
        try:
            job = plan_objects(held, layer_settings, profile)
        except (PlanError, ValueError) as error:
            raise PlanError(f"layer {layer.match!r}: {error}") from None
        job = _named(job, held, len(planned) + 1, layer.match)
        planned.append(LayerJob(layer, layer_settings, job, preview_colour(layer, k)))
    return planned


def _named(job, objects, number, label):
    """``job`` with each note of its own plan (its speed, its stalls, its jumps: what its
    settings make) naming its layer as the plan's lines do (``layer 2 'text': …``,
    :func:`galvoscan.cli.layers.describe_layers`): a job of layers says them all together,
    and a note that a layer stalls must say which. The drawings' own notes (said once, with
    the first part) are left as they are."""
    drawings = {note for o in objects for note in (*o.drawing.notes, *o.drawing.skipped)}
    return replace(job, notes=[note if note in drawings else f"layer {number} {label!r}: {note}"
                               for note in job.notes])


def _layer_fill(layer, o):
    """An object's fill in ``layer``: the layer's settings, but a code's or a photo's own
    fill kept (its modules' lines, its scan lines: a layer's hatch or outline would undo
    it)."""
    fill = layer.settings(o.fill)
    if o.own_fill:
        fill = replace(fill, hatch=o.fill.hatch, hatch_lines=o.fill.hatch_lines,
                       contour=o.fill.contour, outline=o.fill.outline)
    return fill


def merged(layer_jobs):
    """The layers' jobs as one :class:`~.vector_job.VectorJob` for its totals, preview and
    outline (its ``layers`` the :class:`LayerJob` s; its registers and pitch the first
    layer's); one job without layers as it is."""
    if len(layer_jobs) == 1 and layer_jobs[0].layer is None:
        return layer_jobs[0].job
    jobs = [lj.job for lj in layer_jobs]
    total = lambda name: sum(getattr(job, name) for job in jobs)      # noqa: E731
    bounds = np.array([job.bounds_mm for job in jobs])
    notes = list(dict.fromkeys(note for job in jobs for note in job.notes))
    segments = [s for job in jobs for s in job.segments]
    # Each layer's first jump is from where the last one ended, as the preview draws it.
    units_per_mm = jobs[0].pitch.pitch_units / jobs[0].pitch.pitch_mm
    _, jump_mm = jump_mark_lengths(segments, units_per_mm)
    # One pass's jumps likewise: each layer's own, joined where the last ended.
    paths = [p for job in jobs for p in job.paths_mm]
    after = jump_length(paths)
    before = total("jump_before_mm") - total("jump_after_mm") + after
    return VectorJob(segments=segments,
                     paths_mm=paths, jump_before_mm=before, jump_after_mm=after,
                     pitch=jobs[0].pitch, registers=jobs[0].registers,
                     estimate_s=total("estimate_s"), mark_mm=total("mark_mm"),
                     sky_s=total("sky_s"), sky_mode=max(job.sky_mode for job in jobs),
                     jump_mm=jump_mm,
                     bounds_mm=(*bounds[:, :2].min(axis=0).tolist(),
                                *bounds[:, 2:].max(axis=0).tolist()),
                     notes=notes, layers=list(layer_jobs))
