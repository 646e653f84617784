"""Machine profiles written out for the tests: the defaults as the template must give them,
and a profile's text from its keys."""

DEFAULTS = {
    "field": {"size_mm": 110.0, "correction": None, "z_units_per_mm": 0.0},
    "link": {"port": None, "baud": 1_000_000, "spi": None, "timeout_s": 0.5},
    "laser": {"max_power_w": 20.0, "prr_khz": [20.0, 200.0], "spot_mm": 0.05, "guide": True},
    "galvo": {"jump_delay_us": 500.0, "min_jump_delay_us": 240.0, "jump_length_limit_mm": 5.0,
              "max_speed_mm_s": 10_000.0,
              "laser_on_delay_us": 100.0, "laser_off_delay_us": 50.0, "mark_delay_us": 100.0,
              "polygon_delay_us": 0.0, "polygon_scaled": True, "tracking_delay_us": 80.0,
              "head_check": False},
    "defaults": {"speed_mm_s": 1000.0, "power_percent": 10.0, "prr_khz": 50.0, "passes": 1},
    "wobble": {"across_um": 0.0, "along_um": 0.0, "freq_hz": 1000.0},
}


def toml(entries):
    """A profile's text from ``{(section, key): "TOML value"}``."""
    sections = {}
    for (section, key), value in entries.items():
        sections.setdefault(section, []).append(f"{key} = {value}")
    return "".join(f"[{section}]\n" + "".join(f"{line}\n" for line in lines)
                   for section, lines in sections.items())
