"""Job images (galvoscan/outputs/image.py): the bytes the player reads, checked field by field
against the format as docs/user/standalone.md gives it, and bad files refused in one line."""

import struct
import zlib

import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.outputs.image import ImageError, job_image, read_image


JOB = [("jump", 1000, 2000), ("mark", 3000, 2000), ("mark", 3000, 4000)]


def test_the_bytes_are_the_format():
    image = job_image(JOB, {"pitch": 60, "laser_on_delay": -5}, repeats=7)
    magic, version, length, crc, repeats, settings = struct.unpack_from("<4sHIIHH", image)
    assert magic == b"GSJB" and version == 1 and length == len(image) and repeats == 7
    zeroed = image[:10] + bytes(4) + image[14:]
    assert crc == zlib.crc32(zeroed)
    assert settings == 2
    pairs = struct.unpack_from("<4H", image, 18)
    assert pairs == (0x24, 60, 0x2A, (-5) & 0xFFFF)
    segments = struct.unpack_from("<12H", image, 26)
    # vec_x, vec_y, vec_op (bit 0 the op); the last mark is followed by a jump to its end.
    assert segments == (1000, 2000, 0, 3000, 2000, 1, 3000, 4000, 1, 3000, 4000, 0)
    assert len(image) == 26 + 24


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["jump", "mark"]), st.integers(0, 65535),
                          st.integers(0, 65535)), max_size=30),
       st.integers(1, 65535), st.integers(1, 65535), st.integers(0, 255))
def test_read_back(segments, repeats, pitch, power):
    image = read_image(job_image(segments, {"pitch": pitch, "laser_power": power},
                                 repeats=repeats))
    assert image.repeats == repeats and image.registers == {"pitch": pitch, "laser_power": power}
    expected = segments + ([("jump", *segments[-1][1:])] if segments and
                           segments[-1][0] == "mark" else [])
    assert [s[:3] for s in image.segments] == expected


@pytest.mark.parametrize("registers, repeats, message", [
    ({"arm": 1}, 1, "cannot set arm"),
    ({"fault_clear": 1}, 1, "not a register a job sets"),
    ({"pitch": 0}, 1, "outside 1"),
    ({"nonsense": 3}, 1, "not a register"),
    ({}, 0, "repeats must be"),
    ({}, 65536, "repeats must be"),
])
def test_what_the_player_would_refuse_is_refused_here(registers, repeats, message):
    with pytest.raises(ImageError, match=message):
        job_image(JOB, registers, repeats=repeats)


def test_a_job_too_big_for_the_flash():
    with pytest.raises(ImageError, match="the player reads 1 MiB at most"):
        job_image([("mark", k % 60000, 0) for k in range(180_000)], {})


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=80))
def test_any_bytes_are_read_or_refused_in_one_line(data):
    try:
        read_image(data)
    except ImageError as error:
        assert "\n" not in str(error)


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 8 * 44 - 1))
def test_a_flipped_bit_is_refused(position):
    image = bytearray(job_image(JOB, {"pitch": 60}))
    image[position // 8] ^= 1 << position % 8
    with pytest.raises(ImageError):
        read_image(bytes(image))


def test_the_messages():
    image = job_image(JOB, {})
    with pytest.raises(ImageError, match="erased"):
        read_image(b"\xff" * 64)
    with pytest.raises(ImageError, match="truncated"):
        read_image(image[:-6])
    with pytest.raises(ImageError, match="header"):
        read_image(image[:10])


def _recrc(image):
    """The image with its CRC field made right again (after a change)."""
    image = bytearray(image)
    image[10:14] = bytes(4)
    image[10:14] = zlib.crc32(image).to_bytes(4, "little")
    return bytes(image)


def test_what_the_marker_refuses_is_refused_here():
    """Images sound to the player's check (their CRCs are right) that the marker bitstream's
    register file would refuse, so the player would stop on them at the foot switch: a
    setting out of range, a segment's op word out of range, a register the marker has not."""
    from galvoscan.build import preset_register_map
    marker = preset_register_map("marker")
    image = bytearray(job_image(JOB, {"laser_prr": 500}))
    struct.pack_into("<H", image, 20, 0)                # laser_prr = 0 (200 … 2000)
    with pytest.raises(ImageError, match="laser_prr, 0, is outside 200 … 2000"):
        read_image(_recrc(image), regmap=marker)
    image = bytearray(job_image(JOB, {}))
    struct.pack_into("<H", image, len(image) - 2, 0xFFFF)   # the last vec_op
    with pytest.raises(ImageError, match="segment 4's vec_op, 65535, is outside"):
        read_image(_recrc(image), regmap=marker)
    wobbling = job_image(JOB, {"wob_freq": 500})
    assert read_image(wobbling).registers == {"wob_freq": 500}     # any bitstream's register
    with pytest.raises(ImageError, match="sets wob_freq, which the bitstream that plays it "
                                         "does not have"):
        read_image(wobbling, regmap=marker)
