# amaranth: UnusedElaboratable=no
"""The UART command port alone (gateware/host/uart_port.py): bytes on ``rx`` gathered into
frames, replies queued and sent on ``tx``, against a model of the README's frame rules written
here ("a pause of more than three character times ends a frame, so a frame cut short is counted
and a lost byte never shifts later frames; a byte with a bad stop bit spoils its frame")."""

from amaranth.hdl import Value
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.frames import CommandFrame
from galvoscan.gateware.host.uart_port import UARTCommandPort


DIVISOR = 8                 # the fewest clocks a bit the receiver takes: the quickest simulation
CHAR = 10                   # bits in a character time (8N1)
BROKEN = 63                 # ``bits`` of a frame a line error spoilt (frames.py's interface)
LONG = 3.5 * CHAR           # a pause (idle line, in bits) that must end a frame
SHORT = [0, 0, 0, 1, 5, CHAR]   # pauses (bits) that must not


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


def decode_line(samples, divisor):
    """Bytes read off a line sampled once a clock; every bit must last ``divisor`` clocks."""
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
        out.append(sum(b << k for k, b in enumerate(bits[1:9])))
        i = start + 10 * divisor


# --- the model ---------------------------------------------------------------------------------

def model_frames(events, *, gap_chars=3):
    """Frame events for ``(value, idle_bits_before, bad_stop)`` bytes, followed by a long
    pause: (word, bits) per frame; the word is only the bytes gathered, and is None for a
    spoilt frame (whose bytes nobody may use)."""
    assert all(idle <= CHAR or idle > gap_chars * CHAR for _, idle, _ in events)
    frames = []
    gathered, spoilt = [], False

    def hand_on():
        nonlocal gathered, spoilt
        if spoilt:
            frames.append((None, BROKEN))
        else:
            word = 0
            for b in gathered:
                word = word << 8 | b
            frames.append((word, 8 * len(gathered)))
        gathered, spoilt = [], False

    for value, idle, bad_stop in events:
        if idle > gap_chars * CHAR and (gathered or spoilt):
            hand_on()
        if bad_stop:
            spoilt = True
        else:
            gathered.append(value)
            if len(gathered) == 4:
                hand_on()
    if gathered or spoilt:
        hand_on()
    return frames


def check_frames(got, want):
    assert len(got) == len(want), (got, want)
    for (word, bits), (want_word, want_bits) in zip(got, want):
        assert bits == want_bits, (got, want)
        if want_word is not None:
            mask = (1 << want_bits) - 1
            assert word & mask == want_word, (got, want)


# --- running the port ----------------------------------------------------------------------------

def run_port(events, *, replies=(), divisor=DIVISOR, reply_depth=4, gap_chars=3,
             frames_ready=None, tail_chars=5):
    """Drive ``rx`` with the bytes while offering ``replies`` (as fast as the port takes them);
    returns (frames, bytes on tx, clocks at which each reply was taken)."""
    dut = UARTCommandPort(divisor=divisor, reply_depth=reply_depth, gap_chars=gap_chars)
    frames, tx, taken = [], [], []
    clock = [0]

    async def drive(ctx):
        for level, clocks in line_segments(events, divisor):
            ctx.set(dut.rx, level)
            await ctx.tick().repeat(clocks)
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(tail_chars * CHAR * divisor)

    async def reply(ctx):
        for word in replies:
            ctx.set(dut.replies.payload, word)
            ctx.set(dut.replies.valid, 1)
            await ctx.tick().until(dut.replies.ready)
            taken.append(clock[0])
        ctx.set(dut.replies.valid, 0)

    # The frame as its raw bits, word low (one signal sampled, not two slices of it: the
    # simulator evaluates a slice the slow way, on every clock).
    payload = Value.cast(dut.frames.payload)
    assert [(name, field.offset, field.width) for name, field in CommandFrame] == \
        [("word", 0, 32), ("bits", 32, 6)]

    async def monitor(ctx):
        ready = 1
        async for _, _, valid, frame, line in ctx.tick().sample(
                dut.frames.valid, payload, dut.tx):
            if valid and ready:
                frames.append((frame & 0xFFFF_FFFF, frame >> 32))
            tx.append(line)
            clock[0] += 1
            if frames_ready is not None:
                ready = frames_ready(clock[0])
                ctx.set(dut.frames.ready, ready)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(drive)
    sim.add_testbench(reply, background=True)
    sim.add_testbench(monitor, background=True)
    if frames_ready is None:
        async def always_ready(ctx):
            ctx.set(dut.frames.ready, 1)
        sim.add_testbench(always_ready)
    sim.run()
    return frames, tx, taken


def frame_events(data, *, first_idle=LONG, idle=0):
    return [(b, first_idle if i == 0 else idle, False) for i, b in enumerate(data)]


# --- frames ------------------------------------------------------------------------------------

def test_four_bytes_make_a_frame_most_significant_first():
    events = frame_events(b"\x04\x00\x05\x64", first_idle=2) + frame_events(b"\x81\x02\x03\x64",
                                                                            first_idle=0)
    frames, tx, _ = run_port(events)
    assert frames == [(0x04000564, 32), (0x81020364, 32)]
    assert set(tx) == {1}                   # nothing to say


@pytest.mark.parametrize("idle", [0, 1, 5, CHAR, 2 * CHAR - 1])
def test_pauses_of_up_to_two_character_times_keep_a_frame(idle):
    events = frame_events(b"\x12\x34\x56\x78", first_idle=1, idle=idle)
    frames, _, _ = run_port(events)
    assert frames == [(0x12345678, 32)]


@pytest.mark.parametrize("idle", [2.5 * CHAR, 2.9 * CHAR])
def test_pauses_of_under_three_character_times_keep_a_frame(idle):
    events = frame_events(b"\x12\x34\x56\x78", first_idle=1, idle=idle)
    frames, _, _ = run_port(events)
    assert frames == [(0x12345678, 32)]


@pytest.mark.parametrize("gathered", [1, 2, 3])
def test_a_pause_of_more_than_three_character_times_ends_a_frame(gathered):
    data = bytes([0x10, 0x20, 0x30][:gathered])
    events = frame_events(data, first_idle=1) + frame_events(b"\x04\x00\x09\x64")
    frames, _, _ = run_port(events)
    check_frames(frames, [(int.from_bytes(data, "big"), 8 * gathered), (0x04000964, 32)])


@pytest.mark.parametrize("idle", [3.2 * CHAR, 4 * CHAR])
def test_a_pause_just_over_three_character_times_splits_a_frame(idle):
    events = frame_events(b"\x12\x34", first_idle=1) + \
        frame_events(b"\x56\x78\x9a\xbc", first_idle=idle)
    frames, _, _ = run_port(events)
    check_frames(frames, [(0x1234, 16), (0x56789abc, 32)])


def test_a_lone_pause_makes_no_frame():
    frames, _, _ = run_port(frame_events(b"\x01\x02\x03\x04", first_idle=1)
                            + frame_events(b"\x05\x06\x07\x08", first_idle=10 * CHAR))
    assert frames == [(0x01020304, 32), (0x05060708, 32)]


def test_a_lost_byte_costs_only_its_frame():
    """The host's second frame loses its third byte: that frame comes out cut short, and the
    frames after the pause are whole."""
    events = (frame_events(b"\x04\x00\x05\x64", first_idle=1)
              + frame_events(b"\x05\x12\x64")
              + frame_events(b"\x06\x00\x07\x64")
              + frame_events(b"\x07\x00\x08\x64", first_idle=0))
    frames, _, _ = run_port(events)
    check_frames(frames, [(0x04000564, 32), (0x051264, 24), (0x06000764, 32),
                          (0x07000864, 32)])


@pytest.mark.parametrize("bad", [0, 1, 3])
def test_a_bad_stop_bit_spoils_its_frame(bad):
    data = b"\x04\x00\x05\x64"
    events = [(b, 1 if i == 0 else 0, i == bad) for i, b in enumerate(data)]
    events += frame_events(b"\x04\x00\x06\x64")
    frames, _, _ = run_port(events)
    check_frames(frames, [(None, BROKEN), (0x04000664, 32)])


def test_bad_stop_then_the_rest_of_the_next_frame_is_spoilt_whole():
    """Without a pause, the byte after a spoilt frame's last completes it: four good bytes in
    all, still spoilt."""
    events = [(0x04, 1, False), (0x00, 0, True), (0x05, 0, False), (0x64, 0, False),
              (0x04, 0, False)]
    frames, _, _ = run_port(events)
    check_frames(frames, [(None, BROKEN)])


def test_a_frame_waits_for_the_consumer():
    """frames is a stream: an event stays offered until taken."""
    events = frame_events(b"\xAB\xCD\xEF\x64", first_idle=1)
    frames, _, _ = run_port(events, frames_ready=lambda clock: clock % 97 == 0)
    assert frames == [(0xABCDEF64, 32)]


# --- replies -----------------------------------------------------------------------------------

def words(tx):
    data = decode_line(tx, DIVISOR)
    assert len(data) % 4 == 0
    return [int.from_bytes(bytes(data[i:i + 4]), "big") for i in range(0, len(data), 4)]


@pytest.mark.parametrize("depth", [1, 2, 5])
def test_replies_are_queued_and_sent_in_order(depth):
    replies = [0x84000364 + (k << 8) for k in range(depth + 3)]
    _, tx, taken = run_port([], replies=replies, reply_depth=depth,
                            tail_chars=4 * len(replies) + 4)
    assert words(tx) == replies
    # ``depth`` are taken before the first reply has gone out; then one more each time a reply
    # has been handed to the transmitter whole (its fourth character starts): a reply's time
    # apart, the first sooner (the reply being sent holds its place until then).
    reply_time = 4 * CHAR * DIVISOR
    assert sum(t - taken[0] < 3 * CHAR * DIVISOR for t in taken) == depth, taken
    gaps = [b - a for a, b in zip(taken[depth - 1:], taken[depth:])]
    assert 3 * CHAR * DIVISOR <= gaps[0] <= reply_time, gaps
    assert all(reply_time <= g <= reply_time + 4 for g in gaps[1:]), gaps


def test_the_default_reply_queue_holds_257():
    """README/docstring: replies are queued 257 deep by default."""
    dut_replies = [0x80000064 | (k << 8) for k in range(260)]
    divisor = 104           # 115200 baud at 12 MHz: a reply takes longer to send than to queue
    dut = UARTCommandPort(divisor=divisor)
    taken = []
    clock = [0]

    async def offer(ctx):
        for word in dut_replies:
            ctx.set(dut.replies.payload, word)
            ctx.set(dut.replies.valid, 1)
            await ctx.tick().until(dut.replies.ready)
            taken.append(clock[0])
            if len(taken) == 259:
                break

    async def count(ctx):
        async for _ in ctx.tick():
            clock[0] += 1

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(offer)
    sim.add_testbench(count, background=True)
    sim.run()
    before_first_sent = [t for t in taken if t - taken[0] < 3 * CHAR * divisor]
    assert len(before_first_sent) == 257
    assert taken[-2] - taken[0] > 3 * CHAR * divisor    # the 258th waits for a send


def test_replies_go_out_while_frames_come_in():
    """Full duplex: frames keep coming in correctly while replies are being sent."""
    data = b"\x81\x00\x00\x64\x82\x00\x00\x64\x83\x00\x00\x64"
    replies = [0x81123464, 0x82ABCD64, 0x83000064]
    frames, tx, _ = run_port(frame_events(data, first_idle=1), replies=replies,
                             tail_chars=20)
    assert frames == [(0x81000064, 32), (0x82000064, 32), (0x83000064, 32)]
    assert words(tx) == replies


# --- random streams ------------------------------------------------------------------------------

byte_event = st.tuples(st.integers(0, 255), st.sampled_from(SHORT + [LONG, 4 * CHAR]),
                       st.sampled_from([False] * 9 + [True]))


def well_formed(events):
    """A byte after a bad stop bit needs at least one bit of idle line before its start."""
    return [(v, max(idle, 1) if i and events[i - 1][2] else idle, bad)
            for i, (v, idle, bad) in enumerate(events)]


@settings(max_examples=30, deadline=None)
@given(st.lists(byte_event, min_size=1, max_size=14),
       st.lists(st.integers(0, 2 ** 32 - 1), max_size=3))
def test_random_byte_streams_against_the_model(events, replies):
    """Random bytes, short and long pauses, bad stop bits, while replies go out."""
    events = well_formed(events)
    frames, tx, _ = run_port(events, replies=replies, tail_chars=4 * len(replies) + 5)
    check_frames(frames, model_frames(events))
    assert words(tx) == replies


frame = st.binary(min_size=4, max_size=4)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(frame, st.sampled_from(["whole", "whole", "lose", "bad"]),
                          st.integers(0, 3)), min_size=1, max_size=5))
def test_a_lost_or_spoilt_byte_never_shifts_later_frames(host_frames):
    """Each host frame, whole or with one byte lost or spoilt, then the pause the client
    leaves: every whole frame comes out whole and in its place."""
    events, want = [], []
    for data, fate, index in host_frames:
        if fate == "lose":
            data = data[:index] + data[index + 1:]
            want.append((int.from_bytes(data, "big"), 24))
            events += frame_events(data)
        elif fate == "bad":
            events += [(b, LONG if i == 0 else 0, i == index) for i, b in enumerate(data)]
            want.append((None, BROKEN))
        else:
            events += frame_events(data)
            want.append((int.from_bytes(data, "big"), 32))
    frames, _, _ = run_port(well_formed(events))
    check_frames(frames, want)
