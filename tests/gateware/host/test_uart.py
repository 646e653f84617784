# amaranth: UnusedElaboratable=no
"""The UART receiver and transmitter alone (gateware/host/uart.py), against a model of the 8N1
line written here: idle high, a low start bit, eight data bits least significant first, a high
stop bit, each one bit time (``divisor`` system clocks) long."""

from amaranth.sim import Simulator
from hypothesis import example, given, settings, strategies as st
import pytest

from galvoscan.gateware.host.uart import UARTReceiver, UARTTransmitter, uart_divisor


# --- the line model ------------------------------------------------------------------------------

def character_bits(byte, *, stop=1):
    """Line levels of one 8N1 character: start, data LSB first, stop."""
    return [0] + [(byte >> i) & 1 for i in range(8)] + [stop]


def line_segments(events, divisor, *, skew=0.0):
    """(level, clocks) runs of the line for a list of events, the sender's bit time being
    ``divisor * (1 + skew)`` clocks (edges rounded to the nearest clock):

    * ``("byte", value, idle_bits, bad_stop)``: ``idle_bits`` of idle line, then the character
      (with a low stop bit if ``bad_stop``; the line then returns high);
    * ``("glitch", clocks, idle_bits)``: idle, then the line low for ``clocks`` clocks;
    * ``("break", bits, idle_bits)``: idle, then the line low for ``bits`` bit times.
    """
    bit = divisor * (1 + skew)
    levels = []                     # (level, length in sender's bits, or clocks if int-tagged)
    for event in events:
        kind = event[0]
        if kind == "byte":
            _, value, idle, bad_stop = event
            levels.append((1, idle))
            levels += [(b, 1) for b in character_bits(value, stop=0 if bad_stop else 1)]
        elif kind == "glitch":
            _, clocks, idle = event
            levels.append((1, idle))
            levels.append((0, ("clocks", clocks)))
        elif kind == "break":
            _, bits, idle = event
            levels.append((1, idle))
            levels.append((0, bits))
    levels.append((1, 3))           # idle at the end, long enough for the last byte to land
    segments, t, edge = [], 0.0, 0
    for level, length in levels:
        if isinstance(length, tuple):
            t += length[1]
        else:
            t += length * bit
        end = round(t)
        if end > edge:
            if segments and segments[-1][0] == level:
                segments[-1][1] += end - edge
            else:
                segments.append([level, end - edge])
            edge = end
    return segments


def model_receiver(events):
    """What a receiver must make of the events: the bytes, and the number of framing errors."""
    received, errors = [], 0
    for event in events:
        if event[0] == "byte":
            if event[3]:
                errors += 1
            else:
                received.append(event[1])
        elif event[0] == "break":
            errors += 1
        # A glitch (shorter than half a bit) is nothing.
    return received, errors


def decode_line(samples, divisor):
    """Characters read off a line sampled once per clock, checking that every bit lasts exactly
    ``divisor`` clocks and the stop bit at least that: (start clock, byte) per character."""
    chars = []
    i = 0
    assert samples[0] == 1, "the line must start idle"
    while True:
        try:
            i = samples.index(0, i)
        except ValueError:
            return chars
        start = i
        levels = []
        for n in range(10):
            run = samples[start + n * divisor:start + (n + 1) * divisor]
            assert len(run) == divisor, "line ends mid-character"
            assert len(set(run)) == 1, f"bit {n} of the character at clock {start} wobbles"
            levels.append(run[0])
        assert levels[0] == 0 and levels[9] == 1, f"bad framing at clock {start}: {levels}"
        chars.append((start, sum(b << k for k, b in enumerate(levels[1:9]))))
        i = start + 10 * divisor


# --- uart_divisor ---------------------------------------------------------------------------------

@pytest.mark.parametrize("clk_freq, baud, divisor", [
    (12e6, 115_200, 104),         # 104.17: 0.16 % fast
    (12e6, 1_000_000, 12),
    (4e6, 115_200, 35),           # 34.72 rounds up: 0.8 % slow
    (48e6, 3_000_000, 16),
    (8e6, 1_000_000, 8),          # the fewest clocks allowed
])
def test_divisor(clk_freq, baud, divisor):
    assert uart_divisor(clk_freq, baud) == divisor


@pytest.mark.parametrize("clk_freq, baud, message", [
    (12e6, 2_000_000, "at least 8"),         # 6 clocks per bit
    (12e6, 1_500_000, None),                 # exactly 8: fine
    (4e6, 460_800, "off"),                   # 8.68 → 9: 3.5 % off
    (12e6, 0, "positive"),
    (12e6, -9600, "positive"),
])
def test_divisor_refusals(clk_freq, baud, message):
    if message is None:
        assert uart_divisor(clk_freq, baud) == 8
    else:
        with pytest.raises(ValueError, match=message):
            uart_divisor(clk_freq, baud)


@pytest.mark.parametrize("cls, divisor", [(UARTReceiver, 7), (UARTReceiver, 8.0),
                                          (UARTTransmitter, 1)])
def test_constructor_refuses_bad_divisors(cls, divisor):
    with pytest.raises(ValueError, match="divisor"):
        cls(divisor=divisor)


# --- receiver -------------------------------------------------------------------------------------

def run_receiver(events, divisor, *, skew=0.0, ready=True):
    """Drive the receiver's line with the events; returns (bytes taken, framing error pulses,
    the stream's final valid and payload)."""
    dut = UARTReceiver(divisor=divisor)
    got, errors = [], [0]
    final = {}

    async def drive(ctx):
        ctx.set(dut.bytes.ready, ready)
        for level, clocks in line_segments(events, divisor, skew=skew):
            ctx.set(dut.rx, level)
            await ctx.tick().repeat(clocks)
        await ctx.tick().repeat(4)
        final["valid"] = ctx.get(dut.bytes.valid)
        final["payload"] = ctx.get(dut.bytes.payload)

    async def monitor(ctx):
        async for _, _, valid, payload, framing_error in ctx.tick().sample(
                dut.bytes.valid, dut.bytes.payload, dut.framing_error):
            if valid and ready:
                got.append(payload)
            errors[0] += framing_error

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(drive)
    sim.add_testbench(monitor, background=True)
    sim.run()
    return got, errors[0], final


@pytest.mark.parametrize("divisor", [8, 9, 13, 104])
def test_receiver_takes_bytes_at_the_divisor(divisor):
    values = [0x00, 0xFF, 0x55, 0xAA, 0x01, 0x80, 0x64, 0x3C]
    # Back to back (no idle between a stop bit and the next start bit), then spaced.
    events = [("byte", v, 0 if i else 2, False) for i, v in enumerate(values)]
    events += [("byte", v, 1.5 + i, False) for i, v in enumerate(values[:3])]
    got, errors, _ = run_receiver(events, divisor)
    assert got == values + values[:3]
    assert errors == 0


@pytest.mark.parametrize("divisor", [8, 16])
@pytest.mark.parametrize("skew", [-0.02, 0.02])
def test_receiver_tolerates_a_sender_2_percent_off(divisor, skew):
    values = [0x00, 0xFF, 0x7F, 0xFE, 0x81]
    got, errors, _ = run_receiver([("byte", v, 0, False) for v in values], divisor, skew=skew)
    assert got == values and errors == 0


def test_bad_stop_bit_drops_the_byte_and_reports_it_once():
    events = [("byte", 0x12, 1, False), ("byte", 0x34, 0, True), ("byte", 0x56, 1, False),
              ("byte", 0xFF, 0, True), ("byte", 0x00, 1, True), ("byte", 0x78, 1, False)]
    got, errors, _ = run_receiver(events, 10)
    assert got == [0x12, 0x56, 0x78]
    assert errors == 3


@pytest.mark.parametrize("bits", [10, 11, 25, 200])
def test_break_is_one_framing_error_and_no_byte(bits):
    """The line held low for a character time or more: one error, then the receiver waits for
    the line to go high and takes the next byte."""
    events = [("byte", 0xA5, 1, False), ("break", bits, 2), ("byte", 0x5A, 1, False)]
    got, errors, _ = run_receiver(events, 12)
    assert got == [0xA5, 0x5A]
    assert errors == 1


@pytest.mark.parametrize("divisor", [8, 12, 104])
def test_glitches_shorter_than_half_a_bit_are_ignored(divisor):
    events = [("byte", 0x11, 1, False)]
    for clocks in range(1, divisor // 2):
        events.append(("glitch", clocks, 1))
    events += [("byte", 0x22, 1, False), ("glitch", divisor // 2 - 1, 0.3),
               ("byte", 0x33, 0.6, False)]
    got, errors, _ = run_receiver(events, divisor)
    assert got == [0x11, 0x22, 0x33]
    assert errors == 0


def test_a_byte_not_taken_is_replaced_by_the_next():
    events = [("byte", 0x12, 1, False), ("byte", 0x34, 1, False)]
    _, _, final = run_receiver(events, 8, ready=False)
    assert final == {"valid": 1, "payload": 0x34}


event = st.one_of(
    st.tuples(st.just("byte"), st.integers(0, 255), st.sampled_from([0, 0, 0.5, 1, 3]),
              st.booleans()),
    st.tuples(st.just("glitch"), st.integers(1, 3), st.sampled_from([0.5, 1, 2])),
    st.tuples(st.just("break"), st.integers(10, 30), st.sampled_from([1, 2])),
)


def well_formed(events):
    """After a bad stop bit or a break the line must be idle for at least a bit before the next
    start bit (else no receiver can tell where it is), and after a glitch for half a bit: a
    glitch that runs straight into a start bit is that start bit, begun early, to any receiver
    (hypothesis drew a 3-clock glitch at 8 clocks a bit, a byte right after it, the sender
    1.5 % slow: read 3 clocks early, the stop bit was sampled in the last data bit)."""
    out = []
    for ev in events:
        if out and (out[-1][0] == "break" or (out[-1][0] == "byte" and out[-1][3])):
            ev = ev[:2] + (max(ev[2], 1),) + ev[3:]
        elif out and out[-1][0] == "glitch":
            ev = ev[:2] + (max(ev[2], 0.5),) + ev[3:]
        out.append(ev)
    return out


@settings(max_examples=40, deadline=None)
@given(st.lists(event, min_size=1, max_size=10), st.sampled_from([8, 9, 11, 16]),
       st.floats(-0.015, 0.015))
@example([("glitch", 1, 0.5), ("byte", 0, 0, True), ("break", 14, 2), ("glitch", 3, 0.5),
          ("byte", 0, 0, False)], 8, 0.014735098806058472)
def test_receiver_against_the_model(events, divisor, skew):
    """Random bytes, back to back or spaced, bad stop bits, breaks and short glitches, from a
    sender up to 1.5 % off."""
    events = well_formed(events)
    got, errors, _ = run_receiver(events, divisor, skew=skew)
    assert (got, errors) == model_receiver(events)


# --- transmitter ----------------------------------------------------------------------------------

def run_transmitter(values, divisor, gaps):
    """Offer each value after ``gaps[i]`` clocks without valid; returns the line, one sample a
    clock, and the clocks at which each byte was taken."""
    dut = UARTTransmitter(divisor=divisor)
    samples, taken = [], []
    clock = [0]

    async def feed(ctx):
        for value, gap in zip(values, gaps):
            ctx.set(dut.bytes.valid, 0)
            if gap:
                await ctx.tick().repeat(gap)
            ctx.set(dut.bytes.valid, 1)
            ctx.set(dut.bytes.payload, value)
            await ctx.tick().until(dut.bytes.ready)
            taken.append(clock[0])
        ctx.set(dut.bytes.valid, 0)
        await ctx.tick().repeat(12 * divisor)

    async def monitor(ctx):
        async for _, _, tx in ctx.tick().sample(dut.tx):
            samples.append(tx)
            clock[0] += 1

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(feed)
    sim.add_testbench(monitor, background=True)
    sim.run()
    return samples, taken


@pytest.mark.parametrize("divisor", [2, 8, 13])
def test_transmitter_sends_8n1_at_the_divisor(divisor):
    values = [0x00, 0xFF, 0x55, 0xAA, 0x64, 0x80, 0x01]
    samples, _ = run_transmitter(values, divisor, [0] * len(values))
    chars = decode_line(samples, divisor)
    assert [b for _, b in chars] == values
    # Back to back: each character follows the last after its stop bit, with at most one clock
    # of extra idle.
    starts = [s for s, _ in chars]
    assert all(10 * divisor <= b - a <= 10 * divisor + 1 for a, b in zip(starts, starts[1:]))
    assert samples[-1] == 1


def test_transmitter_idles_high_and_waits_for_the_stop_bit():
    samples, taken = run_transmitter([0x0F, 0xF0], 8, [30, 100])
    assert samples[:30] == [1] * 30
    chars = decode_line(samples, 8)
    assert [b for _, b in chars] == [0x0F, 0xF0]
    # The second byte, offered long after, starts within a few clocks of being offered.
    assert chars[1][0] - taken[1] in range(0, 4)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 255), st.sampled_from([0, 0, 1, 5, 90])),
                min_size=1, max_size=6), st.sampled_from([8, 10, 13]))
def test_transmitter_to_receiver(pairs, divisor):
    """What the transmitter sends, with random pauses, the receiver (and the line model) reads
    back byte for byte."""
    values = [v for v, _ in pairs]
    samples, _ = run_transmitter(values, divisor, [g for _, g in pairs])
    assert [b for _, b in decode_line(samples, divisor)] == values
    runs = []
    for level in samples:
        if runs and runs[-1][0] == level:
            runs[-1][1] += 1
        else:
            runs.append([level, 1])

    dut = UARTReceiver(divisor=divisor)
    got = []

    async def drive(ctx):
        ctx.set(dut.bytes.ready, 1)
        for level, clocks in runs:
            ctx.set(dut.rx, level)
            await ctx.tick().repeat(clocks)
        await ctx.tick().repeat(4)

    async def monitor(ctx):
        async for _, _, valid, payload in ctx.tick().sample(dut.bytes.valid, dut.bytes.payload):
            if valid:
                got.append(payload)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(drive)
    sim.add_testbench(monitor, background=True)
    sim.run()
    assert got == values
