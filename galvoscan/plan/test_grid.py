"""A material test grid (meerk40t's "material test"): a square for each combination of speed
and power, each filled at its own settings, the rows and columns labelled in a single-line
font; planned as one vector job a square (the board takes one speed and power at a time), the
labels as one more, at the label settings."""

import math
from dataclasses import dataclass, replace

import numpy as np

from ..geometry.drawing import Drawing
from ..geometry.field import Placement, PlanError
from ..geometry.fill import HatchSet
from ..geometry.speed import choose_pitch
from ..inputs.text import TextSpec, text_drawing
from ..settings.laser import PULSES
from .objects import JobSettings, MarkObject
from .vector_job import plan_objects


__all__ = ["GridCell", "TestGrid", "axis_values", "grid_pitches", "plan_test_grid"]


#: Cells a grid holds at most (each is a job of its own).
MAX_CELLS = 400


def axis_values(low, high, count, what):
    """``count`` values from ``low`` to ``high`` evenly (one: ``low``); one line if wrong."""
    if not (math.isfinite(low) and math.isfinite(high)) or count < 1 or count > 100:
        raise PlanError(f"{what}: A:B:N with N from 1 to 100")
    if count == 1:
        return [low]
    return [low + (high - low) * k / (count - 1) for k in range(count)]


@dataclass
class GridCell:
    """One square: its settings, where it is, and its planned job."""
    speed_mm_s: float
    power_percent: float
    centre_mm: tuple
    job: object = None


@dataclass
class TestGrid:
    """A planned grid: its :class:`GridCell` s, the labels' job, the pulses per point every
    square is marked at, notes (a column whose speed is not the one asked) and the columns'
    labels as text (the speeds made, mm/s)."""
    __test__ = False                # not a pytest class, for all its name
    cells: list
    labels: object
    pulses_per_point: int
    notes: list
    column_labels: list


def _label(speed_mm_s):
    """A column's label: the speed made, mm/s, whole."""
    return f"{speed_mm_s:.0f}"


def _pitches_at(speeds, prr_hz, units_per_mm, max_pitch_mm, pulses):
    """Each speed's :class:`~galvoscan.geometry.speed.Pitch` at ``pulses`` per point (the
    nearest pitch); PlanError when one is out of reach at that many."""
    return [choose_pitch(v, prr_hz, units_per_mm, max_pitch_mm=max_pitch_mm,
                         pulses_per_point=pulses, strict="range") for v in speeds]


def grid_pitches(speeds, prr_hz, units_per_mm, *, max_pitch_mm, pulses_per_point=None):
    """Each speed's pitch, all at one number of pulses per point: ``pulses_per_point``, or
    the number that makes the asked speeds best (the smallest worst error, then the smallest
    total, then the fewest pulses). A material test varies one thing at a time: were each
    column to take its own pulses per point, a column would differ from the next in dose a
    point as well as in speed.

    Raises PlanError (one line) for a speed the machine cannot make at all, or not at the
    pulses per point given, or speeds no one number of pulses per point reaches."""
    # The machine's reach first, each speed at any pulses per point: its refusal says the range.
    for v in speeds:
        choose_pitch(v, prr_hz, units_per_mm, max_pitch_mm=max_pitch_mm, strict="range")
    if pulses_per_point is not None:
        return _pitches_at(speeds, prr_hz, units_per_mm, max_pitch_mm, pulses_per_point)
    best, best_score = None, None
    # (choose_pitch refuses too few pulses for the PRR: more points a second than frames.)
    for pulses in range(PULSES.low, PULSES.high + 1):
        try:
            pitches = _pitches_at(speeds, prr_hz, units_per_mm, max_pitch_mm, pulses)
        except PlanError:
            continue
        errors = [abs(p.error) for p in pitches]
        score = (round(max(errors), 12), round(sum(errors), 12))
        if best_score is None or score < best_score:
            best, best_score = pitches, score
    if best is None:
        raise PlanError(f"{min(speeds):g} to {max(speeds):g} mm/s: no one number of pulses "
                        f"per point makes them all at {prr_hz / 1e3:g} kHz (pitch ≤ "
                        f"{max_pitch_mm:g} mm): closer speeds, or two grids")
    return best


def plan_test_grid(speeds, powers, profile, *, prr_khz, cell_mm=5.0, gap_mm=2.0,
                   label_height_mm=1.5, label_speed_mm_s=500.0, label_power_percent=None,
                   hatch_mm=None, passes=1, pulses_per_point=None):
    """A :class:`TestGrid`: a column a speed, a row a power (the highest at the top), the
    grid centred in the field; each square hatched at ``hatch_mm`` (default half the spot)
    and outlined, all at one number of pulses per point (``pulses_per_point``, or the one
    :func:`grid_pitches` finds best); labels under the columns (the speed made, mm/s) and
    left of the rows (%); a note for each column whose speed is more than 2 % from the one
    asked."""
    if len(speeds) * len(powers) > MAX_CELLS:
        raise PlanError(f"{len(speeds)} × {len(powers)} squares: {MAX_CELLS} at most")
    if not (0.5 <= cell_mm <= 100 and 0 <= gap_mm <= 100):
        raise PlanError("a square from 0.5 to 100 mm, a gap from 0 to 100 mm")
    pitch = cell_mm + gap_mm
    width, height = len(speeds) * pitch - gap_mm, len(powers) * pitch - gap_mm
    x0, y0 = -width / 2, -height / 2
    # The squares and their labels (a row of numbers below, a column at the left) in the field.
    reach = max(width / 2 + gap_mm + 4 * label_height_mm,
                height / 2 + gap_mm + 2 * label_height_mm)
    if reach > profile.field.size_mm / 2:
        raise PlanError(f"{len(speeds)} × {len(powers)} squares of {cell_mm:g} mm, {gap_mm:g} mm "
                        f"apart, make a grid {width:g} × {height:g} mm with its labels reaching "
                        f"±{reach:.1f} mm; the field is ±{profile.field.size_mm / 2:g} mm: fewer "
                        f"or smaller squares")
    hatch = HatchSet(hatch_mm or profile.laser.spot_mm / 2)
    half = cell_mm / 2
    square = np.array([(-half, -half), (half, -half), (half, half), (-half, half),
                       (-half, -half)])
    # Each speed as the machine makes it (whole galvo units, one number of pulses a point for
    # every column): the label says the speed marked.
    pitches = grid_pitches(speeds, profile.prr_register(prr_khz) * 100.0, profile.units_per_mm,
                           max_pitch_mm=profile.laser.spot_mm / 2,
                           pulses_per_point=pulses_per_point)
    pulses = pitches[0].pulses_per_point
    each = f"{pulses} pulse{'' if pulses == 1 else 's'} per point"
    notes = [f"column {k} makes {_label(p.speed_mm_s)} mm/s, not the {asked:g} asked "
             f"({p.error:+.1%}) at {each}; its label says {_label(p.speed_mm_s)}"
             for k, (asked, p) in enumerate(zip(speeds, pitches), 1) if abs(p.error) > 0.02]
    speeds = [p.speed_mm_s for p in pitches]
    cells = []
    for row, power in enumerate(sorted(powers)):
        for column, speed in enumerate(speeds):
            centre = (x0 + column * pitch + half, y0 + row * pitch + half)
            drawing = Drawing(name=f"square {speed:g} mm/s {power:g} %", paths=(square,),
                              closed=(True,))
            settings = JobSettings(speed_mm_s=speed, power_percent=power, prr_khz=prr_khz,
                                   passes=passes, hatch=(hatch,), pulses_per_point=pulses)
            placement = Placement(offset_mm=centre)
            job = plan_objects([MarkObject(drawing, placement, settings)], settings, profile)
            cells.append(GridCell(speed, power, centre, job))
    # Labels: a single-line font, marked once at the label settings.
    label_settings = JobSettings(speed_mm_s=label_speed_mm_s,
                                 power_percent=label_power_percent
                                 if label_power_percent is not None
                                 else profile.defaults.power_percent,
                                 prr_khz=prr_khz, passes=1, hatch=())
    labels = []
    for column, speed in enumerate(speeds):
        labels.append((_label(speed), (x0 + column * pitch + half,
                                      y0 - gap_mm - label_height_mm), "centre"))
    for row, power in enumerate(sorted(powers)):
        labels.append((f"{power:g}%", (x0 - gap_mm, y0 + row * pitch + half -
                                       label_height_mm / 2), "right"))
    labels.append(("mm/s", (x0 + width + gap_mm, y0 - gap_mm - label_height_mm), "left"))
    objects = [MarkObject(text_drawing(TextSpec(text, label_height_mm, font="hershey",
                                                align=align)),
                          Placement(origin="page", offset_mm=at), label_settings)
               for text, at, align in labels]
    labels_job = plan_objects(objects, label_settings, profile)
    return TestGrid(cells, replace(labels_job, notes=[]), pulses, notes,
                    [text for text, _, _ in labels[:len(speeds)]])
