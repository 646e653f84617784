"""The README stays true: its pin table, commands and proof list match the code."""

from pathlib import Path
import re

from amaranth_boards.icebreaker import ICEBreakerPlatform

from galvoscan.platforms.icebreaker import XY2_PMOD_PINS


ROOT = Path(__file__).parent.parent
README = (ROOT / "README.md").read_text()


def pmod1a_fpga_pin(pmod_pin):
    """FPGA pin of a PMOD1A pin, from amaranth-boards' iCEBreaker definition."""
    connector, = (c for c in ICEBreakerPlatform.connectors if (c.name, c.number) == ("pmod", 0))
    return int(connector.mapping[str(pmod_pin)])


def test_pin_table_matches_the_platform():
    rows = re.findall(r"^\| (\d+) \| (\d+) \| `xy2_(\w+)` \|$", README, re.M)
    assert {signal: int(pmod) for pmod, _, signal in rows} == XY2_PMOD_PINS
    for pmod, fpga, _ in rows:
        assert pmod1a_fpga_pin(pmod) == int(fpga)


def test_ci_runs_the_readme_test_command():
    commands = re.findall(r"```sh\n(.+?)\n```", README)
    assert len(commands) == 2
    ci = (ROOT / ".ci" / "run").read_text()
    assert commands[1] in ci
    assert "pytest -W error" in commands[1]
    assert "galvoscan build" in commands[0] and "galvoscan sim" in commands[0]


def test_pictures_exist():
    for picture in re.findall(r"\]\((docs/[^)]+\.png)\)", README):
        assert (ROOT / picture).is_file(), picture
