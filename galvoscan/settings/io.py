"""I/O in a job's queue, each setting declared once: the input a part waits for (a part sensor),
the level it waits for and how long, and the output set for a PLC once the part is marked, with
its pulse.

``mark``'s ``--wait-input``, ``--wait-level``, ``--wait-timeout``, ``--set-output`` and
``--output-pulse`` are made from these (:mod:`galvoscan.cli.job_options`), and a job file's
``[job]`` keys are read with them. The board does them in its queue (RTC5/6's list I/O): a
bitstream with I/O in the queue (the ULX3S's) has two inputs and two outputs
(:data:`INPUTS`, :data:`OUTPUTS`; the README's pin table says where they are).
"""

from .schema import Setting


__all__ = ["INPUTS", "OUTPUTS", "LEVELS", "WAIT_INPUT", "WAIT_LEVEL", "WAIT_TIMEOUT",
           "SET_OUTPUT", "OUTPUT_PULSE", "SENSOR_DISTANCE", "IO_SETTINGS", "DEFAULT_WAIT_TIMEOUT_S",
           "DEFAULT_OUTPUT_PULSE_MS"]


#: The inputs a job may wait for, by name → the board's input (``io_in``): the part sensor
#: on input 0, and a second input.
INPUTS = {"part": 0, "in1": 1}
#: The outputs a job may set, by name → the board's output (``io_out``): the "part done"
#: signal to a PLC on output 0, and a second output.
OUTPUTS = {"done": 0, "out1": 1}
#: The levels a wait may wait for → the input's logic level.
LEVELS = {"high": 1, "low": 0}
#: A wait's time-out when none is given, s: a belt that brings no part within a minute has
#: stopped, and the job stops with it (the laser off) rather than waiting armed for good.
DEFAULT_WAIT_TIMEOUT_S = 60.0
#: An output's pulse when none is given, ms: long enough for a PLC's input filter (a few ms).
DEFAULT_OUTPUT_PULSE_MS = 10.0

WAIT_INPUT = Setting(
    "wait_input", "choice", what="wait input", flag="--wait-input", key="wait_input",
    choices=tuple(INPUTS),
    help="before each part, wait in the board's queue for this input to come to --wait-level "
         "(part: the part sensor, input 0; in1: input 1), the laser armed and the mirrors "
         "still; a part already at the sensor as the wait starts is not taken twice; needs a "
         "bitstream with I/O in the queue (the ULX3S's)")
WAIT_LEVEL = Setting(
    "wait_level", "choice", what="wait level", flag="--wait-level", key="wait_level",
    choices=tuple(LEVELS), default_said="high",
    help="the level --wait-input waits for: high (the default: a sensor that closes on a "
         "part, the input pulled down while it is open) or low")
WAIT_TIMEOUT = Setting(
    "wait_timeout_s", "number", "s", 0, 65.535, what="wait timeout", flag="--wait-timeout",
    key="wait_timeout", metavar="S", default_said=f"{DEFAULT_WAIT_TIMEOUT_S:g} s",
    help="how long --wait-input waits for a part; then the board stops the job, the laser "
         "off (0: for ever)")
SET_OUTPUT = Setting(
    "set_output", "choice", what="set output", flag="--set-output", key="set_output",
    choices=tuple(OUTPUTS),
    help="once each part is marked (the laser off), set this output high for "
         "--output-pulse (done: output 0, a PLC's part-done input; out1: output 1); needs a "
         "bitstream with I/O in the queue (the ULX3S's)")
OUTPUT_PULSE = Setting(
    "output_pulse_ms", "number", "ms", 0, 655.35, what="output pulse",
    flag="--output-pulse", key="output_pulse", metavar="MS",
    default_said=f"{DEFAULT_OUTPUT_PULSE_MS:g} ms",
    help="how long --set-output stays high, in 10 µs steps (0: until the next part's wait "
         "starts)")

SENSOR_DISTANCE = Setting(
    "sensor_distance_mm", "number", "mm", 0, 10_000, what="sensor distance",
    flag="--sensor-distance", key="sensor_distance", metavar="MM",
    help="on the fly, with --wait-input: how far the part sensor sits before the drawing's "
         "place along the belt; once it sees a part the board's queue waits for the "
         "encoder to count that far (RTC's wait_for_encoder) before the part is marked "
         "(default 0: the sensor is at the drawing)")

#: Every I/O setting, in ``--help``'s order.
IO_SETTINGS = (WAIT_INPUT, WAIT_LEVEL, WAIT_TIMEOUT, SET_OUTPUT, OUTPUT_PULSE, SENSOR_DISTANCE)
