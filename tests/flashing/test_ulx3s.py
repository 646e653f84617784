"""The ULX3S's flash writer (galvoscan/flashing/ulx3s.py, through galvoscan/flashing/ecp5.py
and galvoscan/flashing/jtag.py): through pyftdi's bit-bang calls, a model of the FT231X, of
the ECP5's TAP and its background SPI, and of the flash behind it (tests/support/ecp5_jtag.py,
written from IEEE 1149.1, Lattice's tables and FTDI's documents, not from the driver), with
pyspiflash and galvoscan.flashing.program writing as they write the iCEBreaker's; and drivers
broken on purpose, which the same test fails. The flash is the iCEBreaker's W25Q128JV, or the
ISSI IS25LP128 other ULX3S revisions carry (tests/support/issi_flash.py), which
galvoscan/flashing/chips.py drives."""

from functools import partial
from types import SimpleNamespace

import pyftdi.ftdi
import pytest
import spiflash.serialflash as serialflash
from hypothesis import HealthCheck, given, settings, strategies as st

import galvoscan.flashing.chips
import galvoscan.flashing.ecp5
import galvoscan.flashing.jtag
import galvoscan.flashing.writer
from galvoscan import flashing
from galvoscan.flashing import FlashingError, flash_regions, program
from galvoscan.flashing.ecp5 import check_bitstream
from galvoscan.flashing.ulx3s import DEFAULT_URL, open_ulx3s
from galvoscan.gateware.player.image_format import JOB_OFFSET
from galvoscan.sim.spi_flash import SPIFlashModel

from ecp5_jtag import ECP5, Clock, FakeFtdi, ecp5_bitstream
from flash_writes import LFE5U_25F, LFE5U_85F, a_job, bitstream
from issi_flash import SR_BP, SR_QE, SR_SRWD, IS25LPModel


#: What the board's flash holds before: a bitstream the ECP5 runs (it reads the flash).
OLD = ecp5_bitstream(LFE5U_25F, b"old design" * 50)


def ulx3s(monkeypatch, *, idcode=LFE5U_25F, contents=OLD, tdo=None, state="Test-Logic-Reset",
          part=SPIFlashModel):
    """A ULX3S on the USB: its flash (a ``part``) holding ``contents``, its ECP5 configured
    from them, the FT231X that pyftdi's ``Ftdi()`` opens; one clock for all of them and for
    the sleeps."""
    clock = Clock()
    for module in (serialflash, flashing.writer, flashing.jtag, flashing.ecp5):
        monkeypatch.setattr(module, "time", clock)
    flash = part(contents)              # (in deep power-down, as a design may leave it)
    ecp5 = ECP5(flash, idcode=idcode, clock=clock, state=state,
                configured=contents is not None)
    ftdi = FakeFtdi(ecp5, clock, tdo=tdo)
    monkeypatch.setattr(pyftdi.ftdi, "Ftdi", lambda: ftdi)
    return SimpleNamespace(clock=clock, flash=flash, ecp5=ecp5, ftdi=ftdi)


def write(bitstream=None, job=None):
    """What ``galvoscan flash --board ulx3s`` does: (the flash's description, configured)."""
    regions = flash_regions(bitstream, job, check=check_bitstream)
    port, release = open_ulx3s(bitstream=bitstream)
    try:
        what = program(port, regions, any_flash=True)
    finally:
        configured = release()
    return what, configured


def untouched(board):
    """Nothing done to the board: no configuration instruction, no flash command, the
    design still running, the FTDI closed."""
    return (board.ecp5.carried_out == [] and board.flash.commands == []
            and board.ecp5.configured and board.ftdi.closed)

def test_writes_the_bitstream_and_a_job_through_the_ecp5(monkeypatch):
    board = ulx3s(monkeypatch)
    new, job = bitstream(6000), a_job()
    what, configured = write(new, job)
    memory = bytes(board.flash.memory)
    assert memory[:len(new)] == new and memory[len(new):len(new) + 64] == b"\xff" * 64
    assert memory[JOB_OFFSET:JOB_OFFSET + len(job)] == job
    assert what == "Winbond W25Q128 16 MiB" and configured
    # The design cleared before the flash's first command, the key given, the ECP5
    # configured again from the new flash after its last; nothing refused on the way.
    assert [(name, commands > 0) for name, commands in board.ecp5.carried_out] == [
        ("ISC_ENABLE", False), ("ISC_ERASE", False), ("ISC_DISABLE", False),
        ("LSC_PROG_SPI", False), ("LSC_REFRESH", True)]
    assert board.ecp5.carried_out[-1][1] == len(board.flash.commands)
    assert board.ecp5.ignored == [] and board.flash.ignored == []
    assert board.ecp5.configured and not board.ecp5.spi_open
    assert board.ecp5.state == "Test-Logic-Reset"
    assert board.ftdi.url == DEFAULT_URL == "ftdi://ftdi:ft-x/1" and board.ftdi.closed


@pytest.mark.parametrize("state", ["Shift-DR", "Pause-IR", "Exit2-DR", "Update-IR"])
def test_a_tap_left_anywhere_by_another_tool(monkeypatch, state):
    board = ulx3s(monkeypatch, state=state)
    new = bitstream(300)
    assert write(new) == ("Winbond W25Q128 16 MiB", True)
    assert bytes(board.flash.memory[:len(new)]) == new


def test_a_job_alone_onto_a_blank_flash_says_the_ecp5_did_not_configure(monkeypatch):
    board = ulx3s(monkeypatch, contents=None)
    job = a_job()
    assert write(job=job) == ("Winbond W25Q128 16 MiB", False)
    assert bytes(board.flash.memory[JOB_OFFSET:JOB_OFFSET + len(job)]) == job


@pytest.mark.parametrize("idcode, expected, message", [
    (LFE5U_85F, LFE5U_25F, r"the board's FPGA is an LFE5U-85F \(IDCODE 0x41113043\), the "
                           r"bitstream is for an LFE5U-25F \(0x41111043\): build it with "
                           r"galvoscan build --board ulx3s --device 85F"),
    (0x0A012093, None, r"the board's JTAG answers IDCODE 0x0a012093, no ECP5 \(a ULX3S's "
                       r"LFE5U: 12F 0x21111043, 25F 0x41111043"),
])
def test_a_wrong_fpga_is_refused_before_anything_changes(monkeypatch, idcode, expected,
                                                         message):
    board = ulx3s(monkeypatch, idcode=idcode)
    with pytest.raises(FlashingError, match=message) as error:
        write(bitstream(100, idcode=expected) if expected else None, a_job())
    assert "\n" not in str(error.value)
    assert untouched(board) and bytes(board.flash.memory[:len(OLD)]) == OLD


@pytest.mark.parametrize("level, reads", [(1, "ones"), (0, "zeros")])
def test_a_stuck_tdo_is_one_line(monkeypatch, level, reads):
    """No board behind the FTDI, or a broken JTAG line: TDO never moves."""
    board = ulx3s(monkeypatch, tdo=level)
    with pytest.raises(FlashingError, match=f"no JTAG answers on the ULX3S's FTDI "
                                            f"\\(TDO reads all {reads}\\)") as error:
        write(bitstream(100))
    assert "\n" not in str(error.value) and untouched(board)


def test_no_ulx3s_at_the_url_is_one_line(monkeypatch):
    class Absent:
        def open_bitbang_from_url(self, url, **options):
            raise pyftdi.ftdi.FtdiError("UsbError: [Errno 2] Entity not found")
    monkeypatch.setattr(pyftdi.ftdi, "Ftdi", Absent)
    with pytest.raises(FlashingError, match=r"^no ULX3S at ftdi://ftdi:ft-x/2 \(UsbError: "
                                            r".*a udev rule for 0403:6015"):
        open_ulx3s("ftdi://ftdi:ft-x/2")


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(
    st.binary(max_size=400),
    st.builds(ecp5_bitstream, st.sampled_from([LFE5U_25F, LFE5U_85F, 0x12345679]),
              st.binary(max_size=1500))))
def test_a_random_bitstream_is_refused_or_written_exactly(monkeypatch, data):
    board = ulx3s(monkeypatch)
    try:
        what, configured = write(data, a_job())
    except FlashingError as error:
        # Refused in one line before the board changed (not an ECP5's, or another ECP5's).
        assert "\n" not in str(error)
        assert board.ecp5.carried_out == [] and board.flash.commands == []
        assert bytes(board.flash.memory[:len(OLD)]) == OLD
        return
    assert bytes(board.flash.memory[:len(data)]) == data and configured


#: Drivers broken on purpose: each of the model's rules that a driver could get wrong.
BROKEN = {
    # The flash's bytes sent LSB first, as JTAG shifts them.
    "bits not reversed": lambda monkeypatch: monkeypatch.setattr(
        flashing.ecp5, "_REVERSED", bytes(range(256))),
    # The running design keeps the flash.
    "configuration not cleared": lambda monkeypatch: monkeypatch.setattr(
        flashing.ecp5, "_clear_configuration", lambda jtag: None),
    # LSC_PROG_SPI without its key.
    "no background SPI key": lambda monkeypatch: monkeypatch.setattr(
        flashing.ecp5, "SPI_KEY", 0),
    # The busy flag never read (BYPASS's register, which always reads 0): the next
    # instruction comes while the ECP5 still erases.
    "busy not waited for": lambda monkeypatch: monkeypatch.setattr(
        flashing.ecp5, "LSC_CHECK_BUSY", flashing.ecp5.BYPASS),
}


@pytest.mark.parametrize("fault", BROKEN)
def test_a_broken_driver_fails(monkeypatch, fault):
    """The first test's write, with the driver broken: it must not pass for a write."""
    board = ulx3s(monkeypatch)
    new = bitstream(600)
    BROKEN[fault](monkeypatch)
    with pytest.raises(FlashingError) as error:
        write(new, a_job())
    assert "\n" not in str(error.value)
    assert bytes(board.flash.memory[:len(OLD)]) == OLD and board.ftdi.closed


# --- the parts the ULX3S carries --------------------------------------------------------------

def test_writes_an_issi_flash_through_the_ecp5(monkeypatch):
    """The IS25LP128 of other ULX3S revisions, unprotected as it leaves the factory: erased,
    written and read back as the W25Q is, its status register left alone."""
    board = ulx3s(monkeypatch, part=IS25LPModel)
    new, job = bitstream(6000), a_job()
    assert write(new, job) == ("ISSI IS25LP128 16 MiB", True)
    memory = bytes(board.flash.memory)
    assert memory[:len(new)] == new and memory[len(new):len(new) + 64] == b"\xff" * 64
    assert memory[JOB_OFFSET:JOB_OFFSET + len(job)] == job
    commands = board.flash.commands
    assert {0x06, 0x20, 0x02, 0x0B} <= set(commands) and 0x01 not in commands
    assert board.flash.ignored == [] and board.flash.refused == []
    assert board.ecp5.ignored == [] and board.ftdi.closed


def test_an_issi_flash_with_blocks_protected_is_unprotected_first(monkeypatch):
    """BP0-BP3 set (and QE, the board's quad-mode choice): one Write Status Register clears
    the BP bits before the first erase and keeps QE."""
    board = ulx3s(monkeypatch, part=partial(IS25LPModel, status=SR_BP | SR_QE))
    new, job = bitstream(3000), a_job()
    assert write(new, job) == ("ISSI IS25LP128 16 MiB", True)
    assert bytes(board.flash.memory[:len(new)]) == new
    assert bytes(board.flash.memory[JOB_OFFSET:JOB_OFFSET + len(job)]) == job
    assert board.flash.nonvolatile == SR_QE and board.flash.refused == []
    commands = board.flash.commands
    assert commands.count(0x01) == 1 and commands.index(0x01) < commands.index(0x20)
    assert board.flash.ignored == []


def test_an_issi_flash_left_protected_fails(monkeypatch):
    """The driver broken on purpose: the protection not cleared, every erase and program is
    inhibited and the read-back says so, in one line."""
    board = ulx3s(monkeypatch, part=partial(IS25LPModel, status=SR_BP))
    monkeypatch.setattr(flashing.chips, "clear_protection", lambda device: None)
    with pytest.raises(FlashingError, match=r"reads back .* the write failed") as error:
        write(bitstream(600), a_job())
    assert "\n" not in str(error.value)
    assert board.flash.refused and bytes(board.flash.memory[:len(OLD)]) == OLD
    assert board.ftdi.closed


def test_an_issi_flash_whose_status_register_is_locked_is_not_erased(monkeypatch):
    """SRWD set with /WP held low: the BP bits cannot be cleared; said in one line before
    any erase, and the ECP5 configured again from the old flash."""
    board = ulx3s(monkeypatch, part=partial(IS25LPModel, status=SR_BP | SR_SRWD, wp_n=0))
    with pytest.raises(FlashingError, match=r"^the flash \(ISSI IS25LP128 16 MiB\) cannot be "
                                            r"written: its block protection stays on \(status "
                                            r"register 0xbc: SRWD is set and /WP held low, "
                                            r"which locks it\); nothing was erased$"):
        write(bitstream(600), a_job())
    assert not {0x02, 0x20, 0x52, 0xD8, 0xC7, 0x60} & set(board.flash.commands)
    assert board.flash.nonvolatile == SR_BP | SR_SRWD and not board.flash.write_enabled
    assert bytes(board.flash.memory[:len(OLD)]) == OLD
    assert board.ecp5.configured and board.ftdi.closed
