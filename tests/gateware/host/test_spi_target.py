# amaranth: UnusedElaboratable=no
"""The SPI target alone (gateware/host/spi_target.py), driven by a mode-0 host written here:
SCK idles low, the host sets COPI while SCK is low and both sides sample on the rising edge.
Checked against a model of the frame format (gateware/host/frames.py) written here, with the
test-side codec's CRC (tests/support/link_codec.py), not the gateware's: a frame is exactly what is
clocked in while ``cs_n`` is low, handed on with its first 64 bits and whether it is intact
(exactly 80 bits, and the CRC over all of them holds). Answers are offered on ``replies`` for
one clock each, as the decoder offers them: the target takes one only between frames
(``ready`` is high exactly while no frame is being clocked), a newer one replacing one not yet
sent, and shifts it out on CIPO during the next frame, once, most significant bit first (tag,
code, data), then its CRC-16, then zeros. One offered while a frame is being clocked is not
taken, and goes out nowhere."""

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.spi_target import MIN_CLOCKS_PER_SCK, SPITarget

from link_codec import answer as answer_bytes, command, crc16, parse_answer


HALF = MIN_CLOCKS_PER_SCK // 2      # system clocks per half SCK period: the stated maximum SCK
FRAME_BITS = 80                     # a command frame, with its CRC
ANSWER_BITS = 48                    # an answer, with its CRC
#: Clocks the target sees cs_n late: the two synchroniser flip-flops, then the clock on which
#: it starts or ends a frame. ``replies.ready`` is cs_n this many clocks before (high exactly
#: while no frame is being clocked), as :func:`test_replies_ready_is_high_exactly_between_frames`
#: checks clock by clock.
SEEN = 3
JUNK = {"tag": 0xEE, "code": 0xEE, "data": 0xEEEE}     # on the answer lines while not valid


def to_bits(data):
    """The bits of ``data`` (bytes), most significant first."""
    return [(byte >> (7 - i)) & 1 for byte in data for i in range(8)]


def to_word(bits):
    word = 0
    for b in bits:
        word = word << 1 | b
    return word


def to_bytes(bits):
    return bytes(to_word(bits[i:i + 8]) for i in range(0, len(bits), 8))


def crc_bits(bits, crc=0xFFFF):
    """CRC-16/CCITT over a bit string of any length (to build frames that are not whole bytes
    but whose CRC holds); checked against the codec's table in :func:`test_crc_bits`."""
    for b in bits:
        crc = ((crc << 1) & 0xFFFF) ^ (0x1021 if (crc >> 15) ^ b else 0)
    return crc


def checked(bits):
    """``bits`` followed by their CRC: a bit string whose CRC holds, of any length >= 16."""
    return bits + [(crc_bits(bits) >> (15 - i)) & 1 for i in range(16)]


def run_target(transactions, *, half=HALF, idle=8, take=0):
    """Each transaction is a dict: ``bits`` clocked in; ``answers``, (tag, code, data) each
    offered on ``replies`` for one clock (as the decoder offers them), on consecutive clocks
    after ``idle`` clocks with ``cs_n`` high, then ``wait`` clocks (default 0) before ``cs_n``
    falls; ``start``, (clocks, answer): one more offered that many clocks after ``cs_n`` falls
    (fewer than ``half`` - 1); ``late``, (bit, answer): one more offered before the host clocks that
    bit (len(bits): after the last); ``glitch``, (before which bit, clocks) ``cs_n`` goes high in
    the middle (after a late offer at the same bit), or None. While no answer is offered the
    answer lines carry junk. The consumer raises ``frames.ready`` ``take`` clocks after an event
    is offered. Returns (frame events as (payload, intact), CIPO as the host sampled it on each
    rising edge, per transaction, and ``replies.ready`` on each offer's clock, in order)."""
    dut = SPITarget()
    events, cipo, taken = [], [], []

    async def offer(ctx, answer):
        # For one clock, as the decoder offers it; taken or not, it is gone after.
        tag, code, data = answer
        ctx.set(dut.replies.payload, {"tag": tag, "code": code, "data": data})
        ctx.set(dut.replies.valid, 1)
        taken.append(ctx.get(dut.replies.ready))
        await ctx.tick()
        ctx.set(dut.replies.valid, 0)
        ctx.set(dut.replies.payload, JUNK)

    async def host(ctx):
        ctx.set(dut.replies.payload, JUNK)
        await ctx.tick().repeat(4)
        for t in transactions:
            await ctx.tick().repeat(idle)
            for answer in t.get("answers", []):
                await offer(ctx, answer)
            for _ in range(t.get("wait", 0)):
                await ctx.tick()
            ctx.set(dut.cs_n, 0)
            start = t.get("start")
            if start is not None:
                assert start[0] < half - 1
                for _ in range(start[0]):
                    await ctx.tick()
                await offer(ctx, start[1])
                await ctx.tick().repeat(half - start[0] - 1)    # half > start[0] + 1
            else:
                await ctx.tick().repeat(half)
            seen = []
            glitch, late = t.get("glitch"), t.get("late")
            for i, bit in enumerate(t["bits"] + [None]):
                if late is not None and late[0] == i:
                    await offer(ctx, late[1])
                if glitch is not None and glitch[0] == i:
                    ctx.set(dut.cs_n, 1)
                    await ctx.tick().repeat(glitch[1])
                    ctx.set(dut.cs_n, 0)
                    await ctx.tick().repeat(half)
                if bit is None:
                    break
                ctx.set(dut.copi, bit)
                await ctx.tick().repeat(half)
                seen.append(ctx.get(dut.cipo))       # the host samples as SCK rises
                ctx.set(dut.sck, 1)
                await ctx.tick().repeat(half)
                ctx.set(dut.sck, 0)
            await ctx.tick().repeat(half)
            ctx.set(dut.cs_n, 1)
            cipo.append(seen)
        await ctx.tick().repeat(8 + take)      # the last frame through the synchronisers

    async def decoder(ctx):
        """Takes frame events, ``take`` clocks after each is offered, checking that it holds
        meanwhile. Between events it sleeps until the next (clock by clock, the simulation
        takes three times as long)."""
        offered = None
        while True:
            if not ctx.get(dut.frames.valid):
                assert offered is None, "a frame event was withdrawn before it was taken"
                await ctx.posedge(dut.frames.valid)
            event = (ctx.get(dut.frames.payload.payload), ctx.get(dut.frames.payload.intact))
            if offered is not None:
                assert event == offered[0], "a frame event changed before it was taken"
            ready = (offered[1] if offered is not None else 0) >= take
            ctx.set(dut.frames.ready, ready)
            await ctx.tick()
            ctx.set(dut.frames.ready, 0)
            if ready:
                events.append(event)
                offered = None
            else:
                offered = (event, offered[1] + 1 if offered is not None else 1)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(host)
    sim.add_testbench(decoder, background=True)
    sim.run()
    return events, cipo, taken


def frame_event(bits):
    """The event the format calls for after a frame of ``bits``: its first 64 bits (None, for
    "any", when it had fewer: such a frame is not intact, and its payload means nothing), and
    whether it is intact."""
    payload = to_word(bits[:64]) if len(bits) >= 64 else None
    return payload, int(len(bits) == FRAME_BITS and crc16(to_bytes(bits)) == 0)


def model(transactions, *, idle=8):
    """The frame events, the CIPO bits and whether each answer offered is taken, as the format
    calls for (``idle`` as given to :func:`run_target`)."""
    events, cipo, taken = [], [], []
    for n, t in enumerate(transactions):
        # ``ready`` is cs_n SEEN clocks before: high since reset before the first frame, and
        # before the others from SEEN clocks after cs_n rises until SEEN clocks after it falls.
        answers = t.get("answers", [])
        high = None if n == 0 else idle + len(answers) + t.get("wait", 0)   # clocks cs_n high
        # Offered between frames: taken once the target has seen the last frame end, each
        # replacing the one before.
        pending = None
        for k, answer in enumerate(answers):
            taken.append(n == 0 or idle + k >= SEEN)
            pending = answer if taken[-1] else pending
        # Offered as the frame starts: taken until the target has seen cs_n fall (if it has
        # seen it rise), and then it is the one that goes out in this frame.
        start = t.get("start")
        if start is not None:
            taken.append(start[0] < SEEN and (high is None or high >= SEEN - start[0]))
            pending = start[1] if taken[-1] else pending
        bits = t["bits"]
        glitch = t.get("glitch")
        cut = glitch[0] if glitch is not None else None
        parts = [bits] if cut is None else [bits[:cut], bits[cut:]]
        seen = []
        for part in parts:
            events.append(frame_event(part))
            # The waiting answer goes out during the frame (then zeros); only once.
            out = to_bits(answer_bytes(*pending)) if pending is not None else []
            seen += (out + [0] * len(part))[:len(part)]
            pending = None
        if t.get("late") is not None:           # offered during the frame: not taken
            taken.append(False)
        cipo.append(seen)
    return events, cipo, taken


def same(events, expected):
    """Events as expected, a payload of None matching any."""
    return len(events) == len(expected) and all(
        e == x or x[0] is None and e[1] == x[1] for e, x in zip(events, expected))


def frame(data, answer=None, **kw):
    """A transaction of ``data``'s bits; ``answer``, one answer offered before it."""
    return {"bits": to_bits(data), **({"answers": [answer]} if answer is not None else {}),
            **kw}


def check(transactions, **kw):
    """Runs the target and the model on ``transactions``: the same events, CIPO bits and
    answers taken. Returns what the target did."""
    events, cipo, taken = run_target(transactions, **kw)
    expected_events, expected_cipo, expected_taken = model(transactions, idle=kw.get("idle", 8))
    assert same(events, expected_events)
    assert cipo == expected_cipo
    assert taken == expected_taken
    return events, cipo, taken


GOOD = [command(0, 0x04, 0x0564), command(0x5A, 0x81, read=True),
        command(0xFF, 0x7F, 0xFFFF, 0xFFFF, 0xFFFF), command(0x01, 0x12, 0x8000, 0x1234, 0xFEDC)]


def test_crc_bits():
    """The bitwise CRC used to build odd-length frames agrees with the codec's table."""
    for data in GOOD + [b"", b"\x00", b"123456789"]:
        assert crc_bits(to_bits(data)) == crc16(data)
    assert crc_bits(to_bits(b"123456789")) == 0x29B1        # CRC-16/CCITT-FALSE's check value


# --- frames ------------------------------------------------------------------------------------

def test_whole_frames_with_their_crc_are_handed_on_intact():
    events, _, _ = run_target([frame(f) for f in GOOD])
    assert events == [(int.from_bytes(f[:8], "big"), 1) for f in GOOD]
    assert [payload >> 56 for payload, _ in events] == [0, 0x5A, 0xFF, 0x01]   # seq on top


def test_any_single_bit_flipped_makes_a_frame_not_intact():
    """All 80 bits, one at a time (then a whole frame, intact again): the payload is still the
    first 64 bits as received."""
    good = to_bits(GOOD[3])
    flipped = [good[:i] + [1 - good[i]] + good[i + 1:] for i in range(FRAME_BITS)]
    transactions = [{"bits": bits} for bits in flipped] + [{"bits": good}]
    events, _, _ = run_target(transactions, idle=2)
    assert events == [(to_word(bits[:64]), 0) for bits in flipped] + [(to_word(good[:64]), 1)]


@pytest.mark.parametrize("n", [0, 1, 8, 16, 17, 48, 63, 64, 65, 72, 79, 81, 88, 96, 160])
def test_frames_of_other_lengths_are_not_intact_even_when_their_crc_holds(n):
    """n bits whose CRC holds (any bits, under 16): only the length refuses them; the next
    whole frame is intact again."""
    bits = checked([(0x5A3C >> (i % 16)) & 1 for i in range(n - 16)]) if n >= 16 else [1] * n
    assert n < 16 or crc_bits(bits) == 0
    events, _, _ = run_target([{"bits": bits}, frame(GOOD[0])])
    assert same(events, [frame_event(bits), frame_event(to_bits(GOOD[0]))])
    assert [intact for _, intact in events] == [0, 1]


@pytest.mark.parametrize("n", [0, 1, 8, 32, 63, 64, 72, 79])
def test_a_frame_cut_short_is_not_intact(n):
    bits = to_bits(GOOD[1])[:n]
    events, _, _ = run_target([{"bits": bits}, frame(GOOD[1])])
    assert same(events, [(None, 0), (int.from_bytes(GOOD[1][:8], "big"), 1)])
    assert same(events, [frame_event(bits), frame_event(to_bits(GOOD[1]))])


@pytest.mark.parametrize("extra", [[0], [1], [0] * 8, [0, 1] * 8, [0] * 80])
def test_a_frame_run_over_is_not_intact(extra):
    """A whole frame with bits after it: with zeros after it its CRC still holds, so only the
    length refuses it. The payload is still its first 64 bits."""
    bits = to_bits(GOOD[2]) + extra
    events, _, _ = run_target([{"bits": bits}, frame(GOOD[2])])
    payload = int.from_bytes(GOOD[2][:8], "big")
    assert events == [(payload, 0), (payload, 1)]


@pytest.mark.parametrize("half", [HALF, HALF + 1, 10, 25])
def test_sck_at_clk_over_12_and_slower(half):
    transactions = [frame(GOOD[1], answer=(0x12, 0x34, 0x5678)), frame(GOOD[3]),
                    {"bits": to_bits(GOOD[0])[:50]}]
    events, cipo, _ = check(transactions, half=half)
    assert [intact for _, intact in events] == [1, 1, 0]
    assert parse_answer(to_bytes(cipo[0][:ANSWER_BITS])) == (0x12, 0x34, 0x5678)


@pytest.mark.parametrize("take", [1, 5, 30])
def test_a_frame_event_is_held_until_taken(take):
    """The consumer takes each event late: it holds, unchanged, and is handed on once."""
    transactions = [frame(GOOD[0]), {"bits": to_bits(GOOD[1])[:20]}, frame(GOOD[1])]
    check(transactions, idle=take + 10, take=take)


# --- answers on CIPO -----------------------------------------------------------------------------

def test_replies_ready_is_high_exactly_between_frames():
    """``ready`` is high exactly while no frame is being clocked: it is ``cs_n`` as the target
    sees it (:data:`SEEN` clocks late), whatever the answer lines do, through frames of every
    length down to one clock and gaps down to one clock."""
    pattern = ([1] * 6 + [0] + [1] + [0] * 2 + [1] * 2 + [0] * 3 + [1] * 3 + [0] * 4 + [1] * 4
               + [0] * 30 + [1] * 5 + [0] + [1] * 2 + [0] * 5 + [1] * 8)
    dut = SPITarget()
    readies = []

    async def bench(ctx):
        for n, level in enumerate(pattern):
            ctx.set(dut.cs_n, level)
            ctx.set(dut.replies.valid, n % 3 != 1)
            ctx.set(dut.replies.payload, {"tag": n, "code": n, "data": n})
            readies.append(ctx.get(dut.replies.ready))
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert readies == [1] * SEEN + pattern[:-SEEN]


def test_an_answer_goes_out_during_the_next_frame_then_zeros():
    transactions = [frame(GOOD[1]), frame(GOOD[1], answer=(0x5A, 0x01, 0xBEEF)), frame(GOOD[1]),
                    frame(GOOD[1])]
    events, cipo, taken = check(transactions)
    assert taken == [True]
    assert cipo[0] == [0] * FRAME_BITS                          # nothing waiting: zeros
    assert parse_answer(to_bytes(cipo[1][:ANSWER_BITS])) == (0x5A, 0x01, 0xBEEF)
    assert cipo[1][:ANSWER_BITS] == to_bits(answer_bytes(0x5A, 0x01, 0xBEEF))   # MSB first
    assert cipo[1][ANSWER_BITS:] == [0] * (FRAME_BITS - ANSWER_BITS)
    assert cipo[2] == [0] * FRAME_BITS and cipo[3] == [0] * FRAME_BITS  # sent once
    assert parse_answer(to_bytes(cipo[2][:ANSWER_BITS])) is None   # zeros: never an answer
    assert [intact for _, intact in events] == [1] * 4


@pytest.mark.parametrize("answer", [(0, 0, 0), (0xFF, 0xFF, 0xFFFF), (0x80, 0x01, 0x0001),
                                    (0x01, 0x84, 0x8000)])
def test_answers_of_extreme_values(answer):
    _, cipo, _ = check([frame(GOOD[0], answer=answer)])
    assert parse_answer(to_bytes(cipo[0][:ANSWER_BITS])) == answer
    assert cipo[0][ANSWER_BITS:] == [0] * (FRAME_BITS - ANSWER_BITS)


@pytest.mark.parametrize("wait", [0, 1, 60])
def test_an_answer_waits_for_the_next_frame_and_goes_out_once(wait):
    """Offered for one clock, however long before the frame (the answer lines carry junk
    after it)."""
    transactions = [frame(GOOD[0]), frame(GOOD[0], answer=(1, 2, 3), wait=wait),
                    frame(GOOD[0])]
    _, cipo, taken = check(transactions, idle=20)
    assert taken == [True]
    assert parse_answer(to_bytes(cipo[1][:ANSWER_BITS])) == (1, 2, 3)
    assert cipo[0] == [0] * FRAME_BITS and cipo[2] == [0] * FRAME_BITS


@pytest.mark.parametrize("wait", [0, 5])
def test_a_newer_answer_replaces_one_not_yet_sent(wait):
    """Several offered between two frames: the last goes out, once."""
    transactions = [frame(GOOD[0]),
                    frame(GOOD[0], answers=[(1, 2, 3), (4, 5, 6), (7, 8, 9)], wait=wait),
                    frame(GOOD[0])]
    _, cipo, taken = check(transactions)
    assert taken == [True] * 3
    assert parse_answer(to_bytes(cipo[1][:ANSWER_BITS])) == (7, 8, 9)
    assert cipo[2] == [0] * FRAME_BITS


@pytest.mark.parametrize("idle", [1, 2, 3, 4])
def test_an_answer_offered_before_the_target_has_seen_a_frame_end_is_not_taken(idle):
    """Offered on each clock from ``cs_n`` rising: not taken (``ready`` low) until the target
    has seen the frame end; then the last one taken goes out in the next frame."""
    answers = [(0x10 + k, 0x20 + k, 0x3040 + k) for k in range(4)]
    transactions = [frame(GOOD[0]), frame(GOOD[0], answers=answers), frame(GOOD[0])]
    _, cipo, taken = check(transactions, idle=idle)
    assert taken == [idle + k >= SEEN for k in range(4)]
    assert parse_answer(to_bytes(cipo[1][:ANSWER_BITS])) == answers[-1]


@pytest.mark.parametrize("clocks", [0, 1, 2, 3, 4])
def test_an_answer_offered_as_a_frame_starts(clocks):
    """Offered ``clocks`` after ``cs_n`` falls: until the target has seen it fall (the clock
    it starts the frame on included), taken, and it goes out in that frame, in place of the one
    waiting; after, not taken, and the one waiting goes out unharmed."""
    transactions = [frame(GOOD[0]), frame(GOOD[0], answer=(1, 2, 3), start=(clocks, (4, 5, 6))),
                    frame(GOOD[0])]
    _, cipo, taken = check(transactions)
    assert taken == [True, clocks < SEEN]
    assert parse_answer(to_bytes(cipo[1][:ANSWER_BITS])) == ((4, 5, 6) if clocks < SEEN else
                                                             (1, 2, 3))
    assert cipo[2] == [0] * FRAME_BITS


@pytest.mark.parametrize("clocks", [0, 1, 2, 3])
def test_an_answer_offered_as_a_frame_starts_after_a_short_gap(clocks):
    """``cs_n`` high for two clocks only (one answer offered in them, too soon: not taken):
    the target sees the frame end only two clocks late, so an answer offered on the clock
    ``cs_n`` falls comes while the last frame is still being clocked (not taken); one or two
    clocks after, between the two frames as the target sees them (taken, and it goes out)."""
    transactions = [frame(GOOD[0]), frame(GOOD[0], answer=(1, 2, 3), start=(clocks, (4, 5, 6))),
                    frame(GOOD[0])]
    _, cipo, taken = check(transactions, idle=1)
    assert taken == [False, clocks in (1, 2)]
    assert cipo[1] == (to_bits(answer_bytes(4, 5, 6)) + [0] * (FRAME_BITS - ANSWER_BITS)
                       if clocks in (1, 2) else [0] * FRAME_BITS)
    assert cipo[2] == [0] * FRAME_BITS


@pytest.mark.parametrize("at", [0, 1, 40, 47, 48, 79, 80])
def test_an_answer_offered_during_a_frame_is_not_taken(at):
    """``ready`` is low: the answer goes out neither in that frame (the one being sent goes
    on unharmed) nor in the next; the decoder counts it lost."""
    transactions = [frame(GOOD[0], answer=(1, 2, 3), late=(at, (0x10, 0x20, 0x3040))),
                    frame(GOOD[0]), frame(GOOD[0])]
    _, cipo, taken = check(transactions)
    assert taken == [True, False]
    assert cipo[0] == to_bits(answer_bytes(1, 2, 3)) + [0] * (FRAME_BITS - ANSWER_BITS)
    assert cipo[1] == [0] * FRAME_BITS and cipo[2] == [0] * FRAME_BITS


@pytest.mark.parametrize("n", [0, 1, 10, 32, 40, 47])
def test_an_answer_is_cut_off_by_a_short_frame_and_not_sent_again(n):
    """Cut in its data or in its CRC (or taken by an empty frame): what went out is the
    answer's first bits, and it does not go out again."""
    answer = (0xF0, 0x0F, 0xA5C3)
    transactions = [{"bits": [1] * n, "answers": [answer]}, frame(GOOD[0])]
    events, cipo, _ = check(transactions)
    assert cipo[0] == to_bits(answer_bytes(*answer))[:n] and cipo[1] == [0] * FRAME_BITS
    assert [intact for _, intact in events] == [0, 1]


def test_cipo_after_the_answer_in_a_long_frame_is_zero():
    answer = (0xFF, 0xFF, 0xFFFF)
    transactions = [{"bits": [1] * 120, "answers": [answer]}]
    events, cipo, _ = check(transactions)
    assert cipo[0] == to_bits(answer_bytes(*answer)) + [0] * (120 - ANSWER_BITS)
    assert events == [(2 ** 64 - 1, 0)]


# --- cs_n glitches --------------------------------------------------------------------------------

@pytest.mark.parametrize("at", [1, 40, 64, 79])
@pytest.mark.parametrize("clocks", [1, 2, 5])
def test_a_cs_n_glitch_splits_a_frame_into_two_not_intact(at, clocks):
    """The answer goes out in the first part only; the next whole frame is intact again."""
    transactions = [frame(GOOD[3], glitch=(at, clocks), answer=(0xCA, 0xFE, 0xF00D)),
                    frame(GOOD[0])]
    events, cipo, _ = check(transactions)
    assert [intact for _, intact in events] == [0, 0, 1]
    sent = to_bits(answer_bytes(0xCA, 0xFE, 0xF00D)) + [0] * FRAME_BITS
    assert cipo[0] == sent[:at] + [0] * (FRAME_BITS - at)


def test_a_cs_n_pulse_before_any_clock_is_an_empty_frame():
    """It takes the waiting answer (and cuts it off at no bits); the whole frame after it is
    intact, and sends zeros. An answer offered during the pulse's frame (before the pulse) is
    not taken: the next sends zeros too."""
    transactions = [frame(GOOD[2], glitch=(0, 2), answer=(1, 2, 3)),
                    frame(GOOD[2], glitch=(0, 2), late=(0, (4, 5, 6)))]
    events, cipo, taken = check(transactions)
    payload = int.from_bytes(GOOD[2][:8], "big")
    assert same(events, [(None, 0), (payload, 1), (None, 0), (payload, 1)])
    assert taken == [True, False]
    assert cipo == [[0] * FRAME_BITS] * 2


# --- random transactions -----------------------------------------------------------------------

bit_list = st.lists(st.integers(0, 1), max_size=100)
good_frame = st.builds(command, st.integers(0, 255), st.integers(0, 255), st.integers(0, 0xFFFF),
                       st.integers(0, 0xFFFF), st.integers(0, 0xFFFF)).map(to_bits)
flipped_frame = st.tuples(good_frame, st.integers(0, FRAME_BITS - 1)).map(
    lambda f: f[0][:f[1]] + [1 - f[0][f[1]]] + f[0][f[1] + 1:])
cut_short = st.tuples(good_frame, st.integers(0, FRAME_BITS - 1)).map(lambda f: f[0][:f[1]])
run_over = st.tuples(good_frame, st.lists(st.integers(0, 1), min_size=1, max_size=8)).map(
    lambda f: f[0] + f[1])
an_answer = st.tuples(st.integers(0, 255), st.integers(0, 255), st.integers(0, 0xFFFF))

transaction = st.fixed_dictionaries({
    "bits": st.one_of(good_frame, good_frame, flipped_frame, cut_short, run_over, bit_list),
    "answers": st.one_of(st.just([]), st.lists(an_answer, min_size=1, max_size=1),
                         st.lists(an_answer, min_size=2, max_size=3)),
    "wait": st.sampled_from([0, 0, 1, 5]),
    "start": st.one_of(st.none(), st.none(), st.none(),
                       st.tuples(st.integers(0, SEEN + 1), an_answer)),
}).flatmap(lambda t: st.fixed_dictionaries({
    "glitch": st.one_of(st.none(), st.none(), st.tuples(st.integers(0, len(t["bits"])),
                                                        st.integers(1, 4))),
    "late": st.one_of(st.none(), st.none(), st.tuples(st.integers(0, len(t["bits"])),
                                                      an_answer)),
}).map(lambda extra: {**t, **extra}))


@settings(max_examples=40, deadline=None)
@given(st.lists(transaction, min_size=1, max_size=4), st.sampled_from([HALF, HALF, 9]),
       st.integers(1, 20))
def test_random_transactions_against_the_model(transactions, half, idle):
    """Whole frames, damaged, cut short and run over, random bit strings, cs_n glitches,
    answers offered between frames (several, and as the target sees a frame end or start) and
    during them, at SCK = clk/12 or slower."""
    check(transactions, half=half, idle=idle)
