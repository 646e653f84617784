# amaranth: UnusedElaboratable=no
"""One build configuration: its rules, what it implies, and that the boards, the presets and
the simulated board all take it."""

import dataclasses

import pytest

from galvoscan.build import PRESETS, board_config, build_bitstream, preset_register_map
from galvoscan.gateware.build_config import BuildConfig
from galvoscan.gateware.top import GalvoScanTop
from galvoscan.platforms.icebreaker import ALARM_PMOD_PINS, CRYSTAL_HZ


def test_the_options_are_normalised_once():
    config = BuildConfig(modes=("raster", "vector"), spiral_interpolation=True, laser=True)
    # The interpolator is the spiral's: without the spiral there is none to build.
    assert config.spiral_interpolation is False
    assert config.baud == 1_000_000
    assert BuildConfig(modes=("spiral",), laser=False).laser_alarms == 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.player = True


@pytest.mark.parametrize("options, message", [
    (dict(modes=()), "modes must be some of"),
    (dict(modes=("spiral", "spiral")), "each once"),
    (dict(laser_alarms=5), "laser_alarms must be a whole number from 0 to 4"),
    (dict(laser_alarms=True), "laser_alarms must be a whole number"),
    (dict(vector_queue_depth=1), "vector_queue_depth must be a whole number from 2"),
    (dict(wobble=True, modes=("spiral",)), "it needs vector mode"),
    (dict(player=True, modes=("spiral", "raster")), "the job player plays vector jobs"),
    (dict(vector_delays=True, clk_freq=12.5e6, bit_rate=1.25e6),
     "the vector delays count whole µs"),
    (dict(mo_lead=0), "mo_lead must be a positive time"),
    (dict(pixel_lines=True), "pixel lines come with vector mode's delays"),
    (dict(head_check=True), "head_check makes the laser obey the head's status"),
    (dict(head_status=True, laser=False, modes=("spiral",), head_check=True),
     "head_check makes the laser obey"),
    (dict(vector_delays=True, queue_io=True), "I/O in the queue comes with pixel lines"),
    (dict(head_status=True, clk_freq=4e6, baud=500_000),
     "the head status receiver samples a bit 2 clocks after its middle"),
])
def test_bad_options_are_refused_at_construction(options, message):
    with pytest.raises(ValueError, match=message):
        BuildConfig(**options)


def test_the_caps_register_is_what_the_configuration_built():
    # The caps bits in the order the README's register table gives them, bit 0 first.
    order = ("spiral", "raster", "vector", "laser", "correction", "wobble", "delays",
             "interpolation", "uart", "spi", "player", "pixel_lines", "head", "fly", "z", "io")
    for name, config in PRESETS.items():
        caps = preset_register_map(name)["caps"].reset
        built = {flag: bool(caps >> bit & 1) for bit, flag in enumerate(order)}
        assert built == config.capabilities()
        assert built["player"] == (name == "marker")
        assert built["interpolation"] == (name == "cleaner")
        assert built["spi"] == (name != "marker")       # the player takes the SPI pins
        assert built["pixel_lines"] == (name == "engraver")
        assert built["delays"] == (name in ("marker", "engraver"))
        assert built["correction"] and built["laser"] and built["uart"]


def test_the_default_bitstream_is_the_iCEBreakers_default():
    config = PRESETS["default"]
    assert config == board_config("icebreaker")
    assert config.modes == ("spiral", "raster", "vector")
    assert config.laser_alarms == len(ALARM_PMOD_PINS[1].split())
    assert not (config.spiral_interpolation or config.vector_delays or config.wobble or
                config.player)
    assert config.clk_freq == CRYSTAL_HZ and PRESETS["marker"].clk_freq == 24e6


def test_the_top_takes_a_configuration_or_its_options_not_both():
    top = GalvoScanTop(PRESETS["cleaner"])
    assert top.config is PRESETS["cleaner"]
    assert "spiral_interp" in top.regmap and "vec_op" not in top.regmap
    assert GalvoScanTop(clk_freq=12e6, modes=("spiral",)).config.modes == ("spiral",)
    with pytest.raises(TypeError, match="in its BuildConfig, not as modes"):
        GalvoScanTop(PRESETS["default"], modes=("spiral",))
    with pytest.raises(TypeError, match="in its config, not as wobble"):
        build_bitstream("icebreaker", config=PRESETS["default"], wobble=True)
