# amaranth: UnusedElaboratable=no
"""The UART command port alone (gateware/host/uart_port.py): bytes on ``rx`` gathered into
frames, answers sent on ``tx``, against a model of the frame rules written here from
frames.py's docstring ("over the UART each frame is COBS-encoded and ends with a zero byte
...: after a lost or extra byte the receiver finds the next frame at the next zero, and only
the frame the fault fell in is lost"; "answers go back as their six bytes"), with the test's
own codec (link_codec.py: its own CRC and COBS, not the gateware's)."""

from amaranth.hdl import Value
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.frames import Answer, CommandFrame
from galvoscan.gateware.host.uart_port import UARTCommandPort
from link_codec import answer, cobs_decode, cobs_encode, command, crc16, parse_answer


DIVISOR = 8                 # the fewest clocks a bit the receiver takes: the quickest simulation
CHAR = 10                   # bits in a character time (8N1)
ANSWER_CHARS = 6            # an answer on the line: its six bytes, nothing more
PERIOD = 1e-6               # the simulated clock's (any: only clocks count)
IDLES = [0, 0, 0, 1, 5, CHAR, 4 * CHAR]     # pauses (bits) before a byte: none ends a frame

# Frames to send, each with some COBS shape: no zero byte (one group, code 11); zeros inside
# (several groups); a body of zeros; a zero in the CRC (a group ending at the last byte).
PLAIN = command(0x11, 0x22, 0x3344, 0x5566, 0x7788)
GROUPS = command(0x05, 0x22, 0x0003, 0x1200, 0x0034)
ZEROS = command(0x00, 0x00)
CRC_ZERO = command(0x07, 0x05, 129)
assert 0 not in PLAIN and 0 in CRC_ZERO[8:] and GROUPS.count(0) == 3


# --- the line ----------------------------------------------------------------------------------

def line_segments(events, divisor):
    """(level, clocks) runs of the line for ``(value, idle_bits_before, bad_stop)`` bytes."""
    segments = []

    def add(level, clocks):
        if clocks <= 0:
            return
        if segments and segments[-1][0] == level:
            segments[-1][1] += clocks
        else:
            segments.append([level, clocks])

    for value, idle, bad_stop in events:
        add(1, round(idle * divisor))
        for bit in [0] + [(value >> i) & 1 for i in range(8)] + [0 if bad_stop else 1]:
            add(bit, divisor)
        if bad_stop:
            add(1, divisor)         # the line returns high
    return segments


def characters(samples, divisor):
    """``(start, value)`` of the characters on a line sampled once a clock (``start`` the
    clock its start bit begins); every bit must last ``divisor`` clocks."""
    out, i = [], 0
    while True:
        try:
            start = samples.index(0, i)
        except ValueError:
            return out
        if start + 10 * divisor > len(samples):
            raise AssertionError("the line ends mid-character")
        bits = []
        for n in range(10):
            run = samples[start + n * divisor:start + (n + 1) * divisor]
            assert len(set(run)) == 1, f"bit {n} of the character at {start} wobbles"
            bits.append(run[0])
        assert bits[0] == 0 and bits[9] == 1
        out.append((start, sum(b << k for k, b in enumerate(bits[1:9]))))
        i = start + 10 * divisor


def decode_line(samples, divisor):
    """The bytes on a line sampled once a clock."""
    return [value for _, value in characters(samples, divisor)]


def byte_events(data, *, first_idle=1, idle=0, bad=()):
    """``(value, idle_bits_before, bad_stop)`` for each byte of ``data``; the bytes at the
    indices in ``bad`` have a low stop bit."""
    return [(b, first_idle if i == 0 else idle, i in bad) for i, b in enumerate(data)]


def well_formed(events):
    """A byte after a bad stop bit needs at least one bit of idle line before its start."""
    return [(v, max(idle, 1) if i and events[i - 1][2] else idle, bad)
            for i, (v, idle, bad) in enumerate(events)]


def on_wire(frame):
    """A frame's bytes on the line: COBS-encoded, then a zero byte."""
    return cobs_encode(frame) + b"\0"


def payload(frame):
    """What the port hands on of a whole frame: its eight bytes before the CRC, first on top."""
    return int.from_bytes(frame[:8], "big")


# --- the model ---------------------------------------------------------------------------------

def model_frames(events):
    """Frame events for ``(value, idle_bits_before, bad_stop)`` bytes, as the frame rules say:
    the stream is split at its zero bytes (a byte with a bad stop bit is no zero byte, whatever
    its bits: it only spoils the part it falls in); each part that is not empty is one event,
    intact if no byte of it had a bad stop bit and it COBS-decodes to exactly ten bytes whose
    CRC holds. ``(intact, payload)`` per event, the payload None for one not intact (nobody may
    use its bytes). Bytes after the last zero are no frame yet."""
    frames = []
    part, spoilt = bytearray(), False
    for value, _, bad_stop in events:
        if bad_stop:
            spoilt = True
        elif value != 0:
            part.append(value)
        else:
            if part or spoilt:
                decoded = None if spoilt else cobs_decode(bytes(part))
                if decoded is not None and len(decoded) == 10 and crc16(decoded) == 0:
                    frames.append((True, payload(decoded)))
                else:
                    frames.append((False, None))
            part, spoilt = bytearray(), False
    return frames


def check_frames(got, want):
    """The same events, intact the same, and an intact one's payload the same (a broken
    frame's payload is whatever the port last gathered: no one may use it)."""
    assert len(got) == len(want), (got, want)
    for (intact, word), (want_intact, want_word) in zip(got, want):
        assert intact == want_intact, (got, want)
        if want_intact:
            assert word == want_word, (got, want)


# --- running the port ----------------------------------------------------------------------------

#: Clocks from the command decoder taking a frame to offering its answer, at the fewest.
DECODER_CLOCKS = 3


def run_port(events, *, replies=(), divisor=DIVISOR, frames_ready=None, per_frame=False):
    """Drive ``rx`` with the bytes while offering ``replies`` (``(tag, code, data)`` answers) as
    the command decoder does: each valid for one clock while ``replies.ready`` is high, its
    payload held until ``ready`` is high again, and then at once other bits (the next frame's,
    from which the decoder's next answer is made, :data:`DECODER_CLOCKS` later at the
    soonest); as fast as the port takes them, or with ``per_frame`` the k-th once k frames
    have come out. Returns (frames as ``(intact, payload)``, the tx line a clock at a time,
    and for each reply the clock it was taken at and the first clock ``ready`` was high again,
    low every clock in between).

    Only replies and a ``frames_ready`` pattern need the line and the clocks counted: without
    them the monitors wake only when ``frames.valid`` or ``tx`` change (a quicker simulation),
    ``tx`` must stay idle (nothing to say) and comes back None."""
    dut = UARTCommandPort(divisor=divisor)
    segments = line_segments(events, divisor)
    # Idle line after the bytes: enough for the last event, and for the answers (which go out
    # while rx is driven, a character each spare; one per frame, the last after the last).
    rx_chars = sum(clocks for _, clocks in segments) // (CHAR * divisor)
    tail_chars = 2 + (ANSWER_CHARS + 1 if per_frame and replies else
                      max(0, (ANSWER_CHARS + 1) * len(replies) - rx_chars))
    frames, tx, taken, tx_changes = [], [], [], []
    clock = [0]
    every_clock = bool(replies) or frames_ready is not None

    async def drive(ctx):
        # The line changes half a clock after an edge, and waits whole clocks (a delay wakes
        # the testbench once; ``tick().repeat`` would every clock).
        if frames_ready is None:
            ctx.set(dut.frames.ready, 1)
        await ctx.tick()
        await ctx.delay(PERIOD / 2)
        for level, clocks in segments:
            ctx.set(dut.rx, level)
            await ctx.delay(clocks * PERIOD)
        ctx.set(dut.rx, 1)
        await ctx.delay(tail_chars * CHAR * divisor * PERIOD)

    answer_bits = Value.cast(dut.replies.payload)

    async def reply(ctx):
        for k, (tag, code, data) in enumerate(replies):
            while not ctx.get(dut.replies.ready) or (per_frame and len(frames) <= k):
                await ctx.tick()
            bits = (tag << 24) | (code << 16) | data
            ctx.set(answer_bits, bits)
            ctx.set(dut.replies.valid, 1)
            await ctx.tick()
            ctx.set(dut.replies.valid, 0)
            start = clock[0]
            while not ctx.get(dut.replies.ready):
                await ctx.tick()
            taken.append((start, clock[0]))
            # The decoder takes the next frame now: its answer's bits are the frame's, not the
            # answer's, until it is made.
            ctx.set(answer_bits, bits ^ 0xFFFFFFFF)
            await ctx.tick().repeat(DECODER_CLOCKS)

    # The frame as its raw bits, payload low (one signal sampled, not two fields of it: the
    # simulator evaluates a slice the slow way, on every clock).
    word = Value.cast(dut.frames.payload)
    assert [(name, field.offset, field.width) for name, field in CommandFrame] == \
        [("payload", 0, 64), ("intact", 64, 1)]

    def event(frame):
        return (bool(frame >> 64), frame & (2 ** 64 - 1))

    async def monitor(ctx):
        ready = 1 if frames_ready is None else 0
        async for _, _, valid, frame, line in ctx.tick().sample(dut.frames.valid, word, dut.tx):
            if valid and ready:
                frames.append(event(frame))
            tx.append(line)
            clock[0] += 1
            if frames_ready is not None:
                ready = frames_ready(clock[0])
                ctx.set(dut.frames.ready, ready)

    async def watch_frames(ctx):
        # frames.ready is always high here: each event is one clock of valid, taken at the
        # clock edge after valid rises (the payload settles after valid itself).
        while True:
            await ctx.posedge(dut.frames.valid)
            _, _, frame = await ctx.tick().sample(word)
            frames.append(event(frame))
            assert not ctx.get(dut.frames.valid), "an event offered again once taken"

    async def watch_tx(ctx):
        async for (line,) in ctx.changed(dut.tx):
            tx_changes.append(line)

    sim = Simulator(dut)
    sim.add_clock(PERIOD)
    sim.add_testbench(drive)
    if every_clock:
        sim.add_testbench(reply, background=True)
        sim.add_testbench(monitor, background=True)
    else:
        sim.add_testbench(watch_frames, background=True)
        sim.add_testbench(watch_tx, background=True)
    sim.run()
    if not every_clock:
        assert set(tx_changes) <= {1}, "tx moved with nothing to say"
        tx = None
    return frames, tx, taken


# --- frames ------------------------------------------------------------------------------------

def intact_flags(frames):
    return [intact for intact, _ in frames]


def test_a_frame_is_one_intact_event_its_first_eight_bytes_on_top():
    """Frames of every COBS shape, back to back: one intact event each, in order."""
    sent = [PLAIN, GROUPS, ZEROS, CRC_ZERO]
    assert all(len(on_wire(frame)) == 12 for frame in sent)
    frames, _, _ = run_port(byte_events(b"".join(on_wire(frame) for frame in sent)))
    assert frames == [(True, payload(frame)) for frame in sent]


def test_pauses_do_not_end_a_frame():
    """Only a zero byte ends a frame: a host that stalls between bytes still gets through
    (pauses of one, four and twelve character times, which ended a frame before COBS)."""
    idles = [1, CHAR, 0, 4 * CHAR, 0, 0, 12 * CHAR, 0, 1, 0, 0, 4 * CHAR]
    groups = on_wire(GROUPS)
    assert len(groups) == len(idles)
    events = [(b, idle, False) for b, idle in zip(groups, idles)]
    frames, _, _ = run_port(events)
    assert frames == [(True, payload(GROUPS))]


def test_zero_bytes_alone_make_no_event():
    """A zero byte with nothing before it (a host's flush, or the resynchronising zero a host
    sends first) is no frame."""
    data = b"\0\0\0" + on_wire(PLAIN) + b"\0\0" + on_wire(CRC_ZERO) + b"\0"
    frames, _, _ = run_port(byte_events(data))
    assert frames == [(True, payload(PLAIN)), (True, payload(CRC_ZERO))]


def test_a_code_byte_past_a_frame_spoils_it():
    """A code byte larger than ten bytes need (11) refuses its frame, even when the ten bytes
    of a good frame follow it (codes 27 and 251 are 11 in their low four bits: a frame's
    worth, to a counter of bytes left too narrow for them); the next frame is whole."""
    codes = [12, 13, 27, 0x80, 0xFB, 0xFF]
    data = b"".join(bytes([code]) + PLAIN + b"\0" + on_wire(GROUPS) for code in codes)
    frames, _, _ = run_port(byte_events(data))
    assert intact_flags(frames) == [False, True] * len(codes)
    assert frames[1::2] == [(True, payload(GROUPS))] * len(codes)


def test_a_part_that_is_no_frame_is_refused():
    """Something before a zero byte that is no ten-byte frame is one event, not intact: no
    bytes, a lone zero, a group cut short, nine bytes and a zero, a whole frame and a zero or
    two more (its CRC holds over them all: only the count refuses it)."""
    parts = [b"\x01", b"\x01\x01", b"\x05\x11\x22", cobs_encode(PLAIN[:9] + b"\0"),
             cobs_encode(GROUPS + b"\0"), cobs_encode(PLAIN + b"\0\0")]
    assert crc16(GROUPS + b"\0") == crc16(PLAIN + b"\0\0") == 0
    frames, _, _ = run_port(byte_events(b"".join(part + b"\0" + on_wire(PLAIN)
                                                 for part in parts)))
    assert intact_flags(frames) == [False, True] * len(parts)
    assert frames[1::2] == [(True, payload(PLAIN))] * len(parts)


def damage(wire, fault, index=0):
    """A frame's bytes on the line (``wire``, its zero byte last) with one fault before its
    zero byte."""
    body = wire[:-1]
    if fault == "cut":                  # the frame cut short: its last ``index`` bytes lost
        body = body[:-index]
    elif fault == "over":               # run over: ``index`` bytes more
        body = body + bytes(range(0x41, 0x41 + index))
    elif fault == "lose":               # the byte at ``index`` lost
        body = body[:index] + body[index + 1:]
    elif fault == "extra":              # a byte more at ``index``
        body = body[:index] + b"\x5a" + body[index:]
    else:
        raise ValueError(fault)
    return body + b"\0"


@pytest.mark.parametrize("fault, indices", [
    ("cut", [1, 4, 10]),
    ("over", [1, 3]),
    ("lose", [0, 1, 5, 10]),
    ("extra", [0, 3, 11]),
])
def test_a_damaged_frame_is_refused_and_the_next_comes_through(fault, indices):
    """Cut short, run over, a byte lost or a byte more (at each of ``indices``): that frame
    is one event, not intact, and the frame after it, found at the next zero byte, is
    whole."""
    data = b"".join(damage(on_wire(GROUPS), fault, index) + on_wire(CRC_ZERO)
                    for index in indices)
    frames, _, _ = run_port(byte_events(data))
    assert intact_flags(frames) == [False, True] * len(indices)
    assert frames[1::2] == [(True, payload(CRC_ZERO))] * len(indices)


def test_a_lost_zero_byte_costs_the_two_frames_it_joins():
    """Without its zero byte a frame runs into the next: the two are one event, not intact;
    the one after is whole."""
    data = on_wire(PLAIN)[:-1] + on_wire(GROUPS) + on_wire(CRC_ZERO)
    frames, _, _ = run_port(byte_events(data))
    assert intact_flags(frames) == [False, True]
    assert frames[1] == (True, payload(CRC_ZERO))


def test_a_bad_stop_bit_spoils_its_frame():
    """A bad stop bit on the first, second, a middle or the last byte before the zero, or on
    a byte more before the first or after the last (the frame's own bytes all good): the frame
    is refused, the next one whole."""
    bads = [0, 1, 3, 6, 10]
    spoilt = [byte_events(on_wire(GROUPS), bad={bad}) for bad in bads]
    for at in [0, 11]:
        events = byte_events(on_wire(GROUPS))
        spoilt.append(events[:at] + [(0x55, 1, True)] + events[at:])
    events = []
    for frame in spoilt:
        events += frame + byte_events(on_wire(PLAIN))
    frames, _, _ = run_port(well_formed(events))
    assert intact_flags(frames) == [False, True] * len(spoilt)
    assert frames[1::2] == [(True, payload(PLAIN))] * len(spoilt)


def test_a_bad_stop_bit_on_the_zero_byte_joins_two_frames():
    """A zero byte with a bad stop bit is lost, not taken for a frame's end: its frame and the
    next are one event, not intact; the one after is whole."""
    events = byte_events(on_wire(GROUPS), bad={11}) + byte_events(on_wire(PLAIN)) + \
        byte_events(on_wire(ZEROS))
    frames, _, _ = run_port(well_formed(events))
    assert intact_flags(frames) == [False, True]
    assert frames[1] == (True, payload(ZEROS))


def test_a_lone_bad_byte_is_a_refused_frame():
    """A byte with a bad stop bit alone before a zero byte is still something received: one
    event, not intact."""
    events = [(0x00, 1, True), (0x00, 1, False)] + byte_events(on_wire(PLAIN))
    frames, _, _ = run_port(events)
    assert intact_flags(frames) == [False, True]


def test_a_frame_waits_for_the_consumer():
    """frames is a stream: an event stays offered until taken, each taken once."""
    frames, _, _ = run_port(byte_events(on_wire(GROUPS) + on_wire(PLAIN)),
                            frames_ready=lambda clock: clock % 97 == 0)
    assert frames == [(True, payload(GROUPS)), (True, payload(PLAIN))]


# --- damaged frames, every way -----------------------------------------------------------------

def flipped_units(frame, flips):
    """For each ``(byte, bit)``: the frame on the line with that one bit flipped, ending with a
    zero byte (one more if the flip was in the frame's own): each unit starts the port afresh,
    whatever the flip did to the zero bytes."""
    wire = on_wire(frame)
    units = []
    for index, bit in flips:
        damaged = bytearray(wire)
        damaged[index] ^= 1 << bit
        units.append(bytes(damaged) + (b"\0" if damaged[-1] else b""))
    return units


def check_flips(frames_sent, units, got):
    """The port's events for the units match the model's, and unit by unit: a flip that made
    no zero byte is one event, refused; no flip gives an intact event with a payload other
    than a frame sent."""
    check_frames(got, [event for unit in units for event in model_frames(byte_events(unit))])
    sent = {payload(frame) for frame in frames_sent}
    for unit in units:
        count = len(model_frames(byte_events(unit)))
        these, got = got[:count], got[count:]
        if unit.count(0) == 1:      # one zero byte, at the end: none made (or the frame's own
                                    # lost, and the zero after it ends the frame instead)
            assert intact_flags(these) == [False], (unit.hex(), these)
        assert not any(intact and word not in sent for intact, word in these), (unit.hex(), these)


def test_every_bit_flip_of_a_frame_is_refused():
    """All 96 single-bit flips of one frame's twelve bytes on the line (a frame of four COBS
    groups), as one stream."""
    wire = on_wire(GROUPS)
    assert len(wire) == 12 and GROUPS.count(0) == 3
    units = flipped_units(GROUPS, [(i, b) for i in range(len(wire)) for b in range(8)])
    frames, _, _ = run_port(byte_events(b"".join(units)))
    check_flips([GROUPS], units, frames)


command_frame = st.builds(
    lambda seq, address, data, x, y: command(seq, address, data, x, y),
    st.integers(0, 255), st.sampled_from([0, 1, 2, 3, 0x22, 0x7F, 0x80, 0xA2]),
    *[st.sampled_from([0, 1, 0x100, 0xFFFF]) | st.integers(0, 0xFFFF)] * 3)


@settings(max_examples=10, deadline=None)
@given(command_frame, st.lists(st.tuples(st.integers(0, 11), st.integers(0, 7)),
                               min_size=1, max_size=3))
def test_random_frames_with_a_bit_flipped_are_refused(frame, flips):
    """Frames of any content, a bit flipped anywhere on the line, a few one after another and
    then the frame whole."""
    units = flipped_units(frame, flips)
    units.append(on_wire(frame))                        # and then the frame whole
    frames, _, _ = run_port(byte_events(b"".join(units)))
    check_flips([frame], units[:-1], frames[:-1])
    assert frames[-1] == (True, payload(frame))


fate = st.one_of(
    st.just(("whole", 0)), st.just(("whole", 0)),
    st.tuples(st.just("cut"), st.integers(1, 10)),          # (the code byte left)
    st.tuples(st.just("over"), st.integers(1, 4)),
    st.tuples(st.just("lose"), st.integers(0, 10)),
    st.tuples(st.just("extra"), st.integers(0, 11)),
    st.tuples(st.just("bad"), st.integers(0, 10)),
)


@settings(max_examples=12, deadline=None)
@given(st.lists(st.tuples(command_frame, fate), min_size=1, max_size=4),
       st.sampled_from([0, 1, CHAR]))
def test_a_damaged_frame_never_costs_the_next(host_frames, idle):
    """Each host frame whole, or cut short, run over, with a byte lost, a byte more or a bad
    stop bit before its zero byte: every damaged frame is one event, refused, and every whole
    frame comes out whole in its place."""
    events, want = [], []
    for frame, (fault, index) in host_frames:
        wire = on_wire(frame)
        if fault == "whole":
            events += byte_events(wire, first_idle=idle)
            want.append((True, payload(frame)))
        elif fault == "bad":
            events += byte_events(wire, first_idle=idle, bad={index})
            want.append((False, None))
        else:
            events += byte_events(damage(wire, fault, index), first_idle=idle)
            want.append((False, None))
    frames, _, _ = run_port(well_formed(events))
    check_frames(frames, want)


# --- answers -----------------------------------------------------------------------------------

def wire_answers(answers):
    """The answers on the line, as the test's codec writes them: six bytes each, back to
    back."""
    return b"".join(answer(*a) for a in answers)


def answers_on(tx):
    """The answers read off the tx line by the test's codec: six bytes each, every one's CRC
    holding, nothing more."""
    line = bytes(decode_line(tx, DIVISOR))
    assert len(line) % ANSWER_CHARS == 0, line.hex()
    found = [line[i:i + ANSWER_CHARS] for i in range(0, len(line), ANSWER_CHARS)]
    decoded = [parse_answer(p) for p in found]
    assert all(decoded), [p.hex() for p in found]
    return decoded


def check_ready(tx, taken):
    """Each answer's ``replies.ready`` low (``taken``: run_port's clocks, the one it was
    taken at and the first ``ready`` was high again, low in between) until its last byte is
    handed to the transmitter, the clock before that byte's start bit: then high at once."""
    starts = [start for start, _ in characters(tx, DIVISOR)]
    assert len(starts) == ANSWER_CHARS * len(taken)
    for k, (at, back) in enumerate(taken):
        first, last = starts[ANSWER_CHARS * k], starts[ANSWER_CHARS * (k + 1) - 1]
        assert at < first and last - 2 <= back <= last, (k, at, back, first, last)


ANSWERS_WITH_ZEROS = [
    (0x00, 0x00, 0x0000),       # all zero but the CRC
    (0x12, 0x05, 30),           # the CRC's last byte zero
    (0x12, 0x05, 77),           # the CRC's first byte zero
    (0x12, 0x05, 1792),         # zeros in the data and the CRC
    (0x05, 0x22, 0x0100),
    (0x80, 0x81, 0xFFFF),       # no zero byte
    (0x00, 0x00, 0x0000),       # one answer twice over
    (0x00, 0x00, 0x0000),
]
assert answer(0x12, 0x05, 30)[5] == 0 and answer(0x12, 0x05, 77)[4] == 0
assert 0 not in answer(0x80, 0x81, 0xFFFF) and answer(0x12, 0x05, 1792)[3:5] == b"\0\0"


def test_answers_go_out_as_six_bytes_in_order():
    """Each answer (``tag`` in the top byte) goes out as tag, code, data and the CRC over them,
    six bytes back to back and nothing else: here answers with zero bytes anywhere, one after
    another."""
    assert [(name, field.offset, field.width) for name, field in Answer] == \
        [("data", 0, 16), ("code", 16, 8), ("tag", 24, 8)]
    _, tx, taken = run_port([], replies=ANSWERS_WITH_ZEROS)
    assert bytes(decode_line(tx, DIVISOR)) == wire_answers(ANSWERS_WITH_ZEROS)
    assert answers_on(tx) == ANSWERS_WITH_ZEROS
    assert all(len(answer(*a)) == ANSWER_CHARS for a in ANSWERS_WITH_ZEROS)
    check_ready(tx, taken)


def test_one_answer_goes_out_at_a_time():
    """There is no queue: an answer is taken while none is going out, and ``replies.ready``
    is low from then until its last byte has been handed to the transmitter, the payload
    held all that time and changed at once after (run_port); answers offered as soon as
    they can be go back to back on the line, one an answer's time apart."""
    replies = [(k, 0x05, 0x1200 + k) for k in range(4)]
    _, tx, taken = run_port([], replies=replies)
    assert answers_on(tx) == replies
    check_ready(tx, taken)
    chars = characters(tx, DIVISOR)
    # The first byte goes once its eight bits are in the CRC: a few clocks more.
    assert 8 < chars[0][0] - taken[0][0] <= 8 + 4, (chars[0], taken[0])
    # Back to back: a character time apart (the transmitter may hold a stop bit a clock
    # longer), from the first answer's first byte to the last answer's last.
    gaps = [b - a for (a, _), (b, _) in zip(chars, chars[1:])]
    assert all(CHAR * DIVISOR <= g <= CHAR * DIVISOR + 1 for g in gaps), gaps
    # The next answer is taken as soon as the last's last byte is handed on (and the
    # decoder has made it): five characters and the CRC of the first byte for the first,
    # an answer's time for the others.
    starts = [at for at, _ in taken]
    answer_time = ANSWER_CHARS * CHAR * DIVISOR
    gaps = [b - a for a, b in zip(starts, starts[1:])]
    assert (ANSWER_CHARS - 1) * CHAR * DIVISOR + 8 <= gaps[0] <= answer_time, gaps
    assert all(answer_time <= g <= answer_time + ANSWER_CHARS for g in gaps[1:]), gaps


def test_answers_go_out_while_frames_come_in():
    """Full duplex: frames keep coming in whole while answers are being sent, each answer
    offered once a frame has come out (as the decoder does), the last also while the next
    frame comes in."""
    data = on_wire(GROUPS) + on_wire(ZEROS) + on_wire(PLAIN) + on_wire(CRC_ZERO)
    replies = [(0x05, 0x22, 0x0003), (0x00, 0x00, 0x0000), (0x11, 0x22, 0x3344)]
    frames, tx, taken = run_port(byte_events(data), replies=replies, per_frame=True)
    assert frames == [(True, payload(frame)) for frame in (GROUPS, ZEROS, PLAIN, CRC_ZERO)]
    assert answers_on(tx) == replies
    check_ready(tx, taken)
    # The frames come back to back, twelve characters each from the line's first clocks:
    # each answer goes out while the next frame comes in (its first byte from the middle of
    # the stop bit of the zero byte of the frame it answers).
    frame_time = len(on_wire(GROUPS)) * CHAR * DIVISOR
    starts = [start for start, _ in characters(tx, DIVISOR)]
    for k in range(len(replies)):
        first, last = starts[ANSWER_CHARS * k], starts[ANSWER_CHARS * (k + 1) - 1]
        assert (k + 1) * frame_time - CHAR * DIVISOR < first, (k, first)
        assert last + CHAR * DIVISOR < (k + 2) * frame_time, (k, last)


# --- random streams ------------------------------------------------------------------------------

def piece_events(piece, idle, bad):
    """A piece's bytes, a pause before the first, the one at ``bad`` (if any) with a bad stop
    bit."""
    return [(b, idle if i == 0 else 0, bad == i) for i, b in enumerate(piece)]


piece = st.one_of(
    command_frame.map(on_wire),                                     # a frame
    st.tuples(command_frame, fate).map(                             # a damaged frame
        lambda f: damage(on_wire(f[0]), *f[1]) if f[1][0] in ("cut", "over", "lose", "extra")
        else on_wire(f[0])),
    command_frame.map(lambda f: on_wire(f)[:-1]),                   # a frame without its zero
    st.binary(min_size=1, max_size=4),                              # noise
    st.just(b"\0"),
    st.sampled_from([b"\x0c", b"\xff", b"\x01"]),                   # code bytes
)

answer_fields = st.tuples(st.integers(0, 255), st.integers(0, 255),
                          st.sampled_from([0, 0x100, 0xFF00]) | st.integers(0, 0xFFFF))


@settings(max_examples=20, deadline=None)
@given(st.lists(st.tuples(piece, st.sampled_from(IDLES), st.sampled_from([None] * 6 + [0, 1, 5])),
                min_size=1, max_size=4),
       st.lists(answer_fields, max_size=2))
def test_random_byte_streams_against_the_model(pieces, replies):
    """Frames, damaged frames, noise, zero bytes and code bytes, with pauses and now and then a
    bad stop bit, while answers go out: the events are the model's."""
    events = []
    for data, idle, bad in pieces:
        events += piece_events(data, idle, bad)
    events = well_formed(events)
    frames, tx, taken = run_port(events, replies=replies)
    check_frames(frames, model_frames(events))
    if replies:
        assert answers_on(tx) == replies
        check_ready(tx, taken)
