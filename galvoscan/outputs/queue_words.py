"""A job's segments as the board's queue takes them: the ``(vec_x, vec_y, vec_op)`` words of
each (:func:`queue_word`, and back: :func:`segment_of_words`), what the board would refuse
(:func:`check_segment`), and the jump a job ends on (:func:`job_segments`). The streamer
(:mod:`.stream`) sends these words and a job image (:mod:`.image`) holds them, so the same
drawing gives the same wires streamed or played."""

from ..gateware.fields import IOKind, pack
from ..gateware.host.regmap import BY_NAME, VectorOp
from ..gateware.sources.vector import IOVecOpWord, IOWord, PixelVecOpWord, VecOpWord
from ..geometry.segments import IO, IOStep, JUMP, LINE, MARK, OPS, PIXELS


__all__ = ["check_segment", "queue_word", "segment_of_words", "job_segments"]


def check_segment(op, x, y):
    """Refuse a segment the board would: ``op`` one of :data:`~galvoscan.geometry.segments.OPS`,
    ends within the field (a pixel word's two halves, 16 bits each)."""
    if op not in OPS:
        raise ValueError(f"a segment is a jump, a mark, a pixel line, a pixel word or an I/O "
                         f"step, not {op!r}")
    for value in (x, y):
        reg = BY_NAME["vec_x"]
        if isinstance(value, bool) or not isinstance(value, int) or \
                not reg.low <= value <= reg.high:
            raise ValueError(f"segment end {value!r} is outside {reg.low} … {reg.high}")


def queue_word(segment, corner_frames=0):
    """The ``(vec_x, vec_y, vec_op)`` register values that queue one segment (an ``(op, x,
    y)`` tuple, or an :class:`~galvoscan.geometry.segments.IOStep`): what the streamer writes
    and a job image holds. A pixel line is a mark, and a pixel word a jump, with ``vec_op``'s
    ``pixels`` bit set; an I/O step has its ``io`` bit set and what it does in bits 8:0."""
    op, x, y = segment
    if op == IO:
        if not isinstance(segment, IOStep):
            raise ValueError("an I/O step's words need the IOStep (what it does)")
        return x, y, pack(IOVecOpWord, io=1) | pack(
            IOWord, kind=segment.kind, index=segment.index, level=segment.level,
            edge=int(segment.edge))
    if op in (LINE, PIXELS):
        return x, y, pack(PixelVecOpWord, op=VectorOp.MARK if op == LINE else VectorOp.JUMP,
                          corner_frames=corner_frames if op == LINE else 0, pixels=1)
    return x, y, pack(VecOpWord, op=VectorOp[op.upper()], corner_frames=corner_frames)


def segment_of_words(x, y, op_word):
    """``(op, x, y, corner_frames)``: the segment whose :func:`queue_word` these are (an
    I/O word's ``op`` is its :class:`~galvoscan.geometry.segments.IOStep`, ``corner_frames``
    0)."""
    if IOVecOpWord.from_bits(op_word).io:
        word = IOWord.from_bits(op_word & 0x1FF)
        return IOStep(IOKind(word.kind), index=word.index, level=word.level,
                      edge=bool(word.edge), arg_x=x, arg_y=y), x, y, 0
    word = PixelVecOpWord.from_bits(op_word)
    if word.op == VectorOp.MARK:
        op = LINE if word.pixels else MARK
    else:
        op = PIXELS if word.pixels else JUMP
    return op, x, y, word.corner_frames


def job_segments(segments):
    """A vector job's segments as the board is sent them: ending on a jump (to where the last
    mark ends: no move), since the board counts a mark that finds the queue empty as an
    underrun, and a job's end is none; and a jump of the same kind before each I/O step that
    follows a mark or a pixel line (the step waits for the sequencer to be idle, and a line
    must not wait for its pixel words: the board's laser-off delay runs before the step)."""
    out = []
    at = None           # the last segment that moved the head: a jump, a mark or a line
    for segment in segments:
        if segment[0] == IO and at is not None and at[0] != JUMP:
            out.append((JUMP, *at[1:3]))
            at = out[-1]
        out.append(segment)
        if segment[0] in (JUMP, MARK, LINE):
            at = segment
    if at is not None and at[0] != JUMP:
        # (After a pixel line's words, or I/O steps: to where the line ends.)
        out.append((JUMP, *at[1:3]))
    return out
