"""The machine profile written back (galvoscan/profile/writer.py): a key changed is the only line
of the file that differs, every comment kept; each change checked by the profile reader (a bad
value one line, the document and the file as they were); what is written reads back, through
galvoscan's own reader (load_profile), as the profile that was set."""

import difflib
import math

import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.correction.files import save_table
from galvoscan.gateware.field.correction_table import CorrectionTable
from galvoscan.profile.keys import SECTIONS
from galvoscan.profile.machine import ProfileError, default_profile, load_profile
from galvoscan.profile.template import profile_text
from galvoscan.profile.writer import ProfileDocument, profile_key


def _changed_lines(before, after):
    """The lines of ``before`` that ``after`` changed or dropped, and the lines it added."""
    diff = list(difflib.unified_diff(before.splitlines(), after.splitlines(), lineterm="", n=0))
    return ([line[1:] for line in diff if line.startswith("-") and not line.startswith("---")],
            [line[1:] for line in diff if line.startswith("+") and not line.startswith("+++")])


def test_a_changed_key_is_the_only_line_that_differs():
    """Three keys of the template set: those three lines differ, and only they (every comment
    of the template kept, in its place); a key the template leaves commented out is added
    under its section."""
    document = ProfileDocument.default()
    template = profile_text()
    document.set_text("field.size_mm", "70")
    document.set_text("laser.prr_khz", "[30, 80]")
    document.set_text("galvo.polygon_scaled", "false")
    removed, added = _changed_lines(template, document.text())
    assert removed == ["size_mm = 110", "prr_khz = [20, 200]", "polygon_scaled = true"]
    assert added == ["size_mm = 70", "prr_khz = [30, 80]", "polygon_scaled = false"]
    assert [line for line in template.splitlines() if line.startswith("#")] == \
        [line for line in document.text().splitlines() if line.startswith("#")]
    document.set_text("link.port", "/dev/ttyACM0")
    lines = document.text().splitlines()
    port = lines.index('port = "/dev/ttyACM0"')
    assert lines.index("[link]") < port < lines.index("[laser]")


def test_a_round_trip_through_the_profile_reader(tmp_path):
    """Set, saved, and read back by galvoscan's reader (load_profile): the values set, every
    other key the default; saved again unchanged, the file is the same bytes."""
    path = tmp_path / "machine.toml"
    document = ProfileDocument.default(path)
    for name, text in (("field.size_mm", "163.5"), ("laser.prr_khz", "[25, 90]"),
                       ("defaults.prr_khz", "30"), ("galvo.mark_delay_us", "120"),
                       ("link.baud", "3_000_000"), ("laser.guide", "false"),
                       ("link.port", '"COM3"'), ("wobble.freq_hz", "750.5")):
        document.set_text(name, text)
    assert document.changed and not path.exists()          # nothing written until saved
    document.save()
    assert not document.changed
    read = load_profile(path)
    assert read == document.profile
    assert (read.field.size_mm, read.laser.prr_khz, read.defaults.prr_khz) == \
        (163.5, (25.0, 90.0), 30.0)
    assert (read.galvo.mark_delay_us, read.link.baud, read.laser.guide, read.link.port,
            read.wobble.freq_hz) == (120.0, 3_000_000, False, "COM3", 750.5)
    assert read.galvo.jump_delay_us == default_profile().galvo.jump_delay_us
    first = path.read_bytes()
    again = ProfileDocument.load(path)
    assert again.profile == read and not again.changed
    again.save()
    assert path.read_bytes() == first


def test_a_persons_own_comments_and_an_inline_comment_are_kept(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text("# The bench's laser, bought 2024\n[laser]\n"
                    "max_power_w = 20  # as rated\n\n# set by hand\n[field]\nsize_mm = 110\n")
    document = ProfileDocument.load(path)
    document.set_text("laser.max_power_w", "30")
    document.save()
    assert path.read_text() == ("# The bench's laser, bought 2024\n[laser]\n"
                                "max_power_w = 30  # as rated\n\n# set by hand\n[field]\n"
                                "size_mm = 110\n")


@pytest.mark.parametrize("name, text, words", [
    ("field.size_mm", "-3", "[field] size_mm must be a number from 1 to 2000 (mm), not -3"),
    ("field.size_mm", "wide",
     "[field] size_mm must be a number from 1 to 2000 (mm), not 'wide'"),
    ("laser.prr_khz", "[80, 30]", "lowest ≤ highest"),
    ("defaults.prr_khz", "250", "[defaults] prr_khz"),
    ("link.baud", "1.5", "[link] baud must be a whole number"),
    ("laser.guide", "maybe", "[laser] guide"),
    ("field.sze_mm", "70", "did you mean size_mm?"),
    ("fields.size_mm", "70", "did you mean [field]?"),
    ("size_mm", "70", "a key is named with its section"),
])
def test_a_bad_value_is_one_line_and_changes_nothing(tmp_path, name, text, words):
    """Refused by the profile reader's own checks (a cross-key one too: a default PRR outside
    the laser's range): one line naming the key, the document and the file as they were."""
    path = tmp_path / "machine.toml"
    document = ProfileDocument.default(path)
    document.save()
    before, profile = document.text(), document.profile
    with pytest.raises(ProfileError) as refused:
        document.set_text(name, text)
    said = str(refused.value)
    assert words in said and "\n" not in said, said
    assert document.text() == before and document.profile == profile
    assert not document.changed
    assert path.read_text() == before


def test_saved_where_its_correction_table_is_not_found_is_refused(tmp_path):
    """A relative correction table is the profile's folder's: a profile saved to another
    folder would lose it, so it is refused, one line, and nothing is written there."""
    folder = tmp_path / "machine"
    (folder / "tables").mkdir(parents=True)
    save_table(folder / "tables" / "lens.json", CorrectionTable.identity(5), source="test")
    path = folder / "galvoscan.toml"
    path.write_text('[field]\ncorrection = "tables/lens.json"\n')
    document = ProfileDocument.load(path)
    document.set_text("field.size_mm", "70")
    elsewhere = tmp_path / "other" / "galvoscan.toml"
    elsewhere.parent.mkdir()
    with pytest.raises(ProfileError, match="correction: no file"):
        document.save(elsewhere)
    assert list(elsewhere.parent.iterdir()) == []
    document.save()
    assert load_profile(path).field.size_mm == 70 and \
        load_profile(path).correction_table().n == 5


_NAMES = [f"{section}.{key.name}" for section, keys in SECTIONS.items() for key in keys
          if key.kind != "path"]
_VALUES = st.one_of(st.integers(-10**7, 10**7), st.floats(allow_nan=True, allow_infinity=True),
                    st.booleans(), st.text(max_size=12),
                    st.lists(st.floats(-1e3, 1e3), max_size=3))


@settings(max_examples=100, deadline=None)
@given(name=st.sampled_from(_NAMES), value=_VALUES)
def test_whatever_is_set_is_refused_in_one_line_or_reads_back_as_set(tmp_path_factory, name,
                                                                     value):
    """Any value for any key: refused in one line with the document as it was, or set, and
    then the text read back by the profile reader holds that value."""
    path = tmp_path_factory.mktemp("p") / "machine.toml"
    document = ProfileDocument.default(path)
    before = document.text()
    try:
        document.set(name, value)
    except ProfileError as error:
        assert "\n" not in str(error)
        assert document.text() == before
        return
    document.save()
    read = load_profile(path)
    key = profile_key(name)
    got = getattr(getattr(read, key.section), key.name)
    if key.kind == "pair":
        assert got == tuple(float(v) for v in value)
    elif isinstance(value, float) and math.isnan(value):
        pytest.fail("a NaN was accepted")
    else:
        assert got == value
