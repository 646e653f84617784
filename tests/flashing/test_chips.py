"""The flash parts galvoscan writes (galvoscan/flashing/chips.py), picked by their JEDEC id:
pyspiflash's drivers and galvoscan's own for the ISSI IS25LP, through ModelPort (``flash --to
FILE``'s path) onto the W25Q128JV model and the IS25LP128 model (tests/support/issi_flash.py,
written from ISSI's documents, not from the driver). The IS25LP through the ULX3S's ECP5 is
tests/flashing/test_ulx3s.py's."""


import pytest
import spiflash.serialflash as serialflash

import galvoscan.flashing.writer
from galvoscan import flashing
from galvoscan.flashing import FlashingError, ModelPort, flash_regions, program
from galvoscan.flashing.chips import DRIVERS, IS25LPFlashDevice
from galvoscan.flashing.ecp5 import check_bitstream
from galvoscan.gateware.player.image_format import JOB_OFFSET
from galvoscan.sim.spi_flash import SPIFlashModel

from ecp5_jtag import Clock
from flash_writes import a_job, bitstream
from issi_flash import SR_BP, SR_QE, IS25LPModel




def part(jedec, model=SPIFlashModel):
    """``model`` answering ``jedec``: the commands pyspiflash's '25' drivers give are the
    W25Q's (and the IS25LP's) for all of these."""
    return type("Part", (model,), {"jedec_id": jedec})


NO_DRIVER = "a part galvoscan has no driver for: write it with another programmer"


@pytest.mark.parametrize("jedec, any_flash, outcome", [
    (b"\xc2\x20\x18", True, "Macronix MX25E06128 16 MiB"),   # (pyspiflash's name)
    (b"\xef\x40\x18", True, "Winbond W25Q128 16 MiB"),
    (b"\x9d\x60\x18", True, "ISSI IS25LP128 16 MiB"),
    (b"\x9d\x60\x17", True, "ISSI IS25LP064 8 MiB"),
    (b"\x9d\x60\x16", True, "ISSI IS25LP032 4 MiB"),
    (b"\xc2\x20\x18", False, FlashingError("JEDEC id c2 20 18, not a Winbond W25Q")),
    (b"\x9d\x60\x18", False, FlashingError("JEDEC id 9d 60 18, not a Winbond W25Q")),
    # ISSI's 1.8 V IS25WP128, which no ULX3S carries, and an SST25, whose pyspiflash
    # driver cannot write.
    (b"\x9d\x70\x18", True, FlashingError(f"^the flash answers JEDEC id 9d 70 18, {NO_DRIVER}")),
    (b"\xbf\x25\x41", True, FlashingError(f"JEDEC id bf 25 41, {NO_DRIVER}")),
    (b"\xff\xff\xff", True, FlashingError(r"no flash answers \(JEDEC id ff ff ff\)")),
])
def test_the_ulx3s_takes_any_flash_galvoscan_knows(monkeypatch, jedec, any_flash, outcome):
    """The ULX3S's part differs between board revisions; the iCEBreaker's is a W25Q. Through
    ModelPort, as ``flash --to FILE`` writes; an unknown part is named by its id in one line
    before any erase."""
    clock = Clock()
    monkeypatch.setattr(serialflash, "time", clock)
    monkeypatch.setattr(flashing.writer, "time", clock)
    model = part(jedec, IS25LPModel if jedec[0] == 0x9D else SPIFlashModel)(powered_down=False)
    job = a_job()
    regions = flash_regions(job=job)
    if isinstance(outcome, Exception):
        with pytest.raises(FlashingError, match=str(outcome)) as error:
            program(ModelPort(model, clock=clock.monotonic), regions, any_flash=any_flash)
        assert "\n" not in str(error.value)
        assert model.commands[2:] == []         # (after the wake-up and the JEDEC id)
    else:
        assert program(ModelPort(model, clock=clock.monotonic), regions,
                       any_flash=any_flash) == outcome
        assert bytes(model.memory[JOB_OFFSET:JOB_OFFSET + len(job)]) == job


def test_an_issi_flash_through_modelport_by_blocks_and_sectors(monkeypatch):
    """A bitstream over 64 KB blocks and a job (``flash --to FILE``'s path) onto a protected
    IS25LP128: the BP bits cleared, 64 KB and 4 KB erases, each region read back."""
    clock = Clock()
    monkeypatch.setattr(serialflash, "time", clock)
    monkeypatch.setattr(flashing.writer, "time", clock)
    model = IS25LPModel(b"\0" * (JOB_OFFSET + 8192), status=SR_BP | SR_QE)
    new, job = bitstream(200_000), a_job()
    written = []
    what = program(ModelPort(model, clock=clock.monotonic),
                   flash_regions(new, job, check=check_bitstream), progress=written.append,
                   any_flash=True)
    assert what == "ISSI IS25LP128 16 MiB" and sum(written) == len(new) + len(job)
    memory = bytes(model.memory)
    assert memory[:len(new)] == new
    # (The rest of the bitstream's last sector erased; what lies beyond it untouched.)
    end = -(-len(new) // 4096) * 4096
    assert memory[len(new):end] == b"\xff" * (end - len(new)) and memory[end:end + 8] == bytes(8)
    assert memory[JOB_OFFSET:JOB_OFFSET + len(job)] == job
    assert {0xD8, 0x20} <= set(model.commands)
    assert model.nonvolatile == SR_QE and model.refused == [] and model.ignored == []


def test_a_region_beyond_a_smaller_issi_part_is_refused_before_any_erase(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(serialflash, "time", clock)
    model = part(b"\x9d\x60\x16", IS25LPModel)(powered_down=False, status=SR_BP)
    with pytest.raises(FlashingError, match=r"^3,200,000 bytes at 0x100000 do not fit the "
                                            r"flash \(ISSI IS25LP032 4 MiB, 4,194,304 bytes\)$"):
        program(ModelPort(model, clock=clock.monotonic), flash_regions(job=bytes(3_200_000)),
                any_flash=True)
    assert model.commands[2:] == [] and model.nonvolatile == SR_BP


def test_the_drivers_are_pyspiflashs_in_its_order_and_the_issis():
    """galvoscan's table in place of pyspiflash's private pick: every public driver it has
    (but the SST25's, whose write() cannot work), in the order its _get_flash tries them."""
    public = [driver for name, driver in vars(serialflash).items()
              if name.endswith("FlashDevice") and not name.startswith("_")]
    assert list(DRIVERS) == [driver for driver in public
                             if driver is not serialflash.Sst25FlashDevice] + [IS25LPFlashDevice]
