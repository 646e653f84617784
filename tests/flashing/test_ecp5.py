"""The ECP5's bitstream check (galvoscan/flashing/ecp5.py), against bitstreams laid out as
ecppack lays them out (tests/support/ecp5_jtag.py's ecp5_bitstream, from prjtrellis' writer)
and files that are not one. The ECP5's JTAG sequence is tests/flashing/test_ulx3s.py's."""

import pytest

from galvoscan.flashing import FlashingError
from galvoscan.flashing.ecp5 import check_bitstream
from galvoscan.gateware.player.image_format import JOB_OFFSET

from ecp5_jtag import ecp5_bitstream


LFE5U_25F = 0x41111043
LFE5U_85F = 0x41113043


@pytest.mark.parametrize("data, message", [
    (b"\xff\x00GS\x00\xff\x7e\xaa\x99\x7e" + bytes(300), "it is an iCE40's: flash it with "
                                                         "--board icebreaker"),
    (b"hello" * 100, "is not an ECP5 bitstream .* give the .bit galvoscan build"),
    (b"\xff\x00x\x00\xff\xff\xff\xbd\xb3\xff\xff\x22\x00\x00\x00", "has no VERIFY_ID"),
    (ecp5_bitstream(0x12345679), "is for IDCODE 0x12345679, which is no ECP5"),
    (ecp5_bitstream(LFE5U_25F, bytes(JOB_OFFSET)), "would overlap the job image at 0x100000 "
                                                   r"\(.*ecppack --compress\)"),
])
def test_check_bitstream_refuses(data, message):
    with pytest.raises(FlashingError, match=message):
        check_bitstream(data)


def test_check_bitstream_takes_ecppacks_layouts():
    assert check_bitstream(ecp5_bitstream(LFE5U_85F)) == LFE5U_85F
    # No comment (a raw .bin), and ecppack's --spimode command before the CRC reset.
    assert check_bitstream(b"\xff\xff\xbd\xb3\xff\xff" + b"\x79\x00\x00\x00"
                           + b"\x3b\x00\x00\x00\xe2\x00\x00\x00\x21\x11\x10\x43") == 0x21111043
