"""`galvoscan store`, `flash` and `standalone` (galvoscan/cli/standalone.py), and the flash
writer under `flash` (galvoscan/flashing/writer.py) driving pyspiflash into the W25Q128JV model
(and into the ISSI IS25LP128 some ULX3S revisions carry); the ULX3S's writer itself is
tests/flashing/test_ulx3s.py's."""

import json

import pyftdi.ftdi
import pytest
import spiflash.serialflash as serialflash

import galvoscan.flashing.ecp5
import galvoscan.flashing.icebreaker
import galvoscan.flashing.jtag
import galvoscan.flashing.writer
import galvoscan.sim.spi_flash as spi_flash
from galvoscan import flashing
from galvoscan.cli import main
from galvoscan.flashing import FlashingError, ModelPort, flash_regions, program
from galvoscan.gateware.player.image_format import JOB_OFFSET
from galvoscan.outputs.image import read_image
from galvoscan.sim.spi_flash import FLASH_BYTES, SPIFlashModel

from ecp5_jtag import ECP5, FakeFtdi, ecp5_bitstream
from issi_flash import SR_BP, SR_QE, IS25LPModel


SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10">
<rect x="1" y="1" width="6" height="3" fill="none" stroke="black"/>
<line x1="1" y1="8" x2="7" y2="8" stroke="black"/></svg>"""

BITSTREAM = b"\xff\x00GS\x00\xff" + b"\x7e\xaa\x99\x7e" + bytes(range(256)) * 300
#: The ULX3S's (an LFE5U-25F's, as ecppack lays it out).
ECP5_BITSTREAM = ecp5_bitstream(0x41111043, bytes(range(256)) * 20)


@pytest.fixture
def drawing(tmp_path):
    path = tmp_path / "part.svg"
    path.write_text(SVG)
    return path


class FakeClock:
    """pyspiflash's sleeps and clock, as the flash's own time: a write's waits cost nothing."""

    def __init__(self):
        self.now = 0.0

    def time(self):
        return self.now

    def monotonic(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


@pytest.fixture
def fast_flash(monkeypatch):
    clock = FakeClock()
    for module in (serialflash, flashing.writer, flashing.icebreaker, flashing.jtag,
                   flashing.ecp5):
        monkeypatch.setattr(module, "time", clock)
    return clock


def test_store_writes_what_mark_plans(drawing, tmp_path, capsys):
    image_path = tmp_path / "part.img"
    assert main(["mark", str(drawing), "--estimate", "--speed", "500"]) == 0
    planned = capsys.readouterr().out
    assert main(["store", str(drawing), "--speed", "500", "-o", str(image_path),
                 "--repeats", "3"]) == 0
    out = capsys.readouterr().out
    image = read_image(image_path.read_bytes())
    # The same plan, said the same way; the image ends on a jump, as the streamer sends it.
    assert planned.splitlines()[0] in out
    segments = int(planned.split(" segments")[0])
    assert len(image.segments) == segments + 1 and image.segments[-1][0] == "jump"
    assert image.repeats == 3 and image.registers["pitch"] > 0
    assert image.registers["laser_prr"] == 500 and "arm" not in image.registers


def test_store_refuses_in_one_line(drawing, tmp_path):
    with pytest.raises(SystemExit, match="give -o FILE"):
        main(["store", str(drawing)])
    with pytest.raises(SystemExit, match="cannot read|no such|not found|No such"):
        main(["store", str(tmp_path / "missing.svg"), "-o", str(tmp_path / "x.img")])
    assert main(["store", str(drawing), "--estimate"]) == 0
    assert not list(tmp_path.glob("*.img"))


def test_flash_writes_both_and_reads_them_back(drawing, tmp_path, fast_flash, capsys):
    image_path, bit_path, flash_path = (tmp_path / name for name in
                                        ("part.img", "top.bin", "flash.bin"))
    assert main(["store", str(drawing), "-o", str(image_path)]) == 0
    bit_path.write_bytes(BITSTREAM)
    capsys.readouterr()
    assert main(["flash", str(bit_path), "--job", str(image_path), "--to", str(flash_path)]) == 0
    out = capsys.readouterr().out
    assert "bitstream at 0x000000" in out and "job image at 0x100000" in out
    memory = flash_path.read_bytes()
    assert len(memory) == FLASH_BYTES
    assert memory[:len(BITSTREAM)] == BITSTREAM
    job = image_path.read_bytes()
    assert memory[JOB_OFFSET:JOB_OFFSET + len(job)] == job
    assert memory[len(BITSTREAM):len(BITSTREAM) + 64] == b"\xff" * 64


def test_flash_ulx3s_to_a_file_and_to_the_board(drawing, tmp_path, fast_flash, monkeypatch,
                                               capsys):
    """--board ulx3s: the ECP5's .bit to a flash image file, and to a (modelled) board through
    its ECP5's JTAG on the FT231X at the ULX3S's default URL."""
    image_path, bit_path, flash_path = (tmp_path / name for name in
                                        ("part.img", "top.bit", "flash.bin"))
    assert main(["store", str(drawing), "-o", str(image_path)]) == 0
    bit_path.write_bytes(ECP5_BITSTREAM)
    job = image_path.read_bytes()
    args = ["flash", "--board", "ulx3s", str(bit_path), "--job", str(image_path)]
    assert main(args + ["--to", str(flash_path)]) == 0
    memory = flash_path.read_bytes()
    assert memory[:len(ECP5_BITSTREAM)] == ECP5_BITSTREAM
    assert memory[JOB_OFFSET:JOB_OFFSET + len(job)] == job

    flash = SPIFlashModel(BITSTREAM)            # (the wrong board's, so the FPGA starts idle)
    ecp5 = ECP5(flash, idcode=0x41111043, clock=fast_flash, configured=False)
    ftdi = FakeFtdi(ecp5, fast_flash)
    monkeypatch.setattr(pyftdi.ftdi, "Ftdi", lambda: ftdi)
    capsys.readouterr()
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "bitstream at 0x000000" in out and "Winbond W25Q128" in out
    assert bytes(flash.memory[:len(ECP5_BITSTREAM)]) == ECP5_BITSTREAM
    assert bytes(flash.memory[JOB_OFFSET:JOB_OFFSET + len(job)]) == job
    assert ftdi.url == "ftdi://ftdi:ft-x/1" and ftdi.closed and ecp5.configured

    # A job alone onto a board with no bitstream: written, and the ECP5's silence noted.
    ecp5 = ECP5(SPIFlashModel(), idcode=0x41111043, clock=fast_flash, configured=False)
    blank = FakeFtdi(ecp5, fast_flash)
    monkeypatch.setattr(pyftdi.ftdi, "Ftdi", lambda: blank)
    assert main(["flash", "--board", "ulx3s", "--job", str(image_path)]) == 0
    assert "note: the ECP5 did not configure from the flash" in capsys.readouterr().err
    assert bytes(ecp5.flash.memory[JOB_OFFSET:JOB_OFFSET + len(job)]) == job


def test_flash_ulx3s_onto_an_issi_flash(tmp_path, fast_flash, monkeypatch, capsys):
    """--board ulx3s onto the IS25LP128: to a file written through a model of it (as `--to`
    writes, through ModelPort), and to a board whose part has its blocks protected; a part
    galvoscan has no driver for is one line naming its JEDEC id, and no file."""
    bit_path, flash_path = tmp_path / "top.bit", tmp_path / "flash.bin"
    bit_path.write_bytes(ECP5_BITSTREAM)
    args = ["flash", "--board", "ulx3s", str(bit_path)]
    monkeypatch.setattr(spi_flash, "SPIFlashModel", IS25LPModel)
    capsys.readouterr()
    assert main(args + ["--to", str(flash_path)]) == 0
    assert f"ISSI IS25LP128 16 MiB (the file {flash_path})" in capsys.readouterr().out
    assert flash_path.read_bytes()[:len(ECP5_BITSTREAM)] == ECP5_BITSTREAM

    flash = IS25LPModel(status=SR_BP | SR_QE)
    ecp5 = ECP5(flash, idcode=0x41111043, clock=fast_flash, configured=False)
    ftdi = FakeFtdi(ecp5, fast_flash)
    monkeypatch.setattr(pyftdi.ftdi, "Ftdi", lambda: ftdi)
    assert main(args) == 0
    assert "ISSI IS25LP128 16 MiB\n" in capsys.readouterr().out
    assert bytes(flash.memory[:len(ECP5_BITSTREAM)]) == ECP5_BITSTREAM
    assert flash.nonvolatile == SR_QE and flash.refused == []
    assert ecp5.configured and ftdi.closed

    # (ISSI's 1.8 V IS25WP128, which no ULX3S carries.)
    monkeypatch.setattr(spi_flash, "SPIFlashModel",
                        type("IS25WP128", (IS25LPModel,), {"jedec_id": b"\x9d\x70\x18"}))
    other = tmp_path / "other.bin"
    with pytest.raises(SystemExit, match=r"^galvoscan flash: error: the flash answers JEDEC id "
                                         r"9d 70 18, a part galvoscan has no driver for: "
                                         r"write it with another programmer") as error:
        main(args + ["--to", str(other)])
    assert "\n" not in str(error.value) and not other.exists()


@pytest.mark.parametrize("board, data, message", [
    ("ulx3s", BITSTREAM, "top.bit: the bitstream is not an ECP5 bitstream .* it is an "
                         "iCE40's: flash it with --board icebreaker"),
    ("icebreaker", ECP5_BITSTREAM, "top.bit: the bitstream is not an iCE40 bitstream"),
])
def test_flash_refuses_the_other_boards_bitstream(tmp_path, board, data, message):
    bit_path, flash_path = tmp_path / "top.bit", tmp_path / "flash.bin"
    bit_path.write_bytes(data)
    with pytest.raises(SystemExit, match=message):
        main(["flash", "--board", board, str(bit_path), "--to", str(flash_path)])
    assert not flash_path.exists()


@pytest.mark.parametrize("case, message", [
    ("not a bitstream", "not an iCE40 bitstream"),
    ("too big", "would overlap the job image"),
    ("bad image", "corrupt image"),
    ("nothing", "nothing to write"),
])
def test_flash_refuses_before_writing(case, message, drawing, tmp_path, capsys):
    image_path, bit_path, flash_path = (tmp_path / name for name in
                                        ("part.img", "top.bin", "flash.bin"))
    assert main(["store", str(drawing), "-o", str(image_path)]) == 0
    args = ["flash", "--to", str(flash_path)]
    if case == "not a bitstream":
        bit_path.write_bytes(b"hello" * 100)
        args.append(str(bit_path))
    elif case == "too big":
        bit_path.write_bytes(BITSTREAM + bytes(JOB_OFFSET))
        args.append(str(bit_path))
    elif case == "bad image":
        damaged = bytearray(image_path.read_bytes())
        damaged[-1] ^= 1
        image_path.write_bytes(bytes(damaged))
        args += ["--job", str(image_path)]
    with pytest.raises(SystemExit, match=message):
        main(args)
    assert not flash_path.exists()


def test_a_write_that_does_not_take_is_caught(fast_flash):
    """A write-protected part (programs ignored): the read-back names the first byte."""
    model = SPIFlashModel(powered_down=True)
    model._deselect_original = model._deselect

    def ignore_programs():
        if model._received and model._received[0] == 0x02:
            model._selected = False
            return
        model._deselect_original()
    model._deselect = ignore_programs
    with pytest.raises(FlashingError, match=r"reads back 0xff at 0x1, where 0x00 was written"):
        program(ModelPort(model, clock=fast_flash.monotonic), flash_regions(BITSTREAM))


def test_no_flash_answering_is_one_line(fast_flash):
    class Silent:
        frequency = 1e6

        def exchange(self, out=b"", readlen=0, **kwargs):
            return b"\xff" * readlen
    with pytest.raises(FlashingError, match="JEDEC id ff ff ff, not a Winbond W25Q"):
        program(Silent(), flash_regions(BITSTREAM))


def test_standalone_plays_the_stored_job_and_refuses_a_damaged_one(drawing, tmp_path,
                                                                    capsys):
    image_path = tmp_path / "part.img"
    assert main(["store", str(drawing), "--speed", "500", "-o", str(image_path)]) == 0
    capsys.readouterr()
    assert main(["standalone", "--sim", "--flash", str(image_path), "--presses", "2",
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["presses"] == ["done", "done"] and report["refused"] == 0
    assert report["pulses"] > 100 and report["pulses_per_point"] >= 1
    assert abs(report["speed_mm_s"] - 500) < 500 * 0.02
    assert report["underruns"] == report["rejected"] == report["errors"] == 0
    assert report["marks_frame"].startswith("field") and report["field_mm"] == 110
    # The marks lie on the drawing's lines (6 × 3 mm rectangle and a 6 mm line, centred).
    xs = [x for x, _ in report["marks"]]
    assert max(xs) - min(xs) == pytest.approx(6, abs=0.05)

    damaged = bytearray(image_path.read_bytes())
    damaged[-2] ^= 0x10            # (in the last segment: only the CRC sees it)
    image_path.write_bytes(bytes(damaged))
    assert main(["standalone", "--sim", "--flash", str(image_path), "--json"]) == 1
    out, err = capsys.readouterr()
    report = json.loads(out)
    assert report["presses"] == ["bad crc"] and report["refused"] == 1
    assert report["pulses"] == 0 and not report["marks"]
    assert "the board's player will refuse it" in err


def test_standalone_needs_sim(tmp_path):
    with pytest.raises(SystemExit, match="give --sim"):
        main(["standalone", "--flash", str(tmp_path / "x.img")])


def test_flash_refuses_a_bitstream_without_the_player(drawing, tmp_path, capsys):
    """With --job, a bitstream whose build record (beside it, as `build` writes it) says it
    has no job player is refused before any byte: the board would ignore the foot switch."""
    image_path, bit_path, flash_path = (tmp_path / name for name in
                                        ("part.img", "top.bin", "flash.bin"))
    assert main(["store", str(drawing), "-o", str(image_path)]) == 0
    bit_path.write_bytes(BITSTREAM)
    record = bit_path.with_suffix(".build.json")
    record.write_text(json.dumps({"player": False}))
    with pytest.raises(SystemExit, match="top.bin has no job player"):
        main(["flash", str(bit_path), "--job", str(image_path), "--to", str(flash_path)])
    assert not flash_path.exists()
    record.write_text(json.dumps({"player": True}))
    capsys.readouterr()
    assert main(["flash", str(bit_path), "--job", str(image_path), "--to", str(flash_path)]) == 0
    assert "no build record" not in capsys.readouterr().err


def test_store_refuses_the_wobble(drawing, tmp_path):
    with pytest.raises(SystemExit, match="has no wobble stage"):
        main(["store", str(drawing), "--wobble", "40", "-o", str(tmp_path / "x.img")])
    assert not list(tmp_path.glob("*.img"))


def test_standalone_plays_a_whole_flash_image(drawing, tmp_path, fast_flash, capsys):
    """`--flash` takes what `flash --to` wrote (the whole 16 MiB); a file too big for the
    flash above the bitstream is one line."""
    image_path, bit_path, flash_path = (tmp_path / name for name in
                                        ("part.img", "top.bin", "flash.bin"))
    assert main(["store", str(drawing), "-o", str(image_path)]) == 0
    bit_path.write_bytes(BITSTREAM)
    assert main(["flash", str(bit_path), "--job", str(image_path), "--to", str(flash_path)]) == 0
    capsys.readouterr()
    assert main(["standalone", "--sim", "--flash", str(flash_path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["presses"] == ["done"] and report["pulses"] > 100
    big = tmp_path / "big.img"
    big.write_bytes(bytes(FLASH_BYTES - JOB_OFFSET + 1))
    with pytest.raises(SystemExit, match="do not fit the flash above the bitstream"):
        main(["standalone", "--sim", "--flash", str(big)])
