"""What a job's segments are: ``(op, x, y)`` in galvo units, the board's queued commands.

* ``"jump"``: move to ``(x, y)`` with the laser off, then the jump delay;
* ``"mark"``: step the line to ``(x, y)`` at the pitch, every point lit;
* ``"line"``: a **pixel line** to ``(x, y)``: stepped as a mark, at one speed, each point
  lit only if its bit is 1 (bitstreams with pixel lines);
* ``"pixels"``: a **pixel word**, 32 of those bits (``x`` pixels 0-15, ``y`` 16-31, bit 0
  first), queued after its line in order; it moves nothing;
* ``"io"``: an **I/O step** (:class:`IOStep`), done once every segment before it is marked
  (bitstreams with I/O in the queue): wait for an input (a part sensor) or an encoder's count,
  set an output (for a PLC), start or end the fly. It moves nothing; ``x`` and ``y`` are its
  arguments. A job's planned segments hold none: :func:`galvoscan.api.stream_layers` puts a
  part's around its layers as they are sent.

A line of ``n`` points after a jump takes ``n`` bits: its start point first, then each
point the pitch steps (a line of length ``(n - 1) × pitch``).
"""

from ..gateware.fields import IOKind


__all__ = ["JUMP", "MARK", "LINE", "PIXELS", "IO", "OPS", "STEPPED", "PIXELS_PER_WORD",
           "IOStep", "pixel_words", "has_pixel_lines", "io_steps"]


JUMP, MARK, LINE, PIXELS, IO = "jump", "mark", "line", "pixels", "io"
#: Every op a segment may have.
OPS = (JUMP, MARK, LINE, PIXELS, IO)
#: The ops stepped at the pitch, a point each pitch (lit, or by their bits).
STEPPED = (MARK, LINE)
#: Pixels one pixel word carries.
PIXELS_PER_WORD = 32


def pixel_words(bits):
    """The ``("pixels", x, y)`` words that carry ``bits`` (0/1, a point each, in the order
    the line's points come), the last one padded with dark pixels."""
    words = []
    for start in range(0, len(bits), PIXELS_PER_WORD):
        value = 0
        for k, bit in enumerate(bits[start:start + PIXELS_PER_WORD]):
            value |= (1 if bit else 0) << k
        words.append((PIXELS, value & 0xFFFF, value >> 16))
    return words


def has_pixel_lines(segments):
    """Whether ``segments`` hold a pixel line (and so need a bitstream with them)."""
    return any(op == LINE for op, *_ in segments)


class IOStep(tuple):
    """An I/O step, ``("io", arg_x, arg_y)`` as a segment is (so that it goes where segments
    go: the streamer, a job image), with what it does: ``kind`` (an
    :class:`~galvoscan.gateware.fields.IOKind`), ``index`` (the input, output or encoder: 0
    or 1), ``level`` (0 or 1) and ``edge`` (a wait for the input to come to ``level``, not
    only to be at it). ``arg_x`` and ``arg_y`` are the board's ``vec_x`` and ``vec_y``: a
    wait's time-out in ms (0: none), an output's pulse in 10 µs frames (0: held until
    changed), a count wait's signed 32-bit count (``arg_y`` its high half)."""

    def __new__(cls, kind, *, index=0, level=1, edge=False, arg_x=0, arg_y=0):
        kind = IOKind(kind)
        for name, value in (("index", index), ("level", level)):
            if value not in (0, 1):
                raise ValueError(f"an I/O step's {name} is 0 or 1, not {value!r}")
        for name, value in (("arg_x", arg_x), ("arg_y", arg_y)):
            if isinstance(value, bool) or not isinstance(value, int) or \
                    not 0 <= value <= 0xFFFF:
                raise ValueError(f"an I/O step's {name} is 0 … 65535, not {value!r}")
        step = super().__new__(cls, (IO, arg_x, arg_y))
        step.kind, step.index, step.level, step.edge = kind, index, level, bool(edge)
        return step

    def __getnewargs_ex__(self):
        return (self.kind,), dict(index=self.index, level=self.level, edge=self.edge,
                                  arg_x=self[1], arg_y=self[2])

    def __eq__(self, other):
        return isinstance(other, IOStep) and tuple(self) == tuple(other) and \
            (self.kind, self.index, self.level, self.edge) == \
            (other.kind, other.index, other.level, other.edge)

    def __hash__(self):
        return hash((tuple(self), self.kind, self.index, self.level, self.edge))

    def __repr__(self):
        return (f"IOStep({self.kind.name}, index={self.index}, level={self.level}"
                f"{', edge=True' if self.edge else ''}, arg_x={self[1]}, arg_y={self[2]})")


def io_steps(segments):
    """The I/O steps among ``segments``."""
    return [segment for segment in segments if segment[0] == IO]
