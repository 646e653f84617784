"""The analyses the CLI runs: one spiral, uniform against Gaussian sampling, the σ sweep, and
spiral against line-by-line on the paper's two fields.

Every run uses the same rules, so numbers compare:

* the pattern is centred on the field; the spiral's amplitudes span the field;
* the spiral's dwell is the smallest that keeps each axis at or below ``speed_m_s`` (Dai & Tang
  2020: galvo maximum 5 m/s), unless given; the raster runs its lines at that speed;
* the mirror is the galvo model of Wan et al. 2018 (:class:`~.galvo.GalvoModel`), the laser
  Dai & Tang's (50 W, 100 kHz).
"""

from ..gateware.host.regmap import BY_NAME
from ..gateware.points import FIELD_CENTRE
from ..gateware.sources.spiral_table import DEFAULT_SIGMA, SpiralTable
from .dose import Laser, Region
from .galvo import FRAME_PERIOD, GalvoModel
from .patterns import (INTERPOLATIONS, ScanHead, raster_frames, spiral_amplitude,
                       spiral_dwell_for_speed, spiral_frames)
from .scan import analyse


__all__ = ["Setup", "DEFAULT_FIELD_MM", "PAPER_FIELDS_MM", "SWEEP_SIGMAS", "run_spiral",
           "run_raster", "sigma_sweep", "spiral_vs_raster", "FILL_STAGES"]


#: Default field, mm: the paper's uniformity test piece (50 × 20 mm aluminium).
DEFAULT_FIELD_MM = (50.0, 20.0)

#: The paper's two test fields, mm (uniformity on aluminium; time on rusted steel).
PAPER_FIELDS_MM = ((50.0, 20.0), (20.0, 80.0))

#: σ values of the sweep, half-swings.
SWEEP_SIGMAS = (0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.5, 2.0, 3.0, 5.0)

#: Shares of the pattern shown in the fill figure (the paper's figures 5 and 6).
FILL_STAGES = (0.05, 0.20, 0.50, 0.75, 0.85, 1.00)


class Setup:
    """Machine and analysis settings shared by every run.

    Parameters
    ----------
    head : ScanHead
    laser : Laser
    galvo : GalvoModel
    speed_m_s : float
        Per-axis speed the patterns are held to (sets the spiral's dwell and the raster's
        line speed).
    line_spacing_mm : float
        Raster line spacing; default one spot diameter.
    target_dose_j_cm2 : float, optional
        Dose to reach everywhere, for the time-to-dose figures. Default: the raster's one-pass
        dose (power / (speed × spacing)).
    """

    def __init__(self, *, head=None, laser=None, galvo=None, speed_m_s=5.0,
                 line_spacing_mm=None, target_dose_j_cm2=None):
        if not isinstance(speed_m_s, (int, float)) or not 0.01 <= speed_m_s <= 100:
            raise ValueError(f"speed must be from 0.01 to 100 m/s, not {speed_m_s!r}")
        self.head = head or ScanHead()
        self.laser = laser or Laser()
        self.galvo = galvo or GalvoModel.from_step_times()
        self.speed_m_s = float(speed_m_s)
        self.line_spacing_mm = self.laser.spot_mm if line_spacing_mm is None \
            else float(line_spacing_mm)
        if not 0 < self.line_spacing_mm <= 10:
            raise ValueError(f"line spacing must be from 0 to 10 mm, not {line_spacing_mm!r}")
        if target_dose_j_cm2 is None:
            # Energy per area of one raster pass: P / (v × s), in J/cm².
            target_dose_j_cm2 = self.laser.power_w / (
                self.speed_m_s * 1e2 * self.line_spacing_mm * 1e-1)
        self.target_dose_j_cm2 = float(target_dose_j_cm2)

    def region(self, field_mm):
        centre = float(self.head.mm(FIELD_CENTRE))
        return Region((centre, centre), field_mm)


def _check_field(field_mm, head):
    width, height = field_mm
    if not (0 < width <= head.field_mm and 0 < height <= head.field_mm):
        raise ValueError(f"field {width:g} x {height:g} mm must fit the scan head's "
                         f"{head.field_mm:g} mm field")


def run_spiral(setup, *, field_mm=DEFAULT_FIELD_MM, table=None, dwell=None, fraction=1.0,
               interpolation=INTERPOLATIONS[BY_NAME["spiral_interp"].reset]):
    """Analyse the spiral on ``field_mm``; ``fraction`` < 1 runs only the first part of it.
    ``interpolation`` is the ``spiral_interp`` register's setting (default its reset)."""
    _check_field(field_mm, setup.head)
    table = table or SpiralTable()
    amp = (spiral_amplitude(field_mm[0], setup.head), spiral_amplitude(field_mm[1], setup.head))
    if dwell is None:
        dwell = spiral_dwell_for_speed(SpiralTable(points=table.points), amp=amp,
                                       speed_m_s=setup.speed_m_s, head=setup.head)
    frames = spiral_frames(table, dwell=dwell, amp=amp, interpolation=interpolation)
    result = analyse(frames, head=setup.head, laser=setup.laser, galvo=setup.galvo,
                     region=setup.region(field_mm), target_dose_j_cm2=setup.target_dose_j_cm2)
    result.metrics = {"pattern": f"spiral {table.sampling}"
                      + (f" σ={table.sigma:g}" if table.sampling == "gaussian" else "")
                      + (" (σ → ∞)" if table.sampling == "triangle" else ""),
                      "interpolation": interpolation,
                      "field_mm": list(field_mm), "dwell": dwell,
                      "points_per_period": table.points, **result.metrics}
    result.table, result.dwell = table, dwell
    return result


def run_raster(setup, *, field_mm=DEFAULT_FIELD_MM, bidirectional=True, turn_gate=0):
    """Analyse a line-by-line fill of ``field_mm``, lines along X at the setup's speed: the
    sequence of the gateware's raster mode (its register values are in the metrics)."""
    _check_field(field_mm, setup.head)
    head = setup.head
    size = tuple(int(round(float(head.units(s)))) for s in field_mm)
    corner = tuple(FIELD_CENTRE - s // 2 for s in size)
    step = max(1, int(round(float(head.units(setup.speed_m_s * FRAME_PERIOD * 1e3)))))
    spacing = max(1, int(round(float(head.units(setup.line_spacing_mm)))))
    frames = raster_frames(corner=corner, size=size, spacing=spacing, step=step,
                           bidirectional=bidirectional, turn_gate=turn_gate)
    result = analyse(frames, head=head, laser=setup.laser, galvo=setup.galvo,
                     region=setup.region(field_mm), periodic=False,
                     target_dose_j_cm2=setup.target_dose_j_cm2)
    # The gateware's raster mode draws exactly these frames from these register values
    # (tests/gateware/sources/test_vector.py checks the wires against raster_frames).
    registers = {"mode": 1, "ras_x": corner[0], "ras_y": corner[1], "ras_w": size[0],
                 "ras_h": size[1], "ras_spacing": spacing, "ras_step": step, "ras_flags": 0,
                 "ras_turn_gate": 0}
    result.metrics = {"pattern": "raster", "field_mm": list(field_mm),
                      "line_spacing_mm": setup.line_spacing_mm, "registers": registers,
                      **result.metrics}
    return result


def sigma_sweep(setup, *, field_mm=DEFAULT_FIELD_MM, sigmas=SWEEP_SIGMAS, progress=None,
                interpolation=INTERPOLATIONS[BY_NAME["spiral_interp"].reset]):
    """Uniform sampling, Gaussian sampling at each σ and the triangle wave (σ → ∞), all at one
    dwell (that of the default table), so they take the same time and differ only in where the
    points sit."""
    results = []
    reference = run_spiral(setup, field_mm=field_mm, interpolation=interpolation)
    dwell = reference.dwell
    for table in [SpiralTable(sampling="uniform")] + [SpiralTable(sigma=s) for s in sigmas] + \
            [SpiralTable(sampling="triangle")]:
        if table.sampling == "gaussian" and table.sigma == DEFAULT_SIGMA:
            result = reference
        else:
            result = run_spiral(setup, field_mm=field_mm, table=table, dwell=dwell,
                                interpolation=interpolation)
        results.append(result)
        if progress:
            progress(1)
    return results


def spiral_vs_raster(setup, *, fields_mm=PAPER_FIELDS_MM, progress=None,
                     interpolation=INTERPOLATIONS[BY_NAME["spiral_interp"].reset]):
    """Spiral (default table) and raster on each field: a list of (spiral, raster) pairs."""
    pairs = []
    for field in fields_mm:
        spiral = run_spiral(setup, field_mm=field, interpolation=interpolation)
        if progress:
            progress(1)
        raster = run_raster(setup, field_mm=field)
        if progress:
            progress(1)
        pairs.append((spiral, raster))
    return pairs


def fill_points(result, stage, head):
    """Mirror positions (mm) over the first ``stage`` share of the pattern, for the fill figure."""
    path = result.path
    start = int(round(result.warmup_s / path.dt))
    stop = start + int(round(stage * result.frames.duration / path.dt))
    step = max(1, int(round(FRAME_PERIOD / path.dt)))
    return head.mm(path.x[start:stop:step]), head.mm(path.y[start:stop:step])
