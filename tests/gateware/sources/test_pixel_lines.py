"""Pixel lines (issue 37): a line swept at one speed, each point lit or not by a bit of the
pixel words queued after it. The points and pulses decoded off the XY2-100 wires and the DB25
pins against the plain model of tests/support/vector_model.py (Wan et al.'s DDA, each point's
bit taken in order), on the jobs' build."""

import random

import pytest

from vector_board import NO_DELAYS, runs_on_the_wires, set_up_job, start_board
from vector_model import PARK, job_model, merge, pixel_bits


PITCH = 60


def run(job, *, pulses=1, prr_100hz=600, clk_freq=4e6, backend="compiled"):
    board, _ = start_board(clk_freq, backend=backend)
    client = set_up_job(board, job, [("laser_prr", prr_100hz), ("pulses_per_point", pulses),
                                     ("pitch", PITCH), ("jump_delay", 50),
                                     *NO_DELAYS.items(), ("laser_power", 200)])
    expected = merge([(PARK, 0)] + job_model(job, PITCH, pulses))
    points = sum(1 for _ in expected)
    deadline = board.now + points * pulses * 2 / (prr_100hz * 100) + 2e-3
    while board.now < deadline and runs_on_the_wires(board) != expected:
        board.run_for(0.2e-3)
    board.run_for(0.5e-3)
    return board, client, expected


def words_of(bits):
    """Pixel words (x, y) carrying ``bits``, bit 0 first."""
    words = []
    for start in range(0, len(bits), 32):
        value = sum(bit << k for k, bit in enumerate(bits[start:start + 32]))
        words.append(("pixels", value & 0xFFFF, value >> 16))
    return words


def line_job(bits, *, x0=20000, y=30000, reverse=False):
    """A jump to the line's start, the line (one point a bit), and its words."""
    n = len(bits) - 1
    x1 = x0 - n * PITCH if reverse else x0 + n * PITCH
    return [("jump", x0, y), ("line", x1, y)] + words_of(bits)


def test_the_words_bits_are_the_words_as_the_register_map_says():
    assert pixel_bits([(0b101, 0x8000)]) == [1, 0, 1] + [0] * 28 + [1]
    assert words_of([1, 0, 1] + [0] * 28 + [1]) == [("pixels", 0b101, 0x8000)]


@pytest.mark.parametrize("seed", [1, 2])
def test_each_point_of_a_line_is_lit_by_its_own_bit(seed):
    """Two lines there and back (bidirectional), 70 and 45 points of random bits: every
    point on the wires, lit with its pulses exactly where its bit is 1."""
    rng = random.Random(seed)
    first = [rng.randrange(2) for _ in range(70)]
    second = [rng.randrange(2) for _ in range(45)]
    job = line_job(first) + line_job(second, x0=20000 + 69 * PITCH, y=30060, reverse=True) + \
        [("jump", 32768, 32768)]
    board, client, expected = run(job, pulses=2)
    assert runs_on_the_wires(board) == expected
    # The model: the lit points are exactly the 1 bits, two pulses each.
    lit = [pulses for (_, pulses) in expected if pulses]
    assert lit == [2] * (sum(first) + sum(second))
    assert client.read("vec_underruns") == 0
    assert client.read("errors") == 0


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_a_line_short_of_words_is_dark_past_them_and_a_stray_word_lights_nothing(backend):
    """33 points with one word: the 33rd is dark. A word after a jump (no line) is dropped:
    the mirrors do not move for it and nothing is lit. On both simulators: Amaranth's and the
    compiled one."""
    bits = [1, 0, 1, 1] * 8
    job = [("jump", 20000, 30000), ("line", 20000 + 32 * PITCH, 30000)] + words_of(bits) + \
        [("jump", 25000, 25000), ("pixels", 0xFFFF, 0xFFFF), ("jump", 32768, 32768)]
    board, client, expected = run(job, backend=backend)
    on_wires = runs_on_the_wires(board)
    assert on_wires == expected
    assert on_wires[-3:] == [((20000 + 32 * PITCH, 30000), 0), ((25000, 25000), 0),
                             ((32768, 32768), 0)]


def test_dark_and_lit_points_are_held_alike_the_line_keeps_its_speed():
    """Each point of a line, lit or dark, is held for the same frames (the pulses it would
    get): one speed along the line, whatever the picture."""
    bits = [1, 0] * 10 + [0] * 5 + [1] * 5
    job = line_job(bits) + [("jump", 32768, 32768)]
    board, client, expected = run(job, pulses=3, prr_100hz=300)
    frames = [f for _, f in board.xy2_frames()]
    line = [(20000 + k * PITCH, 30000) for k in range(len(bits))]
    held = [sum(1 for f in frames if f == point) for point in line[1:-1]]
    # 3 pulses at 30 kHz: 100 µs, 10 frames; every point alike (±1 for the PRR's phase).
    assert max(held) - min(held) <= 1 and 9 <= min(held) <= 11
