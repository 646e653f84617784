"""A part's I/O on a production line: the wait for the part sensor before it is marked, and
the output that tells a PLC it is done, as the I/O steps the board's queue does around the
part's segments (:class:`~galvoscan.geometry.segments.IOStep`; SCANLAB RTC5/6's list I/O).

Before a part: a jump to where the part's first segment starts (a wait needs it first: the
board does an I/O word as soon as the sequencer is idle, running or not, and a jump is taken
only once the board runs, so the wait starts with the laser led in and the queue filled
behind it, not while the host is still arming), the held "done" output of the last part set
low (an output held, not pulsed), then the wait for the input to come to its level (an edge, so a part still at the sensor is
not marked twice), then, on the fly, the fly's start (the count zeroed as the part arrives:
the part is where the drawing is). A sensor some distance before the drawing's place: the
count zeroed at the sensor (the fly started and ended at once), a wait for the encoder to
count that distance (RTC's ``wait_for_encoder``), and then the fly's start. After the part:
the fly's end, then the output set.
"""

import math
from dataclasses import dataclass

from ..gateware.fields import IOKind
from ..gateware.limits import FRAME_US
from ..geometry.field import PlanError
from ..geometry.segments import JUMP, IOStep
from ..settings.io import (DEFAULT_OUTPUT_PULSE_MS, DEFAULT_WAIT_TIMEOUT_S, INPUTS, LEVELS,
                           OUTPUT_PULSE, OUTPUTS, SENSOR_DISTANCE, SET_OUTPUT, WAIT_INPUT,
                           WAIT_LEVEL, WAIT_TIMEOUT)


__all__ = ["PartIO", "part_io", "part_steps", "first_point"]



@dataclass(frozen=True)
class PartIO:
    """What each part waits for and sets: ``wait_input`` (a name of
    :data:`~galvoscan.settings.io.INPUTS`, None: no wait), its ``wait_level`` (``high`` or
    ``low``) and ``wait_timeout_s`` (0: none), ``set_output`` (a name of
    :data:`~galvoscan.settings.io.OUTPUTS`, None: none) and its ``output_pulse_ms`` (0: held
    until the next part's wait starts); ``sensor_distance_mm``: on the fly, how far the
    sensor sits before the drawing's place along the belt (0: at it)."""
    wait_input: str = None
    wait_level: str = "high"
    wait_timeout_s: float = DEFAULT_WAIT_TIMEOUT_S
    set_output: str = None
    output_pulse_ms: float = DEFAULT_OUTPUT_PULSE_MS
    sensor_distance_mm: float = 0.0

    def __post_init__(self):
        for setting in (WAIT_INPUT, WAIT_LEVEL, WAIT_TIMEOUT, SET_OUTPUT, OUTPUT_PULSE,
                        SENSOR_DISTANCE):
            value = getattr(self, setting.name)
            if value is not None:
                setting.check(value)
        if self.wait_input is None and self.set_output is None:
            raise PlanError("a part's I/O waits for an input or sets an output (or both)")
        if self.sensor_distance_mm and self.wait_input is None:
            raise PlanError(f"{SENSOR_DISTANCE.flag} is a wait's: give --wait-input too")

    @property
    def timeout_ms(self):
        """The wait's time-out as the board counts it, ms (0: none)."""
        return round(self.wait_timeout_s * 1000)

    @property
    def pulse_frames(self):
        """The output's pulse as the board counts it, 10 µs frames (0: held)."""
        return round(self.output_pulse_ms * 1000 / FRAME_US)

    @property
    def wait_s(self):
        """The longest a part's wait may add to its job, s (inf: no time-out)."""
        if self.wait_input is None:
            return 0.0
        return self.wait_timeout_s if self.timeout_ms else math.inf

    def sensor_counts(self, fly):
        """The encoder's counts from the sensor to the drawing's place (``fly``: the part's
        :class:`~galvoscan.plan.fly.FlyPlan`, its counts a mm), as the board's count wait
        takes them: a :class:`~galvoscan.geometry.field.PlanError` past its 31 bits."""
        counts = round(self.sensor_distance_mm * fly.counts_per_mm)
        if counts >= 1 << 31:
            raise PlanError(f"{SENSOR_DISTANCE.flag} {self.sensor_distance_mm:g} mm is "
                            f"{counts:,} counts of the encoder: the board counts to "
                            f"{(1 << 31) - 1:,}")
        return counts

    def before(self, *, fly=None, at=None):
        """The I/O steps before a part's first segment; ``fly``: the part is marked on the
        fly (its :class:`~galvoscan.plan.fly.FlyPlan`; True will do without a sensor
        distance), its count zeroed and the fly started as it reaches the sensor, or as it
        reaches the drawing's place, the sensor distance on; ``at``: where the part's first
        segment starts (galvo units), jumped to first when it waits."""
        steps = []
        if self.wait_input is not None and at is not None:
            steps.append((JUMP, *at))
        if self.set_output is not None and not self.pulse_frames:
            steps.append(IOStep(IOKind.SET_OUTPUT, index=OUTPUTS[self.set_output], level=0))
        if self.wait_input is not None:
            steps.append(IOStep(IOKind.WAIT_INPUT, index=INPUTS[self.wait_input],
                                level=LEVELS[self.wait_level], edge=True,
                                arg_x=self.timeout_ms))
            if self.sensor_distance_mm:
                if not hasattr(fly, "counts_per_mm"):
                    raise PlanError(f"{SENSOR_DISTANCE.flag} is on the fly: give --fly too "
                                    f"(the encoder counts the belt's travel)")
                counts = self.sensor_counts(fly)
                # The count zeroed at the sensor (the fly on and off at once), then a wait
                # for the belt to bring the part the distance on.
                steps += [IOStep(IOKind.FLY_START), IOStep(IOKind.FLY_END),
                          IOStep(IOKind.WAIT_COUNT_UP, arg_x=counts & 0xFFFF,
                                 arg_y=counts >> 16)]
            if fly:
                steps.append(IOStep(IOKind.FLY_START))
        return steps

    def after(self, *, fly=False):
        """The I/O steps after a part's last segment."""
        steps = []
        if fly and self.wait_input is not None:
            steps.append(IOStep(IOKind.FLY_END))
        if self.set_output is not None:
            steps.append(IOStep(IOKind.SET_OUTPUT, index=OUTPUTS[self.set_output], level=1,
                                arg_x=self.pulse_frames))
        return steps

    def line(self):
        """One line saying what each part waits for and sets."""
        said = []
        if self.wait_input is not None:
            said.append(f"each part waits for input {self.wait_input} (input "
                        f"{INPUTS[self.wait_input]}) to go {self.wait_level}, "
                        + (f"{self.wait_timeout_s:g} s at most (then the job stops, the laser "
                           f"off)" if self.timeout_ms else "for as long as it takes"))
        if self.set_output is not None:
            said.append(f"sets output {self.set_output} (output {OUTPUTS[self.set_output]}) "
                        + (f"for {self.output_pulse_ms:g} ms" if self.pulse_frames else
                           "until the next part's wait") + " once it is marked")
        if self.sensor_distance_mm:
            said.append(f"the sensor {self.sensor_distance_mm:g} mm before the drawing's "
                        f"place: each part marked once the encoder has counted that far")
        return "I/O: " + "; ".join(said)


def part_io(wait_input=None, wait_level=None, wait_timeout_s=None, set_output=None,
            output_pulse_ms=None, sensor_distance_mm=None):
    """The :class:`PartIO` of these settings (None: the defaults), or None when there is
    none; a :class:`~galvoscan.geometry.field.PlanError` for a setting of a wait without the
    wait (or of an output without it)."""
    if wait_input is None:
        given = [s.flag for s, v in ((WAIT_LEVEL, wait_level), (WAIT_TIMEOUT, wait_timeout_s),
                                     (SENSOR_DISTANCE, sensor_distance_mm))
                 if v is not None]
        if given:
            raise PlanError(f"{given[0]} is a wait's: give --wait-input too")
    if set_output is None and output_pulse_ms is not None:
        raise PlanError(f"{OUTPUT_PULSE.flag} is an output's: give --set-output too")
    if wait_input is None and set_output is None:
        return None
    return PartIO(wait_input=wait_input, wait_level=wait_level or "high",
                  wait_timeout_s=DEFAULT_WAIT_TIMEOUT_S if wait_timeout_s is None
                  else wait_timeout_s,
                  set_output=set_output,
                  output_pulse_ms=DEFAULT_OUTPUT_PULSE_MS if output_pulse_ms is None
                  else output_pulse_ms,
                  sensor_distance_mm=sensor_distance_mm or 0.0)


def part_steps(io, *, fly=None, queued_fly=False, at=None):
    """``(before, after)``: the I/O steps around a part (``io`` a :class:`PartIO` or None);
    ``fly``: marked on the fly (its :class:`~galvoscan.plan.fly.FlyPlan`); ``queued_fly``: the queue starts and ends the fly even without
    a wait (a job image: the stand-alone player has no host to turn it on); ``at``: where the
    part's first segment starts."""
    before = io.before(fly=fly, at=at) if io is not None else []
    after = io.after(fly=fly) if io is not None else []
    if fly and queued_fly and not any(step.kind == IOKind.FLY_START for step in before):
        before.append(IOStep(IOKind.FLY_START))
        after.insert(0, IOStep(IOKind.FLY_END))
    return before, after


def first_point(segments):
    """Where ``segments`` start: their first jump's end (None: they start with no jump)."""
    for op, x, y in segments:
        if op == JUMP:
            return (x, y)
        return None
    return None
