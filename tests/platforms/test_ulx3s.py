"""The ULX3S board: its PLL against Trellis' own ecppll, its pins, its configuration, and the
bitstream with every feature."""

import re
import subprocess
from pathlib import Path

import pytest

from galvoscan.cli import main
from galvoscan.gateware.build_config import MODES
from galvoscan.platforms.pll import ecp5_pll_settings
from galvoscan.platforms.ulx3s import (ULX3S_CLOCK_HZ, ULX3S_PINS, ULX3SScanner,
                                       ulx3s_platform)


@pytest.mark.toolchain
@pytest.mark.parametrize("mhz", [20, 24, 40, 48, 60])
def test_pll_settings_make_what_ecppll_makes(mhz, tmp_path):
    """Trellis' ecppll (yowasp-ecppll) finds its own dividers; ours may differ from its, but
    must make the same frequency exactly within the PLL's limits (ecppll puts the output on
    CLKOP, ours on CLKOS with CLKOP as feedback, so that 24 and 48 MHz are exact too)."""
    from galvoscan.toolchain import tool, tool_env
    subprocess.run([tool("yowasp-ecppll"), "-i", "25", "-o", str(mhz), "-f", "pll.v"],
                   cwd=tmp_path, env=tool_env(), capture_output=True, text=True, check=True)
    verilog = (tmp_path / "pll.v").read_text()
    theirs = {key: int(value) for key, value in
              re.findall(r"\.(CLKI_DIV|CLKFB_DIV|CLKOP_DIV)\((\d+)\)", verilog)}
    their_mhz = 25 * theirs["CLKFB_DIV"] / theirs["CLKI_DIV"]
    ours = ecp5_pll_settings(25e6, mhz * 1e6)
    assert ours.f_out == mhz * 1e6
    assert ours.f_in / ours.clki_div * ours.clkfb_div * ours.clkop_div / ours.clkos_div \
        == mhz * 1e6
    assert 3.125e6 <= ours.f_pfd <= 400e6 and 400e6 <= ours.f_vco <= 800e6
    assert 3.125e6 <= ours.f_clkop <= 400e6
    if their_mhz == mhz:       # where ecppll is exact, its VCO is ours
        assert 25 / theirs["CLKI_DIV"] * theirs["CLKFB_DIV"] * theirs["CLKOP_DIV"] == \
            ours.f_vco / 1e6


def test_pll_refuses_what_it_cannot_make():
    with pytest.raises(ValueError, match="cannot make exactly 24.3 MHz"):
        ecp5_pll_settings(25e6, 24.3e6)
    with pytest.raises(ValueError, match="makes 3.125 to 400 MHz"):
        ecp5_pll_settings(25e6, 500e6)


def _header_sites():
    """``{"GP3": "B9", …}``: the header's pins on the ECP5's balls, from amaranth-boards."""
    connector = ulx3s_platform().connectors["gpio", 0]
    return {f"G{'P' if pin.endswith('+') else 'N'}{pin[:-1]}": site
            for pin, site in connector.mapping.items()}


def test_every_pin_is_on_the_header_once():
    headers = [pin for pin, _, _ in ULX3S_PINS.values()]
    assert len(set(headers)) == len(headers)
    assert set(headers) <= set(_header_sites())
    # Inputs and outputs, and "spare" for a pin kept for what is still to come (none now).
    assert {"i", "o"} <= {direction for _, direction, _ in ULX3S_PINS.values()} \
        <= {"i", "o", "spare"}


#: The build's LPF port names → ULX3S_PINS' names.
LPF_NAMES = [(r"xy2_0__(\w+)__io", r"xy2_\1"), (r"laser_0__(\w+)__io", r"laser_\1"),
             (r"host_spi_0__(\w+)__io", r"spi_\1"), (r"machine_0__(\w+)__io", r"\1"),
             (r"interlock_0__io", "interlock_open"), (r"laser_alarm_0__io", "laser_alarm"),
             (r"head_status_0__io", "xy2_status"), (r"encoder_0__(\w+)__io", r"encoder_\1"),
             (r"xy2_z_0__io", "xy2_z"), (r"io_in_0__io", "io_in"), (r"io_out_0__io", "io_out")]


def test_the_configuration_holds_every_feature():
    config = ULX3SScanner.config()
    assert config.clk_freq == ULX3S_CLOCK_HZ == 24e6
    assert config.modes == MODES and config.links == ("spi", "uart")
    assert all(config.capabilities().values()), config.capabilities()
    # XY2-100: 12 clocks a bit; 3 Mbaud: 8 clocks a bit, exactly.
    assert config.clocking.clocks_per_bit == 12
    assert config.baud == 3_000_000 and config.clocking.uart_divisor == 8
    # On a clock too slow for 3 Mbaud (the tests' 8 MHz), the fastest rate it carries.
    assert ULX3SScanner.config(clock=8e6).baud == 1_000_000


@pytest.mark.parametrize("argv, message", [
    (["--clock", "24.3e6"], "cannot make exactly 24.3 MHz"),
    (["--device", "25F"], "--device is the ULX3S's"),
    (["--preset", "marker"], "the marker preset is the iCEBreaker's"),
])
def test_build_refuses_in_one_line(argv, message):
    board = [] if "--device" in argv else ["--board", "ulx3s"]
    with pytest.raises(SystemExit, match=re.escape(message)) as refusal:
        main(["build", *board, *argv])
    assert "\n" not in str(refusal.value)


@pytest.mark.toolchain
@pytest.mark.xdist_group("ulx3s_build")
def test_build_ulx3s(ulx3s_build):
    """Every feature in one bitstream on the 25F: under half its LUT4s, and twice its clock."""
    folder, code, report = ulx3s_build
    assert code == 0, report
    assert report["board"] == "ulx3s" and report["device"] == "25F"
    bitstream = Path(report["bitstream"])
    assert bitstream.suffix == ".bit" and bitstream.stat().st_size > 100_000
    assert report["modes"] == list(MODES) and report["correction_nodes"] == 33
    assert report["player"] and report["links"] == ["spi", "uart"]
    assert report["luts_available"] == 24288
    assert 0 < report["luts"] <= 0.5 * report["luts_available"]
    assert report["clock_mhz"] == 24 and report["fmax_mhz"] >= 2 * 24
    assert report["baud"] == 3_000_000
    assert report["dsps"] > 0 and report["brams"] > 0
    # Each signal on the ball that ULX3S_PINS puts it on (amaranth-boards' map of the
    # header), and every signal of the table there.
    sites = _header_sites()
    placed = {}
    for port, site in re.findall(r'LOCATE COMP "([^"]+)" SITE "(\w+)"',
                                 (folder / "galvoscan_ulx3s.lpf").read_text()):
        for pattern, name in LPF_NAMES:
            if re.fullmatch(pattern + r"(\[\d+\])?", port):
                placed[re.sub(pattern, name, port)] = site
    assert placed == {name: sites[pin] for name, (pin, direction, _) in ULX3S_PINS.items()
                      if direction != "spare"}
    # nextpnr took the PLL's output for the system clock and timed it at 24 MHz.
    log = (folder / "galvoscan_ulx3s.tim").read_text()
    assert re.search(r"Derived frequency constraint of 24\.0+ MHz", log)
