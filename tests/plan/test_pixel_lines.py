"""A photo planned as pixel lines (issue 37): the segments decoded as the board steps them (a
decoder written here from the register map's words, not the planner's code) light exactly the
dithered grid's dark cells, each line swept back and forth with its scan offset, run in and
out dark; and what cannot be marked that way is refused in one line."""

import math

import numpy as np
import pytest
from PIL import Image

from galvoscan.api import Job, Photo, PlanError, plan
from galvoscan.inputs.photo import PhotoSpec, photo_bitmap
from galvoscan.profile.machine import default_profile


def picture(path, rows=40, columns=60):
    """A picture with a dark disc, a gradient and a lone dark pixel."""
    y, x = np.mgrid[0:rows, 0:columns]
    grey = np.clip(40 + 4 * x, 0, 255)
    grey[(x - 20) ** 2 + (y - 20) ** 2 < 80] = 0
    grey[35, 50] = 0
    Image.fromarray(grey.astype(np.uint8)).save(path)
    return path


def decode(segments, pitch):
    """``[(direction, [(x, y, bit)])]`` per pixel line: its points one pitch apart from where
    the jump before it left the head, each with its bit (vec_x bit k, then vec_y, bit 0
    first)."""
    here, lines = None, []
    k = 0
    while k < len(segments):
        op, x, y = segments[k]
        if op == "jump":
            here = (x, y)
        elif op == "line":
            assert y == here[1], "a photo's line is horizontal"
            steps, rest = divmod(abs(x - here[0]), pitch)
            assert rest == 0, "a line is a whole number of pitches"
            direction = 1 if x > here[0] else -1
            words = []
            while k + 1 < len(segments) and segments[k + 1][0] == "pixels":
                k += 1
                words.append(segments[k][1] | segments[k][2] << 16)
            bits = [(word >> b) & 1 for word in words for b in range(32)]
            assert len(bits) - 32 < steps + 1 <= len(bits), "as many words as the line needs"
            lines.append((direction, [(here[0] + direction * pitch * n, y, bits[n])
                                      for n in range(steps + 1)]))
            here = (x, y)
        else:
            raise AssertionError(f"a photo as pixel lines has no {op}")
        k += 1
    return lines


@pytest.fixture
def photo(tmp_path):
    return picture(tmp_path / "photo.png")


def test_the_lines_light_exactly_the_dark_cells_with_the_scan_offset(photo):
    profile = default_profile()
    planned = plan(Job(photos=(Photo(str(photo), 3.0),), speed_mm_s=800), profile)
    job = planned.vector_job
    pitch = job.registers["pitch"]
    units_per_mm = 65536 / profile.field.size_mm
    assert pitch == round(profile.laser.spot_mm * units_per_mm)
    cell = pitch / units_per_mm
    dark = photo_bitmap(PhotoSpec(str(photo), 3.0, cell))
    rows, columns = dark.shape
    # The cells' centres, galvo units: the grid centred on the field's centre.
    centre_x = lambda c: round((-columns * cell / 2 + (c + 0.5) * cell) * units_per_mm + 32768)  # noqa: E731
    centre_y = lambda r: round((rows * cell / 2 - (r + 0.5) * cell) * units_per_mm + 32768)  # noqa: E731
    offset = round(job.pitch.speed_mm_s * 80e-6 * units_per_mm)
    assert offset > 0
    lines = decode(job.segments, pitch)
    assert len(lines) == sum(1 for r in range(rows) if dark[r].any())
    directions = [direction for direction, _ in lines]
    assert directions == [(-1) ** n for n in range(len(lines))], "back and forth"
    marked_rows = [r for r in range(rows) if dark[r].any()]
    for (direction, points), r in zip(lines, marked_rows):
        lit = sorted(x for x, y, bit in points if bit)
        assert {y for _, y, _ in points} == {centre_y(r)}
        # Each dark cell of the row, sent the tracking delay ahead in the line's direction.
        assert lit == sorted(centre_x(c) + direction * offset for c in np.flatnonzero(dark[r]))
        # Run in and out dark, over three tracking delays at the line's speed at least.
        run_mm = 3 * job.pitch.speed_mm_s * 80e-6
        ends = [x for x, _, _ in points]
        first_lit = min(lit) if direction > 0 else max(lit)
        last_lit = max(lit) if direction > 0 else min(lit)
        assert abs(first_lit - ends[0]) >= run_mm * units_per_mm - pitch
        assert abs(ends[-1] - last_lit) >= run_mm * units_per_mm - pitch
    # The link words: a line, its jump and a word each 32 points, not a mark a run of cells.
    runs = plan(Job(photos=(Photo(str(photo), 3.0, lines="runs"),), speed_mm_s=800), profile)
    assert len(job.segments) * 2 < len(runs.segments)


def test_one_way_lines_all_go_left_to_right(photo):
    planned = plan(Job(photos=(Photo(str(photo), 3.0, one_way=True),)))
    assert {d for d, _ in decode(planned.segments, planned.vector_job.registers["pitch"])} \
        == {1}


def test_the_pixel_lines_speed_is_a_pulse_count_at_their_pitch_and_the_delays_step_aside(photo):
    profile = default_profile()
    job = plan(Job(photos=(Photo(str(photo), 3.0),), speed_mm_s=1000, prr_khz=50),
               profile).vector_job
    pitch_mm = job.registers["pitch"] * profile.field.size_mm / 65536
    n = job.registers["pulses_per_point"]
    assert job.pitch.speed_mm_s == pytest.approx(pitch_mm * 50e3 / n)
    assert n == min((1, 2, 3, 4), key=lambda k: abs(pitch_mm * 50e3 / k - 1000))
    assert job.registers["laser_on_delay"] == job.registers["laser_off_delay"] == 0
    assert any("laser_on_delay" in note for note in job.notes)
    # Every line's time, and the jumps': within 1.2 × lines × length ÷ speed.
    lines = decode(job.segments, job.registers["pitch"])
    sweep_s = sum(len(points) for _, points in lines) * pitch_mm / job.pitch.speed_mm_s
    assert sweep_s <= job.estimate_s <= 1.2 * sweep_s


def test_a_photo_whose_run_in_leaves_the_field_is_refused(photo):
    edge = 110 / 2 - 1.6          # the photo's side 0.1 mm inside the field's
    with pytest.raises(PlanError, match="run in and out .* past its sides .* move it"):
        plan(Job(photos=(Photo(str(photo), 3.0, at_mm=(edge, 0.0)),), speed_mm_s=2000))


def test_an_unknown_way_of_marking_a_photo_is_one_line():
    with pytest.raises(PlanError, match="pixels or runs, not 'dots'"):
        Photo("a.png", 3.0, lines="dots")


def test_a_pixel_line_job_ends_on_a_jump_to_where_its_last_line_ends(photo):
    from galvoscan.outputs.queue_words import job_segments
    planned = plan(Job(photos=(Photo(str(photo), 3.0),)))
    sent = job_segments(planned.segments)
    last_line = next(s for s in reversed(planned.segments) if s[0] == "line")
    assert sent[-1] == ("jump", *last_line[1:])
    assert math.isclose(len(sent), len(planned.segments) + 1)
