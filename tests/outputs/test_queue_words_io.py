"""I/O steps as the queue's words (galvoscan/outputs/queue_words.py): ``vec_op`` as the
registers page gives it (bit 9 io; bits 2:0 what it does, bit 3 which input, output or
encoder, bit 4 the level, bit 5 an edge; ``vec_x`` and ``vec_y`` its arguments), written out
here from that page and not from the layout, read back the same; the jump a job puts before a
step that follows a mark or a pixel line; and an image that holds them."""

import pytest
from hypothesis import given, strategies as st

from galvoscan.gateware.fields import IOKind
from galvoscan.geometry.segments import IOStep
from galvoscan.outputs.image import ImageError, job_image, read_image
from galvoscan.outputs.queue_words import (check_segment, job_segments, queue_word,
                                           segment_of_words)
from galvoscan.build import preset_register_map
from galvoscan.platforms.ulx3s import ULX3SScanner


def documented_op(kind, index, level, edge):
    """``vec_op`` of an I/O word, from the registers page's words."""
    return (1 << 9) | kind | index << 3 | level << 4 | edge << 5


steps = st.builds(lambda kind, index, level, edge, x, y: IOStep(
    kind, index=index, level=level, edge=edge, arg_x=x, arg_y=y),
    st.sampled_from(list(IOKind)), st.integers(0, 1), st.integers(0, 1), st.booleans(),
    st.integers(0, 65535), st.integers(0, 65535))


@given(steps)
def test_an_io_step_is_its_documented_word_and_back(step):
    check_segment(*step)
    x, y, op = queue_word(step)
    assert (x, y) == (step[1], step[2])
    assert op == documented_op(step.kind.value, step.index, step.level, int(step.edge))
    back, bx, by, corner = segment_of_words(x, y, op)
    assert back == step and (bx, by, corner) == (x, y, 0)
    assert back.kind == step.kind and back.edge == step.edge


@pytest.mark.parametrize("make, message", [
    (lambda: IOStep(IOKind.WAIT_INPUT, index=2), "index is 0 or 1"),
    (lambda: IOStep(IOKind.SET_OUTPUT, level=3), "level is 0 or 1"),
    (lambda: IOStep(IOKind.WAIT_INPUT, arg_x=70000), "arg_x is 0 … 65535"),
    (lambda: IOStep(IOKind.WAIT_INPUT, arg_y=-1), "arg_y is 0 … 65535"),
    (lambda: IOStep(9), "9"),
])
def test_a_wrong_step_is_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()


WAIT = IOStep(IOKind.WAIT_INPUT, arg_x=1000)
DONE = IOStep(IOKind.SET_OUTPUT, arg_x=1000)


def test_a_jump_comes_before_a_step_after_a_mark_or_a_line():
    segments = [WAIT, ("jump", 10, 20), ("mark", 30, 20), DONE]
    assert job_segments(segments) == [WAIT, ("jump", 10, 20), ("mark", 30, 20),
                                      ("jump", 30, 20), DONE]
    lines = [("jump", 0, 0), ("line", 5, 0), ("pixels", 3, 0), DONE]
    assert job_segments(lines) == [*lines[:3], ("jump", 5, 0), DONE]
    # After a jump none is needed; and a job still ends on one.
    assert job_segments([("jump", 1, 2), DONE]) == [("jump", 1, 2), DONE]
    assert job_segments([WAIT, ("mark", 4, 4)]) == [WAIT, ("mark", 4, 4), ("jump", 4, 4)]


def test_an_image_holds_the_steps_and_only_a_bitstream_with_io_takes_them():
    segments = [WAIT, ("jump", 10, 20), ("mark", 30, 20), DONE]
    image = job_image(segments, {"pitch": 60})
    read = read_image(image, regmap=ULX3SScanner.config().register_map())
    assert [s[0] for s in read.segments] == [WAIT, "jump", "mark", "jump", DONE]
    # The marker's register file takes no I/O word (its vec_op is 9 bits).
    with pytest.raises(ImageError, match="vec_op"):
        read_image(image, regmap=preset_register_map("marker"))
