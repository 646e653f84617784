"""A part's I/O (galvoscan/plan/part_io.py): the steps queued before and after a part, as the
docs give them (the held output cleared, the wait on an edge with its time-out in ms, the fly
started at the part), the line it says, and the settings refused in one line."""

import math

import pytest

from galvoscan.gateware.fields import IOKind
from galvoscan.geometry.field import PlanError
from galvoscan.plan.part_io import PartIO, part_io
from galvoscan.settings.schema import SettingError


def kinds(steps):
    return [(s.kind, s.index, s.level, s.edge, s[1]) for s in steps]


def test_a_part_waits_for_the_sensor_and_pulses_done():
    io = part_io(wait_input="part", set_output="done")
    assert io.wait_timeout_s == 60 and io.output_pulse_ms == 10 and io.wait_level == "high"
    assert kinds(io.before()) == [(IOKind.WAIT_INPUT, 0, 1, True, 60_000)]
    assert kinds(io.after()) == [(IOKind.SET_OUTPUT, 0, 1, False, 1000)]   # 10 ms: 1000 frames
    assert io.wait_s == 60


def test_on_the_fly_the_fly_starts_at_the_part():
    io = part_io(wait_input="in1", wait_level="low", wait_timeout_s=0, set_output="out1",
                 output_pulse_ms=0)
    assert kinds(io.before(fly=True)) == [
        (IOKind.SET_OUTPUT, 1, 0, False, 0),         # the last part's held output cleared
        (IOKind.WAIT_INPUT, 1, 0, True, 0),          # no time-out
        (IOKind.FLY_START, 0, 1, False, 0)]
    assert kinds(io.after(fly=True)) == [(IOKind.FLY_END, 0, 1, False, 0),
                                         (IOKind.SET_OUTPUT, 1, 1, False, 0)]
    assert io.wait_s == math.inf
    assert "for as long as it takes" in io.line() and "until the next part's wait" in io.line()


def test_an_output_alone_waits_for_nothing():
    io = part_io(set_output="done", output_pulse_ms=655.35)
    assert io.before(fly=True) == [] and io.wait_s == 0
    assert kinds(io.after(fly=True)) == [(IOKind.SET_OUTPUT, 0, 1, False, 65535)]
    assert io.line() == "I/O: sets output done (output 0) for 655.35 ms once it is marked"


def test_no_io_is_none():
    assert part_io() is None


@pytest.mark.parametrize("settings, error, message", [
    (dict(wait_level="low"), PlanError, "--wait-level is a wait's: give --wait-input too"),
    (dict(wait_timeout_s=3), PlanError, "--wait-timeout is a wait's"),
    (dict(output_pulse_ms=3), PlanError, "--output-pulse is an output's"),
    (dict(wait_input="belt"), SettingError, "wait input must be part, in1, not 'belt'"),
    (dict(wait_input="part", wait_timeout_s=65.536), SettingError, "wait timeout must be"),
    (dict(set_output="done", output_pulse_ms=-0.01), SettingError, "output pulse must be"),
    (dict(set_output="done", output_pulse_ms=float("nan")), SettingError, "output pulse"),
])
def test_wrong_settings_are_one_line(settings, error, message):
    with pytest.raises(error, match=message.replace("(", r"\(")) as refused:
        part_io(**settings)
    assert "\n" not in str(refused.value)


def test_a_part_io_needs_something_to_do():
    with pytest.raises(PlanError, match="waits for an input or sets an output"):
        PartIO()


def test_the_settings_pages_io_table_is_the_declarations():
    from pathlib import Path
    from galvoscan.settings.io import IO_SETTINGS
    from galvoscan.settings.schema import markdown_table
    page = (Path(__file__).parents[2] / "docs" / "reference" / "settings.md").read_text(
        encoding="utf-8")
    assert markdown_table(IO_SETTINGS) in page


def test_a_sensor_before_the_drawing_waits_for_the_encoder():
    """1.5 mm at 200 counts/mm: the count zeroed at the sensor, a wait for 300 counts up, then
    the fly's start; a distance past the count's 31 bits, or off the fly, refused."""
    class Fly:
        counts_per_mm = 200.0
    io = part_io(wait_input="part", sensor_distance_mm=1.5)
    assert kinds(io.before(fly=Fly())) == [
        (IOKind.WAIT_INPUT, 0, 1, True, 60_000), (IOKind.FLY_START, 0, 1, False, 0),
        (IOKind.FLY_END, 0, 1, False, 0), (IOKind.WAIT_COUNT_UP, 0, 1, False, 300),
        (IOKind.FLY_START, 0, 1, False, 0)]
    Fly.counts_per_mm = 10_000.0
    far = part_io(wait_input="part", sensor_distance_mm=9_000)
    big = far.before(fly=Fly())[3]
    assert (big[2] << 16 | big[1]) == 90_000_000
    Fly.counts_per_mm = 250_000.0
    with pytest.raises(PlanError, match="the board counts to 2,147,483,647"):
        far.before(fly=Fly())
    with pytest.raises(PlanError, match="--sensor-distance is on the fly: give --fly too"):
        io.before(fly=None)
    with pytest.raises(PlanError, match="--sensor-distance is a wait's"):
        part_io(set_output="done", sensor_distance_mm=2)


def test_a_wait_is_led_by_a_jump_to_the_parts_first_point():
    """With where the part starts, its wait comes after a jump there (a word the board takes
    only once it runs); an output alone needs none."""
    from galvoscan.plan.part_io import first_point
    segments = [("jump", 100, 200), ("mark", 300, 200)]
    io = part_io(wait_input="part", set_output="done")
    steps = io.before(at=first_point(segments))
    assert steps[0] == ("jump", 100, 200) and steps[1].kind == IOKind.WAIT_INPUT
    assert part_io(set_output="done").before(at=(1, 2)) == []
    assert first_point([("mark", 1, 2)]) is None and first_point([]) is None
