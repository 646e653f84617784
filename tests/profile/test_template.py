"""The profile template (galvoscan/profile/template.py): where its default jump delays come
from, said in its comment, is what the mirror model and the link give."""

import re

import pytest

from galvoscan.analysis.galvo import GalvoModel
from galvoscan.profile.machine import default_profile
from galvoscan.profile.template import profile_text

from link_codec import FRAME_LINE_BITS


def comment():
    return " ".join(line.lstrip("# ") for line in profile_text().splitlines()
                    if line.startswith("#"))


def test_the_jump_delays_model_figures_are_the_models():
    """Wan et al.'s galvo, as the analysis models it: a jump of a few cells and one of 5 mm come
    within 10 µm of their ends in the times the template says (to 5 %), and the default
    jump delays for those lengths are no shorter than those times (to 5 %)."""
    found = re.search(r"where a ([\d.]+) mm jump comes within (\d+) µm of its end in about "
                      r"(\d+) µs and a ([\d.]+) mm one in about (\d+) µs", comment())
    assert found, "the template's mirror model figures"
    short_mm, band_um, short_us, long_mm, long_us = map(float, found.groups())
    galvo = GalvoModel.from_step_times()
    profile = default_profile()
    units_per_mm = profile.units_per_mm
    for mm, said in ((short_mm, short_us), (long_mm, long_us)):
        step = mm * units_per_mm
        settled_us = galvo.step_time(step, band=band_um / 1000 / mm, substeps=4) * 1e6
        assert settled_us == pytest.approx(said, rel=0.05), mm
        assert profile.jump_delay_register(mm) >= 0.95 * settled_us, mm


def test_the_link_figure_is_the_links():
    found = re.search(r"at ([\d,]+) baud it takes (\d+) µs to bring a jump and its mark",
                      comment())
    assert found
    baud = int(found[1].replace(",", ""))
    assert baud == default_profile().link.baud
    assert int(found[2]) == round(2 * FRAME_LINE_BITS / baud * 1e6)


def test_the_default_jump_delays_are_no_shorter_than_the_model_needs():
    """From a cell's jump to the limit length, the default delay is no more than 5 % short
    of what the modelled galvo takes to come within 10 µm (a fifth of the default spot)."""
    galvo = GalvoModel.from_step_times()
    profile = default_profile()
    for mm in (0.05, 0.1, 0.2, 0.5, 1, 2, 3, 4, 5):
        step = mm * profile.units_per_mm
        settled_us = galvo.step_time(step, band=0.010 / mm, substeps=4) * 1e6
        assert profile.jump_delay_register(mm) >= 0.95 * settled_us, (mm, settled_us)
