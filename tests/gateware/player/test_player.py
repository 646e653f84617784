"""The job player (gateware/player/player.py) on the system top's pins: a job image in the
simulated board's flash (the W25Q128JV model), a press of the foot switch, and what the
wires, the laser pins and the registers (read over the UART with the real client) show."""

import zlib

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.gateware.fields import PlayerResult, PlayerState, PlayerStatus, Status
from galvoscan.link.client import HostClient
from galvoscan.gateware.player.image_format import CRC_BYTES, Word
from galvoscan.outputs.image import job_image
from galvoscan.outputs.stream import JobStreamer
from galvoscan.sim.board import SimTransport, SimulatedBoard

from player_board import JOB, PLAYER_BOARD, REGISTERS


_BOARD = []


def board_with(image):
    """The player's board from power-up with ``image`` in its flash: on the compiled backend
    (held to Amaranth's, record for record, by tests/sim/test_compiled.py's player test),
    built once and reset for each test (building it again converts the design anew)."""
    if not _BOARD:
        _BOARD.append(SimulatedBoard(flash=image, backend="compiled", **PLAYER_BOARD))
    else:
        _BOARD[0].reset(flash=image)
    return _BOARD[0]


def player_status(client):
    return PlayerStatus.from_bits(client.read("player"))


def press_and_wait(board, client, *, timeout_s=0.05):
    board.press_start(1.5e-3)
    waited = 0.0
    while True:
        status = player_status(client)
        if status.state == PlayerState.IDLE:
            return status
        board.run_for(0.5e-3)
        waited += 0.5e-3
        assert waited < timeout_s, "the player did not finish"


def laser_was_enabled(board):
    return any(pins[0] for _, pins in board.laser_changes)


def marked_points(board):
    """``(x, y, pulses, frames)`` of each run of frames at one place, the park before the job
    and the last place (held until the end of the run) left out."""
    return [point[:4] for point in board.points()[1:-1]]


def test_plays_the_image_as_the_streamer_streams_it():
    """The same drawing streamed by the host (JobStreamer, as `mark` runs it) and played from
    the flash: the same points in the same order on the wires, and the same pulses and dwell
    at each, but for the job's first two points. Vector points are paced by the laser's
    pulses, whose phase when ``run`` is set differs: the player sets it as soon as the MO lead
    is over, the host some polls later. (The host streams to the same build, its flash
    erased and its player idle, as `mark` streams to the default bitstream.)"""
    streamed = board_with(None)
    JobStreamer(HostClient(SimTransport(streamed)), poll_s=0).run_vector(
        JOB, REGISTERS, timeout_s=1e9)
    streamed.run_for(0.3e-3)
    streamed_points = marked_points(streamed)

    played = board_with(job_image(JOB, REGISTERS))      # (the same board, reset)
    client = HostClient(SimTransport(played))
    status = press_and_wait(played, client)
    played.run_for(0.3e-3)
    assert status.result == PlayerResult.DONE and status.refused == 0
    played_points = marked_points(played)
    assert [p[:2] for p in played_points] == [p[:2] for p in streamed_points]
    assert played_points[2:] == streamed_points[2:]
    assert sum(p[2] for p in played_points) > 10
    # Disarmed at the end, the queue empty, nothing refused or counted as an error.
    flags = Status.from_bits(client.read("status"))
    assert not flags.armed and not flags.vector_busy and not flags.player_busy
    assert client.read("errors") == 0 and client.read("vec_underruns") == 0


def test_repeats_play_the_segments_again():
    """Three repeats: the job's points three times over, each repeat starting with the jump
    back to its start (its pulses differ by the first points' phase, as above)."""
    once = board_with(job_image(JOB, REGISTERS))
    press_and_wait(once, HostClient(SimTransport(once)))
    positions = [point[:2] for point in once.points()[1:]]
    pulses_once = len(once.pulses)
    thrice = board_with(job_image(JOB, REGISTERS, repeats=3))     # (the same board, reset)
    status = press_and_wait(thrice, HostClient(SimTransport(thrice)))
    assert status.result == PlayerResult.DONE
    assert [point[:2] for point in thrice.points()[1:]] == 3 * positions
    assert abs(len(thrice.pulses) - 3 * pulses_once) <= 2 * 3 and pulses_once


def _with_crc(image):
    """``image`` (bytes) with its CRC made right again, as a damaged writer would."""
    image = bytearray(image)
    image[CRC_BYTES.start:CRC_BYTES.stop] = bytes(4)
    crc = zlib.crc32(image)
    image[CRC_BYTES.start:CRC_BYTES.stop] = crc.to_bytes(4, "little")
    return bytes(image)


def _word(image, index, value):
    image = bytearray(image)
    image[2 * index:2 * index + 2] = value.to_bytes(2, "little")
    return bytes(image)


GOOD = job_image(JOB, REGISTERS)
REFUSALS = {
    "erased": (None, PlayerResult.NO_IMAGE),
    "other data": (b"\x00" * 64, PlayerResult.NO_IMAGE),
    "truncated": (GOOD[:len(GOOD) - 7], PlayerResult.BAD_CRC),
    "version 2": (_with_crc(_word(GOOD, Word.VERSION, 2)), PlayerResult.BAD_VERSION),
    "odd length": (_with_crc(_word(GOOD, Word.LENGTH_LOW, len(GOOD) - 1)),
                   PlayerResult.BAD_HEADER),
    "length past a segment": (_with_crc(_word(GOOD, Word.LENGTH_LOW, len(GOOD) - 2)),
                              PlayerResult.BAD_HEADER),
    "length past the flash": (_with_crc(_word(GOOD, Word.LENGTH_HIGH, 0xF1)),
                              PlayerResult.BAD_HEADER),
    "length past 1 MiB": (_with_crc(_word(GOOD, Word.LENGTH_HIGH, 0x10)),
                          PlayerResult.BAD_HEADER),
    "too many settings": (_with_crc(_word(GOOD, Word.SETTINGS, 256)),
                          PlayerResult.BAD_HEADER),
    "no repeats": (_with_crc(_word(GOOD, Word.REPEATS, 0)), PlayerResult.BAD_HEADER),
    "a setting arms": (_with_crc(_word(GOOD, Word.SETTINGS + 1, 0x10)),
                       PlayerResult.BAD_SETTING),
    "a setting clears faults": (_with_crc(_word(GOOD, Word.SETTINGS + 1, 0x14)),
                                PlayerResult.BAD_SETTING),
    "a setting out of range": (_with_crc(_word(GOOD, Word.SETTINGS + 2, 0)),
                               PlayerResult.REFUSED),
}


@pytest.mark.parametrize("name", REFUSALS)
def test_a_bad_image_never_arms_the_laser(name):
    image, result = REFUSALS[name]
    board = board_with(image)
    client = HostClient(SimTransport(board))
    status = press_and_wait(board, client)
    assert status.result == result
    assert not laser_was_enabled(board) and not board.pulses
    flags = Status.from_bits(client.read("status"))
    assert flags.job_refused == result.refused and not flags.armed
    assert status.refused == int(result.refused)
    # The head is left where it was: nothing was queued.
    assert {(x, y) for _, x, y in board.frames} == {(32768, 32768)}


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(position=st.integers(0, len(GOOD) * 8 - 1))
def test_any_flipped_bit_is_refused(position):
    image = bytearray(GOOD)
    image[position // 8] ^= 1 << position % 8
    board = board_with(bytes(image))
    client = HostClient(SimTransport(board))
    status = press_and_wait(board, client)
    assert status.result.refused and not laser_was_enabled(board) and not board.pulses


def test_a_host_write_of_arm_stops_the_job():
    long_job = [("jump", 30000, 30000)] + [("mark", 30000 + 200 * k, 30000 + 100 * (k % 2))
                                           for k in range(1, 40)]
    board = board_with(job_image(long_job, REGISTERS))
    client = HostClient(SimTransport(board))
    board.press_start(1.5e-3)
    while not board.pulses:
        board.run_for(0.2e-3)
    client.write("arm", 0)
    board.run_for(0.1e-3)
    status = player_status(client)
    assert status.state == PlayerState.IDLE and status.result == PlayerResult.HOST
    flags = Status.from_bits(client.read("status"))
    assert not flags.armed and not flags.laser_enable and not flags.vector_busy
    # The queue was emptied: the next job (a host's) is not refused.
    assert client.read("fifo_free") == PLAYER_BOARD["vector_queue_depth"]
    pulses = len(board.pulses)
    board.run_for(0.5e-3)
    assert len(board.pulses) == pulses


def test_the_interlock_opening_stops_the_job():
    long_job = [("jump", 30000, 30000)] + [("mark", 30000 + 200 * k, 30000)
                                           for k in range(1, 40)]
    board = board_with(job_image(long_job, REGISTERS))
    client = HostClient(SimTransport(board))
    board.press_start(1.5e-3)
    while not board.pulses:
        board.run_for(0.2e-3)
    board.interlock_closed = False
    board.run_for(0.1e-3)
    status = player_status(client)
    assert status.state == PlayerState.IDLE and status.result == PlayerResult.FAULT
    pulses = len(board.pulses)
    board.interlock_closed = True
    board.run_for(0.5e-3)
    assert len(board.pulses) == pulses
    # A latched fault stays latched: the next press arms, sees it, and stops (no pulse).
    status = press_and_wait(board, client)
    assert status.result == PlayerResult.FAULT and len(board.pulses) == pulses


def test_a_short_glitch_on_the_start_input_starts_nothing():
    board = board_with(GOOD)
    client = HostClient(SimTransport(board))
    board.press_start(0.5e-3)          # half the debounce
    board.run_for(2e-3)
    assert player_status(client).result == PlayerResult.NONE
    assert board.engine.flash_counts() == (0, 0)       # (commands, ignored): never read
