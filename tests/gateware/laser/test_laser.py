# amaranth: UnusedElaboratable=no
# (parameter checks build components without elaborating them)
"""The laser controller on its pins: Liao & Chen 2016's sequence, PRR accuracy, interlock,
watchdog, and fuzzed command streams with the interlock toggling, checked on every clock."""

import pytest
from amaranth.sim import Simulator
from hypothesis import HealthCheck, event, given, settings, strategies as st

from galvoscan.link.client import HostClient
from galvoscan.gateware.host.regmap import STATUS_BITS
from galvoscan.gateware.laser.controller import LaserController

from sim_board import QUICK_SIM_BOARD, SimBoard, SimUARTTransport, quick_board


CLK = 4e6


def test_bad_parameters():
    with pytest.raises(ValueError, match="mo_lead must be a positive time"):
        LaserController(clk_freq=CLK, mo_lead=0)
    with pytest.raises(ValueError, match="latch_pulse must be a positive time"):
        LaserController(clk_freq=CLK, latch_pulse=-1e-6)


def run_controller(script, cycles):
    """Run ``script`` against a controller (5 ms lead at 4 MHz); record the pins every clock."""
    dut = LaserController(clk_freq=CLK)
    sim = Simulator(dut)
    sim.add_clock(1 / CLK)
    pins = []

    async def watch(ctx):
        for _ in range(cycles):
            pins.append({name: ctx.get(getattr(dut, f"laser_{name}"))
                         for name in ("power", "latch", "mo", "am", "prr", "enable")})
            await ctx.tick()

    async def drive(ctx):
        await script(ctx, dut)

    sim.add_testbench(watch)
    sim.add_testbench(drive, background=True)
    sim.run()
    return dut, pins


def edges(pins, name, level=1):
    return [i for i in range(1, len(pins))
            if pins[i][name] == level and pins[i - 1][name] != level]


def test_the_003_sequence_on_the_pins():
    disarm_at = 25_000

    async def script(ctx, dut):
        ctx.set(dut.interlock_open, 0)
        ctx.set(dut.power, 200)
        ctx.set(dut.prr, 600)                  # 60.0 kHz
        ctx.set(dut.watchdog_ms, 1000)
        ctx.set(dut.marking, 1)
        await ctx.tick().repeat(20)
        ctx.set(dut.arm, 1)
        await ctx.tick().repeat(disarm_at - 20)
        ctx.set(dut.arm, 0)

    dut, pins = run_controller(script, disarm_at + 200)
    us = CLK / 1e6                              # clocks per µs

    off = {"power": 0, "latch": 0, "mo": 0, "am": 0, "prr": 0, "enable": 0}
    # Nothing before arming; the buffers' enable rises with arm (and the interlock closed).
    assert all(p == off for p in pins[:21])
    assert pins[21]["enable"] == 1
    # Power first, then the latch pulse after ≥ 1 µs of set-up, ≥ 1 µs wide, ≥ 1 µs of hold.
    power_set = next(i for i, p in enumerate(pins) if p["power"] == 200)
    latch_up, = edges(pins, "latch", 1)
    latch_down, = edges(pins, "latch", 0)
    mo_up, = edges(pins, "mo", 1)
    assert latch_up - power_set >= 1 * us
    assert latch_down - latch_up >= 1 * us
    assert mo_up - latch_down >= 1 * us
    assert all(p["power"] == 200 for p in pins[power_set:disarm_at])
    # Modulation 5 ms after MO (and not a clock sooner).
    am_up, = edges(pins, "am", 1)
    assert am_up - mo_up == 5e-3 * CLK
    # PRR at 60 kHz, 50 % duty, measured on the pin while modulating.
    window = pins[am_up:disarm_at]
    rises = edges(window, "prr", 1)
    frequency = (len(rises) - 1) / ((rises[-1] - rises[0]) / CLK)
    assert frequency == pytest.approx(60e3, rel=1e-3)
    periods = [b - a for a, b in zip(rises, rises[1:])]
    assert max(periods) - min(periods) <= 1                 # one clock of jitter at most
    high = sum(p["prr"] for p in window[rises[0]:rises[-1]])
    assert high / (rises[-1] - rises[0]) == pytest.approx(0.5, abs=0.01)
    # Disarm: the enable, modulation, MO and the power pins drop on the same clock.
    am_down, = edges(pins, "am", 0)
    mo_down, = edges(pins, "mo", 0)
    enable_down, = edges(pins, "enable", 0)
    assert am_down == mo_down == enable_down
    assert pins[enable_down] == off and pins[-1] == off


def test_power_change_while_armed_is_latched_again():
    async def script(ctx, dut):
        ctx.set(dut.interlock_open, 0)
        ctx.set(dut.power, 10)
        ctx.set(dut.prr, 500)
        ctx.set(dut.watchdog_ms, 1000)
        await ctx.tick().repeat(5)
        ctx.set(dut.arm, 1)
        await ctx.tick().repeat(100)
        ctx.set(dut.power, 99)

    _, pins = run_controller(script, 200)
    assert len(edges(pins, "latch", 1)) == 2
    second_latch = edges(pins, "latch", 1)[1]
    changed = next(i for i, p in enumerate(pins) if p["power"] == 99)
    assert 0 < second_latch - changed <= 8
    assert pins[-1]["mo"] == 1                  # MO stays on through a power change


# --- the whole system, from host commands ---------------------------------------------------------

#: The system top the laser is tested in: the spiral, which runs from power-up and so makes
#: the laser emit once armed, and nothing else (no raster, vector or correction stage, which
#: the laser controller does not see), at 0.6 of the default build's cost a clock.
SPIRAL_ONLY = {"modes": ("spiral",), "correction": None}


def status_bits(client, *names):
    status = client.read("status")
    return {name: bool(status & (1 << STATUS_BITS[name])) for name in names}


def test_spiral_and_laser_from_host_commands():
    # A tenth of the paper's 5 ms MO lead (the top's default, below; the controller's 5 ms on
    # its pins: test_the_003_sequence_on_the_pins): the same sequence, a tenth of the clocks.
    # The default build, on the compiled board (held to Amaranth's simulator, laser pins and
    # all, by tests/sim/test_compiled.py), at the tests' quick board's 8 MHz.
    from galvoscan.gateware.top import GalvoScanTop
    assert GalvoScanTop(clk_freq=CLK).config.mo_lead == 5e-3
    lead = QUICK_SIM_BOARD["mo_lead"]
    assert lead == 0.5e-3
    board = quick_board(record_laser=True)
    clk = board.clk_freq
    client = HostClient(SimUARTTransport(board))
    client.write("laser_power", 128)
    client.write("laser_prr", 1000)             # 100 kHz
    start = len(board.laser_pins)
    client.write("arm", 1)
    board.run_for(lead + 1e-3)
    assert status_bits(client, "mo_on", "emitting", "running") == \
        {"mo_on": True, "emitting": True, "running": True}
    # Liao & Chen's sequence on the system's pins: power, latch pulse, MO, 5 ms, modulation.
    run = board.laser_pins[start:]
    power_set = next(i for i, p in enumerate(run) if p[5] == 128)
    latch_up = next(i for i, p in enumerate(run) if p[4])
    latch_down = next(i for i in range(latch_up, len(run)) if not run[i][4])
    mo_up = next(i for i, p in enumerate(run) if p[0])
    am_up = next(i for i, p in enumerate(run) if p[1])
    assert power_set < latch_up < latch_down < mo_up < am_up
    assert latch_up - power_set >= 1e-6 * clk and latch_down - latch_up >= 1e-6 * clk
    assert am_up - mo_up >= lead * clk
    # PRR on the pin during emission, and the pulse counter agrees with it.
    pulses_before = client.read("pulses")
    mark = len(board.laser_pins)
    board.run_for(1e-3)
    end = len(board.laser_pins)
    pulses_after = client.read("pulses")        # (counted when the read arrives: later)
    window = board.laser_pins[mark:end]
    rises = [i for i in range(1, len(window)) if window[i][2] and not window[i - 1][2]]
    frequency = (len(rises) - 1) / ((rises[-1] - rises[0]) / clk)
    assert frequency == pytest.approx(100e3, rel=2e-3)
    assert pulses_after - pulses_before >= len(rises)

    # Stopping the scan stops emission; MO stays on; starting again resumes it at once.
    client.write("run", 0)
    board.run_for(1e-4)
    assert status_bits(client, "mo_on", "emitting") == {"mo_on": True, "emitting": False}
    client.write("run", 1)
    board.run_for(1e-4)
    assert status_bits(client, "emitting")["emitting"]

    # The interlock opens: everything off within the two synchroniser clocks, and a fault
    # latches.
    mark = len(board.laser_pins)
    board.interlock_closed = False
    board.run_for(1e-4)
    assert_interlock_cuts_the_outputs(board.laser_pins[mark - 3:])
    assert status_bits(client, "fault_interlock", "mo_on", "interlock_open") == \
        {"fault_interlock": True, "mo_on": False, "interlock_open": True}
    # A clear while it is open does nothing; closed, it clears, but the laser waits for re-arm.
    client.write("fault_clear", 1)
    assert status_bits(client, "fault_interlock")["fault_interlock"]
    board.interlock_closed = True
    board.run_for(1e-4)
    client.write("fault_clear", 1)
    board.run_for(2e-3)
    assert status_bits(client, "fault_interlock", "mo_on") == \
        {"fault_interlock": False, "mo_on": False}
    client.write("arm", 0)
    client.write("arm", 1)
    board.run_for(lead + 1e-3)
    assert status_bits(client, "mo_on", "emitting") == {"mo_on": True, "emitting": True}


def assert_interlock_cuts_the_outputs(pins):
    """Every laser output is low from the third clock the interlock pin is open on (it passes
    two synchroniser flip-flops), and on every clock laser_enable is low."""
    for clock in range(3, len(pins)):
        mo, am, prr, _, latch, power, enable, *_ = pins[clock]
        if all(pins[clock - back][3] for back in range(3)):
            assert not (mo or am or prr or latch or power or enable), \
                f"laser on with the interlock open for 3 clocks (clock {clock})"
        if not enable:
            assert not (mo or am or prr or latch or power), "a laser output without enable"


def test_alarm_latches_a_fault_and_an_unconnected_alarm_blocks_arming():
    board = SimBoard(mo_lead=2e-4, record_laser=True, alarms_clear=False, **SPIRAL_ONLY)
    client = HostClient(SimUARTTransport(board))
    client.write("laser_power", 50)
    client.write("arm", 1)
    board.run_for(1e-3)
    # An alarm input pulled up (unconnected) reads as an alarm: nothing is enabled.
    assert status_bits(client, "alarm", "fault_alarm", "laser_enable", "mo_on") == \
        {"alarm": True, "fault_alarm": True, "laser_enable": False, "mo_on": False}
    assert not any(pins[0] or pins[6] for pins in board.laser_pins)
    # The laser's alarms clear: clear the fault, re-arm, and it emits.
    board.alarms_clear = True
    board.run_for(1e-5)
    client.write("fault_clear", 1)
    client.write("arm", 0)
    client.write("arm", 1)
    board.run_for(1e-3)
    assert status_bits(client, "fault_alarm", "laser_enable", "emitting") == \
        {"fault_alarm": False, "laser_enable": True, "emitting": True}
    # An alarm while emitting: off within the synchroniser, latched, held after it clears.
    mark = len(board.laser_pins)
    board.alarms_clear = False
    board.run_for(1e-5)
    board.alarms_clear = True
    board.run_for(1e-4)
    pins = board.laser_pins[mark:]
    first = next(i for i, p in enumerate(pins) if p[7])
    assert all(not any(p[j] for j in (0, 1, 2, 4, 5, 6)) for p in pins[first + 2:])
    assert status_bits(client, "fault_alarm", "alarm", "emitting") == \
        {"fault_alarm": True, "alarm": False, "emitting": False}


@pytest.mark.parametrize("spans_an_edge", [False, True])
def test_interlock_glitch_reaches_the_outputs_only_with_a_fault(spans_an_edge):
    """A glitch on the interlock pin that no clock edge samples changes nothing; one that is
    sampled cuts the outputs and latches a fault (it cannot cut them and leave no fault)."""
    period = 1 / CLK

    async def script(ctx, dut):
        ctx.set(dut.interlock_open, 0)
        ctx.set(dut.alarm, 0)
        ctx.set(dut.power, 100)
        ctx.set(dut.prr, 500)
        ctx.set(dut.watchdog_ms, 60000)
        ctx.set(dut.marking, 1)
        await ctx.tick().repeat(5)
        ctx.set(dut.arm, 1)
        await ctx.tick().repeat(400)
        # A glitch a fifth of a clock long, between two edges or across one.
        await ctx.delay(period * (0.9 if spans_an_edge else 0.3))
        ctx.set(dut.interlock_open, 1)
        await ctx.delay(period * 0.2)
        ctx.set(dut.interlock_open, 0)

    dut = LaserController(clk_freq=CLK, mo_lead=50e-6, alarms=1)
    sim = Simulator(dut)
    sim.add_clock(period)
    pins, faults = [], []

    async def watch(ctx):
        for _ in range(600):
            pins.append((ctx.get(dut.laser_am), ctx.get(dut.laser_mo), ctx.get(dut.laser_enable)))
            faults.append(ctx.get(dut.faults.interlock))
            await ctx.tick()

    async def drive(ctx):
        await script(ctx, dut)

    sim.add_testbench(watch)
    sim.add_testbench(drive, background=True)
    sim.run()
    assert pins[400] == (1, 1, 1)
    cut = [i for i in range(400, 600) if pins[i] != (1, 1, 1)]
    if spans_an_edge:
        assert cut and faults[-1] == 1 and cut == list(range(cut[0], 600))
    else:
        assert not cut and faults[-1] == 0


def test_watchdog_switches_the_laser_off():
    board = SimBoard(mo_lead=2e-4, **SPIRAL_ONLY)
    client = HostClient(SimUARTTransport(board))
    client.write("watchdog", 2)                 # ms
    client.write("arm", 1)
    board.run_for(1e-3)
    assert status_bits(client, "emitting")["emitting"]
    board.run_for(3e-3)                         # the host falls silent
    assert status_bits(client, "fault_watchdog", "mo_on", "emitting") == \
        {"fault_watchdog": True, "mo_on": False, "emitting": False}


# --- fuzzed command streams with the interlock toggling --------------------------------------------

laser_writes = st.sampled_from([("arm", 1), ("arm", 0), ("laser_power", 0), ("fault_clear", 1),
                                ("run", 1), ("run", 0), ("laser_power", 77), ("watchdog", 1),
                                ("keepalive", 1)])
# Bytes that are no frame (a damaged one: refused, and while armed a link fault).
garbage = st.binary(min_size=1, max_size=12)


@settings(max_examples=24, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.one_of(laser_writes, garbage), st.booleans(), st.booleans(),
                          st.integers(0, 400)), min_size=3, max_size=12))
def test_fuzzed_commands_never_emit_unsafely(steps):
    lead = 100e-6
    board = SimBoard.powered_up(backend="compiled", mo_lead=lead, record_laser=True,
                                **SPIRAL_ONLY)
    link = SimUARTTransport(board)
    client = HostClient(link)
    client.write("arm", 1)                      # start armed, so emission is within reach
    for data, toggle_interlock, toggle_alarms, wait_us in steps:
        if toggle_interlock:
            board.interlock_closed = not board.interlock_closed
        if toggle_alarms:
            board.alarms_clear = not board.alarms_clear
        if isinstance(data, tuple):
            client.write(*data)
        else:
            link.send_bytes(data + b"\0")
        board.run_for(wait_us * 1e-6)
    board.run_for(2 * lead)

    lead_clocks = lead * CLK
    event("emitted" if any(pins[1] for pins in board.laser_pins) else "did not emit")
    assert_interlock_cuts_the_outputs(board.laser_pins)
    mo_on_for = 0
    for clock, (mo, am, prr, _, _, _, enable, alarm, guide) in enumerate(board.laser_pins):
        # The buffers are enabled only while armed, and the guide laser is off while armed.
        assert not (enable and guide), "guide laser on with the laser enabled"
        if clock >= 3 and all(board.laser_pins[clock - back][7] for back in range(3)):
            assert not (mo or am or prr or enable), "laser on with an alarm for 3 clocks"
        if am:
            assert mo and mo_on_for >= lead_clocks, "modulation before the MO lead"
        mo_on_for = mo_on_for + 1 if mo else 0


def test_status_block_counts_and_latches():
    """Saturating counters stop at 65535, wrapping ones go round, and a sticky flag stays set
    until status is read."""
    from amaranth.sim import Simulator
    from galvoscan.gateware.host.status import StatusBlock

    with pytest.raises(ValueError, match="distinct identifiers"):
        StatusBlock(saturating=["a"], wrapping=["a"])
    block = StatusBlock(saturating=["stops"], wrapping=["wraps"])

    async def testbench(ctx):
        ctx.set(block.counts.stops, 65534)      # not reachable from reset in a test's time
        ctx.set(block.counts.wraps, 65535)
        ctx.set(block.events.stops, 1)
        ctx.set(block.events.wraps, 1)
        await ctx.tick()
        assert (ctx.get(block.counts.stops), ctx.get(block.counts.wraps)) == (65535, 0)
        await ctx.tick()
        assert (ctx.get(block.counts.stops), ctx.get(block.counts.wraps)) == (65535, 1)
        ctx.set(block.events.stops, 0)
        ctx.set(block.events.wraps, 0)
        ctx.set(block.flags.clipped, 1)
        ctx.set(block.flags.armed, 1)
        assert ctx.get(block.status.armed) == 1           # a state: as it is now
        await ctx.tick()
        ctx.set(block.flags.clipped, 0)
        await ctx.tick()
        assert ctx.get(block.status.clipped) == 1         # an event: until status is read
        ctx.set(block.status_read, 1)
        await ctx.tick()
        assert ctx.get(block.status.clipped) == 0

    sim = Simulator(block)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()


def test_guide_laser_only_while_disarmed_and_ready_after_the_lead():
    """The guide laser follows its register while disarmed and goes off on arming; status
    says `laser_ready` once MO has led for the MO lead, not before."""
    board = SimBoard(mo_lead=1e-3, record_laser=True, **SPIRAL_ONLY)
    client = HostClient(SimUARTTransport(board))
    client.write("guide", 1)
    board.run_for(2e-6)
    assert board.top_pin("laser_guide") == 1
    client.write("arm", 1)
    armed_at = len(board.laser_pins)
    board.run_for(1e-4)
    # Off within a clock of arming (the register write), and the laser not ready yet.
    assert board.top_pin("laser_guide") == 0
    assert status_bits(client, "laser_enable", "laser_ready") == \
        {"laser_enable": True, "laser_ready": False}
    board.run_for(1e-3)
    assert status_bits(client, "laser_ready") == {"laser_ready": True}
    client.write("arm", 0)
    board.run_for(2e-6)
    assert status_bits(client, "laser_ready") == {"laser_ready": False}
    assert board.top_pin("laser_guide") == 1           # the register still asks for it
    assert armed_at > 0
