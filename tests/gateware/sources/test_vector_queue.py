# amaranth: UnusedElaboratable=no
"""The vector queue (gateware/sources/vector_queue.py) against a list: what goes in comes out
in order, each command's end point from the host's frame or from the registers, and the room
it reports."""

from amaranth.sim import Simulator
from hypothesis import example, given, settings, strategies as st

import pytest

from galvoscan.gateware.fields import VectorOp
from galvoscan.gateware.sources.vector_queue import VectorQueue


def run_queue(writes, *, depth, delays, take_every):
    """Push ``writes`` ((op, corner, segment, x, y) each), taking a command every
    ``take_every`` clocks; the commands out, the refusals and the free counts seen."""
    dut = VectorQueue(depth=depth, delays=delays)
    out, refused, free_seen = [], [], []

    async def testbench(ctx):
        pending = list(writes)
        clock = 0
        while pending or ctx.get(dut.empty) == 0:
            free_seen.append((ctx.get(dut.free), ctx.get(dut.empty)))
            ctx.set(dut.commands.ready, clock % take_every == 0)
            if pending:
                op, corner, segment, x, y = pending[0]
                ctx.set(dut.vec_op, {"op": VectorOp(op), "corner_frames": corner} if delays
                        else op)
                ctx.set(dut.segment, segment)
                # The frame's end point and the registers' differ: which one is queued shows.
                ctx.set(dut.segment_x, x if segment else x ^ 0xFFFF)
                ctx.set(dut.segment_y, y if segment else y ^ 0xFFFF)
                ctx.set(dut.vec_x, x ^ 0xFFFF if segment else x)
                ctx.set(dut.vec_y, y ^ 0xFFFF if segment else y)
                # The register file pushes only while there is room, and counts a refusal.
                if ctx.get(dut.ready):
                    ctx.set(dut.push, 1)
                    pending.pop(0)
                else:
                    ctx.set(dut.push, 0)
                    refused.append(clock)
            else:
                ctx.set(dut.push, 0)
            if ctx.get(dut.commands.valid) and ctx.get(dut.commands.ready):
                payload = ctx.get(dut.commands.payload)
                out.append((VectorOp(payload.op).value, payload.corner_frames if delays else 0,
                            payload.x, payload.y))
            await ctx.tick()
            clock += 1
            assert clock < 100_000

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return out, refused, free_seen


write = st.tuples(st.integers(0, 1), st.integers(0, 127), st.booleans(),
                  st.integers(0, 0xFFFF), st.integers(0, 0xFFFF))


@settings(max_examples=12, deadline=None)
@given(writes=st.lists(write, max_size=24), depth=st.integers(2, 8), delays=st.booleans(),
       take_every=st.integers(1, 4))
# A queue a slow sequencer fills, and one it keeps up with (nine writes, six places).
@example(writes=[(0, 0, False, 0, 0)] * 16, depth=4, delays=False, take_every=2)
@example(writes=[(0, 0, False, 0, 0)] * 9, depth=6, delays=False, take_every=2)
def test_the_queue_hands_on_every_write_in_order(writes, depth, delays, take_every):
    out, refused, free_seen = run_queue(writes, depth=depth, delays=delays,
                                        take_every=take_every)
    assert out == [(op, corner if delays else 0, x, y) for op, corner, _, x, y in writes]
    assert all(0 <= free <= depth for free, _ in free_seen)
    assert all((free == depth) == bool(empty) for free, empty in free_seen)
    # Offered one a clock and taken one every take_every clocks, the writes outrun the
    # sequencer by at least this many (less one the output may hold): past the depth, some
    # had to wait (were refused).
    outrun = len(writes) - -(-len(writes) // take_every) - 1
    if outrun > depth:
        assert refused


def test_a_depth_the_counters_cannot_hold_is_refused():
    with pytest.raises(ValueError, match="depth must be a whole number from 2"):
        VectorQueue(depth=1)
