"""A job's segments as the board's queue takes them: the ``(vec_x, vec_y, vec_op)`` words of
each (:func:`segment_words`, and back: :func:`segment_of_words`), what the board would refuse
(:func:`check_segment`), and the jump a job ends on (:func:`job_segments`). The streamer
(:mod:`.stream`) sends these words and a job image (:mod:`.image`) holds them, so the same
drawing gives the same wires streamed or played."""

from ..gateware.fields import pack
from ..gateware.host.regmap import BY_NAME, VectorOp
from ..gateware.sources.vector import PixelVecOpWord, VecOpWord
from ..geometry.segments import JUMP, LINE, MARK, OPS, PIXELS


__all__ = ["check_segment", "segment_words", "segment_of_words", "job_segments"]


def check_segment(op, x, y):
    """Refuse a segment the board would: ``op`` one of :data:`~galvoscan.geometry.segments.OPS`,
    ends within the field (a pixel word's two halves, 16 bits each)."""
    if op not in OPS:
        raise ValueError(f"a segment is a jump, a mark, a pixel line or a pixel word, not "
                         f"{op!r}")
    for value in (x, y):
        reg = BY_NAME["vec_x"]
        if isinstance(value, bool) or not isinstance(value, int) or \
                not reg.low <= value <= reg.high:
            raise ValueError(f"segment end {value!r} is outside {reg.low} … {reg.high}")


def segment_words(op, x, y, corner_frames=0):
    """The ``(vec_x, vec_y, vec_op)`` register values that queue one segment: what the
    streamer writes and a job image holds: a pixel line is a mark, and a pixel word a jump,
    with ``vec_op``'s ``pixels`` bit set."""
    if op in (LINE, PIXELS):
        return x, y, pack(PixelVecOpWord, op=VectorOp.MARK if op == LINE else VectorOp.JUMP,
                          corner_frames=corner_frames if op == LINE else 0, pixels=1)
    return x, y, pack(VecOpWord, op=VectorOp[op.upper()], corner_frames=corner_frames)


def segment_of_words(x, y, op_word):
    """``(op, x, y, corner_frames)``: the segment whose :func:`segment_words` these are."""
    word = PixelVecOpWord.from_bits(op_word)
    if word.op == VectorOp.MARK:
        op = LINE if word.pixels else MARK
    else:
        op = PIXELS if word.pixels else JUMP
    return op, x, y, word.corner_frames


def job_segments(segments):
    """A vector job's segments as the board is sent them: ending on a jump (to where the last
    mark ends: no move), since the board counts a mark that finds the queue empty as an
    underrun, and a job's end is none."""
    segments = list(segments)
    if segments and segments[-1][0] != JUMP:
        # (After a pixel line's words: to where the line ends.)
        end = next(s for s in reversed(segments) if s[0] != PIXELS)
        segments.append((JUMP, *end[1:]))
    return segments
