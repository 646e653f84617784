"""The W25Q128JV model (galvoscan/sim/spi_flash.py) held to its datasheet's facts, through
whole transactions (as the host's programmer drives it) and through its pins."""

import pytest

from galvoscan.sim.spi_flash import FLASH_BYTES, JEDEC_ID, SPIFlashModel


def awake(**kwargs):
    flash = SPIFlashModel(powered_down=False, **kwargs)
    return flash


def status(flash):
    return flash.transfer(b"\x05\x00")[1]


def wait_ready(flash):
    polls = 0
    while status(flash) & 1:
        polls += 1
        assert polls < 10**6
    return polls


def test_jedec_id_and_read():
    flash = awake(contents={0x1000: b"abc"})
    assert flash.transfer(b"\x9f\x00\x00\x00")[1:] == JEDEC_ID
    assert flash.transfer(b"\x03\x00\x10\x00" + bytes(4))[4:] == b"abc\xff"
    # Fast read: one dummy byte after the address.
    assert flash.transfer(b"\x0b\x00\x10\x00\x00" + bytes(3))[5:] == b"abc"


def test_deep_power_down_answers_only_the_release():
    flash = SPIFlashModel({0: b"\x42"}, powered_down=True)
    assert flash.transfer(b"\x9f\x00\x00\x00")[1:] == b"\xff\xff\xff"
    assert flash.transfer(b"\x03\x00\x00\x00\x00")[4] == 0xFF
    flash.transfer(b"\xab")
    # Within tRES1 (3 µs) it still ignores; after it, it reads.
    assert flash.transfer(b"\x03\x00\x00\x00\x00")[4] == 0xFF
    flash.wait(3e-6)
    assert flash.transfer(b"\x03\x00\x00\x00\x00")[4] == 0x42
    assert [c for _, c in flash.ignored] == [0x9F, 0x03, 0x03]
    # And power-down again (0xB9): reads nothing until released.
    flash.transfer(b"\xb9")
    flash.wait(3e-6)
    assert flash.transfer(b"\x03\x00\x00\x00\x00")[4] == 0xFF


def test_program_needs_write_enable_and_only_clears_bits():
    flash = awake()
    flash.transfer(b"\x02\x00\x00\x10\x0f")
    assert flash.memory[0x10] == 0xFF                   # no WEL: nothing
    flash.transfer(b"\x06")
    assert status(flash) & 2                            # WEL set
    flash.transfer(b"\x02\x00\x00\x10\x0f")
    assert status(flash) & 1                            # busy while programming
    wait_ready(flash)
    assert not status(flash) & 2                        # WEL cleared after
    flash.transfer(b"\x06")
    flash.transfer(b"\x02\x00\x00\x10\xf3")
    wait_ready(flash)
    assert flash.memory[0x10] == 0x03                   # 0x0F & 0xF3: bits only cleared


def test_program_wraps_within_its_page():
    flash = awake()
    flash.transfer(b"\x06")
    flash.transfer(b"\x02\x00\x01\xfe" + b"\x01\x02\x03\x04")
    wait_ready(flash)
    assert flash.memory[0x1FE:0x200] == b"\x01\x02"
    assert flash.memory[0x100:0x102] == b"\x03\x04"     # wrapped to the page's start
    assert flash.memory[0x200] == 0xFF


@pytest.mark.parametrize("command, size", [(0x20, 4096), (0x52, 32768), (0xD8, 65536)])
def test_erases_their_aligned_block(command, size):
    flash = awake(contents={0: bytes(3 * size)})
    flash.transfer(bytes([command]) + (size + 5).to_bytes(3, "big"))
    assert flash.memory[size] == 0                      # no WEL: nothing
    flash.transfer(b"\x06")
    flash.transfer(bytes([command]) + (size + 5).to_bytes(3, "big"))
    polls = wait_ready(flash)
    assert polls > 10                                   # it takes its time (45 ms …)
    assert flash.memory[size:2 * size] == b"\xff" * size
    assert flash.memory[size - 1] == 0 and flash.memory[2 * size] == 0


def test_busy_ignores_all_but_the_status():
    flash = awake(contents={0: b"\x00"})
    flash.transfer(b"\x06")
    flash.transfer(b"\x20\x00\x00\x00")
    assert flash.transfer(b"\x03\x00\x00\x00\x00")[4] == 0xFF
    assert flash.ignored[-1][1] == 0x03


def test_pins_and_transactions_agree():
    """The pin-level driver gives what the byte-level one does (mode 0)."""
    flash = awake(contents={0x20: b"\x5a\xa5\x0f"})
    out = b"\x03\x00\x00\x20\x00\x00\x00"
    got = bytearray()
    t = 0.0
    cipo = flash.pins(0, 0, 0, t)
    for byte in out:
        value = 0
        for bit in range(7, -1, -1):
            t += 1e-7
            cipo = flash.pins(0, 1, byte >> bit & 1, t)         # rising: both sample
            value = value << 1 | cipo
            t += 1e-7
            cipo = flash.pins(0, 0, byte >> bit & 1, t)         # falling: next bit out
        got.append(value)
    flash.pins(1, 0, 0, t + 1e-7)
    assert bytes(got[4:]) == b"\x5a\xa5\x0f"


def test_contents_must_fit():
    with pytest.raises(ValueError, match="do not fit"):
        SPIFlashModel({FLASH_BYTES - 1: b"ab"})
