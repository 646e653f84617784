"""The numbers the gateware and the host share: queue depth, frame time, the ranges of the
register map's limits. Declared once here; the register map (:mod:`.host.regmap`), the cores
and the host take them from this module, which imports nothing, so the command line can read
them without loading Amaranth."""

__all__ = ["WORD_MAX", "VECTOR_QUEUE_DEPTH", "FRAME_US", "DEFAULT_CLOCK_HZ",
           "LASER_ON_LEAD_US", "LASER_DELAY_MAX_US", "SCANNER_DELAY_MAX_US",
           "CORNER_FRAMES_MAX", "DEFAULT_TABLE_POINTS", "MIN_POINTS", "MAX_POINTS", "DEFAULT_CORRECTION_NODES",
           "WOBBLE_MAX_AMPLITUDE", "WOBBLE_MAX_HZ"]


#: Largest value a frame's data field carries.
WORD_MAX = 0xFFFF
#: Segments the vector queue holds (block RAM); a build may have a shorter one, and the host
#: reads a board's own off ``fifo_free`` while the queue is empty.
VECTOR_QUEUE_DEPTH = 512
#: An XY2-100 frame, in µs: 20 bits at 2 Mbit/s. The unit of ``dwell``, ``ras_turn_gate``
#: and the corner holds, and the time a vector point's frame takes.
FRAME_US = 10
#: The iCEBreaker's and the iCEstick's crystal, the default system clock, Hz.
DEFAULT_CLOCK_HZ = 12_000_000
#: The vector sequencer decides a frame's laser two 10 µs frames before that frame's point
#: reaches the head: how far ahead a negative ``laser_on_delay`` can reach, plus one µs.
LASER_ON_LEAD_US = 20
#: Largest laser-on and laser-off delays, in µs.
LASER_DELAY_MAX_US = 1023
#: Largest mark and polygon delays, in µs.
SCANNER_DELAY_MAX_US = 4095
#: Largest scaled corner hold a mark carries (``vec_op`` bits 7:1), in frames.
CORNER_FRAMES_MAX = 127
#: Samples per axis of the default spiral table (the paper's 128).
DEFAULT_TABLE_POINTS = 128
#: Samples per sine period of a spiral table, a multiple of 4 (the quarter-period symmetry)
#: within these bounds (the ROM address registers are 12 bits at most).
MIN_POINTS = 8
MAX_POINTS = 4096
#: Nodes per axis of the default (identity) correction table.
DEFAULT_CORRECTION_NODES = 17
#: Largest wobble amplitude, galvo units (≈ 6.9 mm on a 110 mm field): the figure's products
#: stay within 12 bits.
WOBBLE_MAX_AMPLITUDE = 4095
#: Highest wobble frequency, Hz: a quarter of the XY2-100 frame rate, so a turn of the figure
#: has at least four points.
WOBBLE_MAX_HZ = 25_000
