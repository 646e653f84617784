"""The register bus arbiter (gateware/host/bus_arbiter.py): the host first, the player on the
clocks between, and a host's write of arm, run or mode seen."""

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.host.bus_arbiter import BusArbiter
from galvoscan.gateware.host.regmap import BY_NAME


ADDRESSES = [BY_NAME[name].address for name in ("arm", "run", "mode", "pitch", "vec_op")]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.sampled_from(ADDRESSES), st.integers(0, 65535),
                          st.sampled_from(ADDRESSES), st.integers(0, 65535), st.booleans(),
                          st.booleans()), min_size=1, max_size=30))
def test_each_clock(clocks):
    dut = BusArbiter()

    async def testbench(ctx):
        previous = None
        for given_, host_address, host_data, player_address, player_data, \
                player_writes, write_ok in clocks:
            ctx.set(dut.host_given, given_)
            ctx.set(dut.host.address, host_address)
            ctx.set(dut.host.write_data, host_data)
            ctx.set(dut.player.address, player_address)
            ctx.set(dut.player.write_data, player_data)
            ctx.set(dut.bus.write_ok, write_ok)
            # Each side asks for its write on the clock after it gave it (the host's decoder
            # for a frame taken; the player only for a clock it was granted).
            host_en = previous is not None and previous[0]
            player_en = previous is not None and previous[1]
            ctx.set(dut.host.write_en, host_en)
            ctx.set(dut.player.write_en, player_en)
            assert ctx.get(dut.grant) == (not given_)
            assert ctx.get(dut.bus.address) == (host_address if given_ else player_address)
            assert ctx.get(dut.bus.write_data) == (host_data if given_ else player_data)
            assert ctx.get(dut.bus.write_en) == (host_en or player_en)
            assert ctx.get(dut.host.write_ok) == ctx.get(dut.player.write_ok) == write_ok
            takes = previous is not None and previous[2] in ADDRESSES[:3]
            assert ctx.get(dut.host_took_over) == (host_en and write_ok and takes)
            previous = (given_, (not given_) and player_writes, host_address)
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
