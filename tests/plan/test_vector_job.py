"""A vector job's jumps (galvoscan/plan/vector_job.py): held as long as their lengths need by
the profile's default variable jump delay, a photo's estimate against one delay for every
jump, and what the link brings against what the board takes."""

from galvoscan import api
from galvoscan.outputs.link_budget import expected_underruns, link_segments_per_s
from galvoscan.profile.machine import default_profile, parse_profile
from photos import grey_photo


def test_a_photos_estimate_drops_with_the_default_jump_delays(tmp_path):
    """The 30 mm photo: its thousands of short gaps wait 240 µs and a little, not the 500 µs
    of a jump across the field, as they did with one delay for every jump; the holds add few
    segments, and the link at 1 Mbaud still brings them faster than the board takes them."""
    job = api.Job(photos=(api.Photo(str(grey_photo(tmp_path / "grey.png")), 30.0,
                                    lines="runs"),))
    one_delay = api.plan(job, parse_profile("[galvo]\njump_length_limit_mm = 0\n")).vector_job
    variable = api.plan(job, default_profile()).vector_job
    assert one_delay.registers["jump_delay"] == 500
    jumps = sum(op == "jump" for op, _, _ in one_delay.segments)
    assert jumps > 50_000
    # Every jump 500 µs and a frame before; now at least 240 µs and a frame, most of them.
    assert variable.estimate_s < one_delay.estimate_s - jumps * (510 - 300) * 1e-6
    assert len(one_delay.segments) < len(variable.segments) < 1.1 * len(one_delay.segments)
    assert expected_underruns(variable, 1_000_000) == []


def test_the_shortest_jump_outlasts_the_link_bringing_it_and_its_mark():
    """Whatever a photo's dark cells, a jump and its mark take the board no less time than the
    link at the profile's baud takes to bring those two segments: the default short-jump delay
    and its frame (the board counts 10 µs frames) against 2 segments at 8,268 a second."""
    profile = default_profile()
    frames = 1 + -(-profile.jump_delay_register(0) // 10)
    assert frames * 10e-6 >= 2 / link_segments_per_s(profile.link.baud)
