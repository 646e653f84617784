"""The iCE40's bitstream (the iCEBreaker's FPGA), checked before it goes to the flash: its
preamble, and its size, which must end below the job image."""

from ..gateware.player.image_format import JOB_OFFSET
from .errors import FlashingError


__all__ = ["ICE40_PREAMBLE", "check_bitstream"]


#: An iCE40 bitstream's synchronisation word (after an optional comment).
ICE40_PREAMBLE = b"\x7e\xaa\x99\x7e"


def check_bitstream(data, *, name="the bitstream"):
    """Refuse what is not an iCE40 bitstream, or one that would reach the job image."""
    if ICE40_PREAMBLE not in data[:256]:
        raise FlashingError(f"{name} is not an iCE40 bitstream (no 7E AA 99 7E preamble): "
                            f"give the .bin galvoscan build writes")
    if len(data) > JOB_OFFSET:
        raise FlashingError(f"{name} is {len(data):,} bytes: it would overlap the job image "
                            f"at {JOB_OFFSET:#x}")
