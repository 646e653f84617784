"""Test-side XY2-100 reader, written from the XY2-100 protocol as scan heads read it,
independent of the gateware and the CLI.

A simulation testbench records every system clock's wire levels (or just the falling-edge
samples); the functions here turn those recordings into frames and check the protocol's timing.
"""

from amaranth.sim import Simulator


SYNC_PATTERN = "1" * 19 + "0"


def record_falling_edges(dut, clk_freq, *, frames, extra_testbench=None, vcd=None):
    """Simulate ``dut`` from power-up; return ``(sync, x, y)`` sampled at each falling
    ``xy2_clk`` edge until ``frames`` parity bits (SYNC low) have been seen."""
    sim = Simulator(dut)
    sim.add_clock(1 / clk_freq)
    samples = []

    async def scan_head(ctx):
        parity_bits = 0
        async for _, sync, x, y in ctx.negedge(dut.xy2_clk).sample(
                dut.xy2_sync, dut.xy2_x, dut.xy2_y):
            samples.append((sync, x, y))
            parity_bits += not sync
            if parity_bits == frames:
                return

    sim.add_testbench(scan_head)
    if extra_testbench is not None:
        sim.add_testbench(extra_testbench, background=True)
    if vcd:
        with sim.write_vcd(vcd):
            sim.run()
    else:
        sim.run()
    return samples


def frames_from_samples(samples, *, control="001"):
    """Split falling-edge samples into frames and decode them.

    Every frame must be exactly the SYNC pattern 1×19 then 0, with the expected control bits
    and even parity; nothing may come between frames. Returns a list of ``(x, y)``.
    """
    sync = "".join(str(s) for s, _, _ in samples)
    x_bits = "".join(str(x) for _, x, _ in samples)
    y_bits = "".join(str(y) for _, _, y in samples)
    assert len(sync) % 20 == 0, f"{len(sync)} bits is not a whole number of frames"
    frames = []
    for start in range(0, len(sync), 20):
        assert sync[start:start + 20] == SYNC_PATTERN, \
            f"frame {start // 20}: SYNC {sync[start:start + 20]}"
        decoded = []
        for axis, bits in (("X", x_bits), ("Y", y_bits)):
            word = bits[start:start + 20]
            assert word[:3] == control, f"frame {start // 20} {axis}: control bits {word[:3]}"
            assert word.count("1") % 2 == 0, f"frame {start // 20} {axis}: odd parity {word}"
            decoded.append(int(word[3:19], 2))
        frames.append(tuple(decoded))
    return frames
