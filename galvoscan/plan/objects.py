"""The objects of a job: a job's settings in user units (:class:`JobSettings`), one object to
mark with its placement and fill (:class:`MarkObject`), and the objects a code
(:func:`code_object`) and a photo (:func:`photo_object`) make."""

from dataclasses import dataclass, replace
import math

from ..geometry.field import Placement, PlanError
from ..geometry.fill import Contour, HatchSet, LineOrder
from ..inputs.codes import CodeFill, CodeKind, code_drawing, data_said
from ..inputs.photo import photo_drawing
from .pixel_lines import PixelRaster


__all__ = ["JobSettings", "MarkObject", "code_object", "photo_object", "DOT_OVERLAP"]


@dataclass(frozen=True)
class JobSettings:
    """A job's parameters in user units (mm/s, %, kHz), as the command line gives them."""
    speed_mm_s: float
    power_percent: float
    prr_khz: float
    passes: int = 1
    hatch: tuple = ()               # HatchSets (.fill), each filling the closed shapes
    hatch_lines: LineOrder = LineOrder.SERPENTINE
    contour: Contour = None         # rings inward from the shapes' edges, None: none
    outline: bool = True
    pulses_per_point: int = None    # None: chosen with the pitch for the speed
    delays_us: tuple = ()           # (register, µs) pairs in place of the profile's delays
    sky: object = None              # SkyWriting (a plan.sky.Sky), None: off


@dataclass(frozen=True, eq=False)
class MarkObject:
    """One object of a job: a drawing, where it goes, and how it is filled (``fill``'s hatch,
    hatch_lines, contour and outline; the job's speed, power and passes are the job's), with
    ``keep_clear_mm`` around its bounds that no other object may reach into (a code's quiet
    zone); ``keep_order``: its paths marked in the drawing's own order (a photo's scan lines),
    not re-ordered to cut jumps."""
    drawing: object
    placement: object
    fill: JobSettings
    keep_clear_mm: float = 0.0
    keep_order: bool = False
    layer: str = None               # the layer (by name) it takes its settings from
    own_fill: bool = False          # its fill is its own (a code's, a photo's): no layer's
    #: A photo marked as pixel lines (:class:`~.pixel_lines.PixelRaster`), its drawing's runs
    #: then only what the preview and the checks see; None: the drawing's paths are marked.
    pixels: object = None


#: How much narrower than the spot a dotted code's module may be (its dot 4/3 of it).
DOT_OVERLAP = 0.75


def code_object(spec, settings, *, centre_mm=(0.0, 0.0), spot_mm):
    """The code as a :class:`~.objects.MarkObject` of a job at ``settings``: centred on
    ``centre_mm`` (field mm), filled along its rows at the widest spacing that divides a
    module evenly and is at most half the spot (or as dots), its quiet zone kept clear."""
    drawing, module = code_drawing(spec)
    # A module narrower than the spot cannot be marked apart from its neighbours (a dot may
    # reach a little past its module: readers take dots that touch).
    smallest = spot_mm * (DOT_OVERLAP if spec.fill is CodeFill.DOTS else 1.0)
    if module < smallest:
        raise PlanError(f"{spec.kind.value} code {data_said(spec.data)}: modules of "
                        f"{module * 1000:.0f} µm, less than the {spot_mm * 1000:.0f} µm spot"
                        f"{' (a dot may be 4/3 of its module)' if spec.fill is CodeFill.DOTS else ''}"
                        f": a larger --size, or less data")
    if spec.fill is CodeFill.DOTS:
        fill = replace(settings, hatch=(), contour=None, outline=True)
    else:
        lines = max(1, math.ceil(module / (spot_mm / 2) - 1e-9))
        # Along the rows; a Code 128's bars along their length (a few long lines a bar, not
        # a short one across it every spacing of its height).
        angle = 90.0 if spec.kind is CodeKind.CODE128 else 0.0
        fill = replace(settings, hatch=(HatchSet(module / lines, angle),), contour=None,
                       outline=True)
    return MarkObject(drawing, Placement(offset_mm=tuple(centre_mm)), fill,
                      keep_clear_mm=spec.quiet * module, own_fill=True)


def photo_object(spec, settings, *, centre_mm=(0.0, 0.0), pixel_units=None):
    """The photo as a :class:`~.objects.MarkObject` at ``settings``' speed and power,
    centred on ``centre_mm`` (field mm), its lines in scan order; ``pixel_units``: marked as
    pixel lines, its cells (``spec.line_spacing_mm``) that many galvo units."""
    drawing, dark = photo_drawing(spec)
    raster = None if pixel_units is None else \
        PixelRaster(dark, pixel_units, bidirectional=spec.bidirectional)
    fill = replace(settings, hatch=(), contour=None, outline=True)
    # Centred by the grid, not by the marks (which need not reach its edges).
    rows, columns = dark.shape
    corner = (centre_mm[0] - columns * spec.line_spacing_mm / 2,
              centre_mm[1] - rows * spec.line_spacing_mm / 2)
    return MarkObject(drawing, Placement(origin="page", offset_mm=corner), fill,
                      keep_order=True, own_fill=True, pixels=raster)
