"""Job images: a vector job as the board's job player reads it from the flash
(``galvoscan store`` writes one, ``galvoscan flash --job`` puts it at its offset).

The format is declared once, in :mod:`galvoscan.gateware.player.image_format`; the segments
are the words the streamer writes (:func:`~.queue_words.queue_word`), planned as ``mark`` plans
them, so the same drawing gives the same wires streamed or played.
"""

import zlib
from dataclasses import dataclass

from ..gateware.host.regmap import BY_ADDRESS, BY_NAME
from ..gateware.player.image_format import (CRC_BYTES, FORMAT_VERSION, HEADER_BYTES, HEADER_WORDS,
                                            JOB_OFFSET, MAGIC, MAX_IMAGE_BYTES, MAX_SETTINGS,
                                            PLAYER_OWNED, SEGMENT_WORDS, Word)
from ..geometry.corners import corner_frames
from .queue_words import check_segment, job_segments, queue_word, segment_of_words


__all__ = ["ImageError", "JobImage", "job_image", "read_image", "image_in_flash", "JOB_OFFSET",
           "MAX_IMAGE_BYTES"]


class ImageError(ValueError):
    """An image that cannot be made, or a file that is not a sound one: one line."""


@dataclass
class JobImage:
    """What an image holds: its settings (register name → value, in the order written),
    repeats, and segments ``(op, x, y, corner_frames)``."""
    registers: dict
    repeats: int
    segments: list

    @property
    def marks(self):
        return sum(op == "mark" for op, *_ in self.segments)


def job_image(segments, registers, *, repeats=1):
    """The image of a vector job: ``segments`` (``(op, x, y)``, galvo units) with
    ``registers`` (``{name: value}``: pitch, pulses per point, power, PRR, delays …), as
    :meth:`~.stream.JobStreamer.run_vector` would run them, played ``repeats`` times on each
    start. Raises :class:`ImageError` (one line) for what the player would refuse."""
    if isinstance(repeats, bool) or not isinstance(repeats, int) or not 1 <= repeats <= 0xFFFF:
        raise ImageError(f"repeats must be a whole number from 1 to 65535, not {repeats!r}")
    settings = []
    for name, value in registers.items():
        reg = BY_NAME.get(name)
        if reg is None or reg.access != "rw":
            raise ImageError(f"{name!r} is not a register a job sets")
        if name in ("mode", "run"):
            continue                # (the player selects vector mode and runs it itself)
        if name in PLAYER_OWNED:
            raise ImageError(f"a job image cannot set {name}: the player drives it itself")
        if isinstance(value, bool) or not isinstance(value, int) or \
                not reg.low <= value <= reg.high:
            raise ImageError(f"{name} = {value!r} is outside {reg.low} … {reg.high}")
        settings.append((reg.address, reg.encode(value)))
    if len(settings) > MAX_SETTINGS:
        raise ImageError(f"{len(settings)} settings: an image holds {MAX_SETTINGS} at most")
    segments = job_segments(segments)
    length = HEADER_BYTES + 4 * len(settings) + 2 * SEGMENT_WORDS * len(segments)
    if length > MAX_IMAGE_BYTES:
        raise ImageError(f"the job needs {length / 2**20:.1f} MiB; the player reads "
                         f"{MAX_IMAGE_BYTES / 2**20:g} MiB at most ({len(segments):,} "
                         f"segments: split it, or mark it from a host)")
    for segment in segments:
        try:
            check_segment(*segment)
        except ValueError as error:
            raise ImageError(str(error)) from None
    corners = corner_frames(segments, registers.get("polygon_delay", 0)) \
        if registers.get("polygon_scaled") else [0] * len(segments)
    words = [0] * HEADER_WORDS
    for address, value in settings:
        words += [address, value]
    for segment, hold in zip(segments, corners):
        words += queue_word(segment, hold)
    assert length == 2 * len(words)
    words[Word.MAGIC_LOW:Word.MAGIC_HIGH + 1] = (int.from_bytes(MAGIC[:2], "little"),
                                                  int.from_bytes(MAGIC[2:], "little"))
    words[Word.VERSION] = FORMAT_VERSION
    words[Word.LENGTH_LOW], words[Word.LENGTH_HIGH] = length & 0xFFFF, length >> 16
    words[Word.REPEATS] = repeats
    words[Word.SETTINGS] = len(settings)
    image = bytearray(b"".join(word.to_bytes(2, "little") for word in words))
    crc = zlib.crc32(image)         # (its own four bytes are still zero)
    image[CRC_BYTES.start:CRC_BYTES.stop] = crc.to_bytes(4, "little")
    return bytes(image)


def image_in_flash(flash):
    """The job image in a whole flash's bytes (``flash --to`` writes them): from its offset, as
    long as its header says (at most :data:`MAX_IMAGE_BYTES`), or all of that region when it
    has no sound length (an erased or damaged image, which the checks then refuse)."""
    region = bytes(flash[JOB_OFFSET:JOB_OFFSET + MAX_IMAGE_BYTES])
    if len(region) >= HEADER_BYTES and region[:4] == MAGIC:
        length = int.from_bytes(region[2 * Word.LENGTH_LOW:2 * Word.LENGTH_LOW + 2], "little") \
            | int.from_bytes(region[2 * Word.LENGTH_HIGH:2 * Word.LENGTH_HIGH + 2],
                             "little") << 16
        if HEADER_BYTES <= length <= len(region):
            return region[:length]
    return region


def _checked(reg, word, what):
    """``word`` decoded as register ``reg`` takes it, if its register file takes it."""
    value = reg.decode(word)
    if not reg.low <= value <= reg.high:
        raise ImageError(f"{what} {reg.name}, {value}, is outside {reg.low} … {reg.high}: the "
                         f"register file refuses that write")
    return value


def read_image(data, *, regmap=None):
    """The :class:`JobImage` in ``data`` (an image file's bytes), checked as the player
    checks it, and its settings and segments as the register file of the bitstream that
    plays it checks them (``regmap``, that bitstream's register map; default: every register
    galvoscan knows); :class:`ImageError` (one line) says what is wrong."""
    regmap = BY_NAME if regmap is None else regmap
    data = bytes(data)
    if len(data) < HEADER_BYTES:
        raise ImageError(f"not a job image: {len(data)} bytes, shorter than its "
                         f"{HEADER_BYTES}-byte header")
    if data[:4] != MAGIC:
        raise ImageError("not a job image (galvoscan store writes them)" if
                         data[:4] != b"\xff" * 4 else "an erased image: all 0xFF")
    words = [int.from_bytes(data[i:i + 2], "little") for i in range(0, len(data) - 1, 2)]
    if words[Word.VERSION] != FORMAT_VERSION:
        raise ImageError(f"a job image of format {words[Word.VERSION]}; this galvoscan "
                         f"writes and its player reads format {FORMAT_VERSION}")
    length = words[Word.LENGTH_LOW] | words[Word.LENGTH_HIGH] << 16
    if length != len(data):
        raise ImageError(f"a truncated or padded image: its header says {length} bytes, the "
                         f"file has {len(data)}")
    if length % 2 or length > MAX_IMAGE_BYTES:
        raise ImageError(f"a damaged image: a length of {length} bytes")
    zeroed = bytearray(data)
    zeroed[CRC_BYTES.start:CRC_BYTES.stop] = bytes(4)
    crc = int.from_bytes(data[CRC_BYTES.start:CRC_BYTES.stop], "little")
    if zlib.crc32(zeroed) != crc:
        raise ImageError("a corrupt image: its CRC-32 does not match")
    repeats, count = words[Word.REPEATS], words[Word.SETTINGS]
    if repeats == 0:
        raise ImageError("a damaged image: 0 repeats")
    if count > MAX_SETTINGS:
        raise ImageError(f"a damaged image: {count} settings")
    body = words[HEADER_WORDS:]
    if 2 * count > len(body) or (len(body) - 2 * count) % SEGMENT_WORDS:
        raise ImageError("a damaged image: its settings and segments do not fill it")
    registers = {}
    for address, value in zip(body[0:2 * count:2], body[1:2 * count:2]):
        reg = BY_ADDRESS.get(address)
        if reg is None or reg.name in PLAYER_OWNED:
            raise ImageError(f"a damaged image: a setting of address {address:#04x}")
        if reg.name not in regmap:
            raise ImageError(f"it sets {reg.name}, which the bitstream that plays it does not "
                             f"have: its register file refuses that write")
        registers[reg.name] = _checked(regmap[reg.name], value, "its setting of")
    segments = []
    rest = body[2 * count:]
    for i in range(0, len(rest), SEGMENT_WORDS):
        x, y, op_word = (_checked(regmap[name], word, f"segment {i // SEGMENT_WORDS + 1}'s")
                         for name, word in zip(("vec_x", "vec_y", "vec_op"),
                                               rest[i:i + SEGMENT_WORDS]))
        segments.append(segment_of_words(x, y, op_word))
    return JobImage(registers=registers, repeats=repeats, segments=segments)
