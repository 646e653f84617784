"""What a job's segments are: ``(op, x, y)`` in galvo units, the board's queued commands.

* ``"jump"``: move to ``(x, y)`` with the laser off, then the jump delay;
* ``"mark"``: step the line to ``(x, y)`` at the pitch, every point lit;
* ``"line"``: a **pixel line** to ``(x, y)``: stepped as a mark, at one speed, each point
  lit only if its bit is 1 (bitstreams with pixel lines);
* ``"pixels"``: a **pixel word**, 32 of those bits (``x`` pixels 0-15, ``y`` 16-31, bit 0
  first), queued after its line in order; it moves nothing.

A line of ``n`` points after a jump takes ``n`` bits: its start point first, then each
point the pitch steps (a line of length ``(n - 1) × pitch``).
"""

__all__ = ["JUMP", "MARK", "LINE", "PIXELS", "OPS", "STEPPED", "PIXELS_PER_WORD",
           "pixel_words", "has_pixel_lines"]


JUMP, MARK, LINE, PIXELS = "jump", "mark", "line", "pixels"
#: Every op a segment may have.
OPS = (JUMP, MARK, LINE, PIXELS)
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
