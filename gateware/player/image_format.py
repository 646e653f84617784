"""The job image the player reads from the flash and ``galvoscan store`` writes: declared once
here, for both (imports nothing, so the host reads it without Amaranth).

An image is a sequence of 16-bit little-endian words::

    word  0, 1   magic, the bytes "GSJB"
    word  2      format version (FORMAT_VERSION)
    word  3, 4   length of the whole image in bytes (low word first): even, at least
                 HEADER_BYTES, at most MAX_IMAGE_BYTES (1 MiB)
    word  5, 6   CRC-32 (zlib's) of the whole image with these four bytes read as zero
    word  7      repeats: times the job runs on each start (1 … 65535)
    word  8      settings: the number of (address, value) pairs that follow (at most
                 MAX_SETTINGS)
    then         the settings: register writes done before the laser is armed
    then         the segments, three words each: vec_x, vec_y, vec_op (the queue's words,
                 as the register map spells them)

The player checks magic, version, length and CRC over the whole image before it writes any
register; a setting may not address a register the player drives itself (PLAYER_OWNED).
"""

__all__ = ["MAGIC", "MAGIC_WORDS", "FORMAT_VERSION", "JOB_OFFSET", "FLASH_BYTES",
           "MAX_IMAGE_BYTES", "HEADER_WORDS", "HEADER_BYTES", "SEGMENT_WORDS", "Word",
           "PLAYER_OWNED", "CRC_BYTES", "MAX_SETTINGS"]


#: The image's first four bytes.
MAGIC = b"GSJB"
#: The same, as the two words the player compares.
MAGIC_WORDS = (int.from_bytes(MAGIC[0:2], "little"), int.from_bytes(MAGIC[2:4], "little"))
FORMAT_VERSION = 1
#: Where the image starts in the flash: 1 MiB, above the UP5K's bitstream (about 104 kB).
JOB_OFFSET = 0x100000
#: The iCEBreaker's flash (W25Q128JV): 16 MiB.
FLASH_BYTES = 16 * 1024 * 1024
#: The largest image the player reads: 1 MiB, some 174,000 segments (the flash holds 15 MiB
#: above JOB_OFFSET; the player's word counters are sized to this).
MAX_IMAGE_BYTES = 1 << 20


class Word:
    """Index of each header word."""
    MAGIC_LOW = 0
    MAGIC_HIGH = 1
    VERSION = 2
    LENGTH_LOW = 3
    LENGTH_HIGH = 4
    CRC_LOW = 5
    CRC_HIGH = 6
    REPEATS = 7
    SETTINGS = 8


HEADER_WORDS = 9
#: The most settings an image holds (a job writes some twenty registers).
MAX_SETTINGS = 255
HEADER_BYTES = 2 * HEADER_WORDS
#: Bytes of the image the CRC reads as zero: the CRC's own.
CRC_BYTES = range(2 * Word.CRC_LOW, 2 * Word.CRC_HIGH + 2)
#: Words of a segment: vec_x, vec_y, vec_op.
SEGMENT_WORDS = 3
#: Registers a setting may not write: the player arms, selects, runs and feeds the queue
#: itself, and a fault is cleared only by a host.
PLAYER_OWNED = ("arm", "mode", "run", "vec_x", "vec_y", "vec_op", "vec_flush", "fault_clear")
