"""``galvoscan bench``: the quick run's figures against what the protocols allow."""

import json

import pytest

from galvoscan.cli import main


def test_bench_quick(capsys):
    # On the compiled board: the run measures the Python backend's speed too, and streaming
    # over the Python backend (96 s of the suite as a second run) is the link tests' and
    # test_compiled's, record for record.
    backend = "compiled"
    assert main(["bench", "--quick", "--json", "--backend", backend]) == 0
    result = json.loads(capsys.readouterr().out)
    # XY2-100: 20 bits at 2 Mbit/s, back to back; XY2-200 twice that.
    assert result["frames_per_s"] == 100_000 and result["idle_clocks"] == 0
    assert result["xy2_200"]["frames_per_s"] == 200_000
    assert result["xy2_200"]["idle_clocks"] == 0
    link = result["link"]
    # SPI: 80 bits of two half periods at SCK = 12 MHz / 12, plus half a period before cs_n
    # rises and four with it high: the host this bench plays.
    assert abs(link["spi_frames_per_s"] - 1 / ((2 * 80 + 5) * 0.5e-6)) < 1
    # UART: a frame's ten bytes COBS-encoded (one byte more) and the zero after them, 10-bit
    # characters back to back at 115 200 baud.
    assert abs(link["uart_frames_per_s"] - 115_200 / 120) < 1
    # A jump reaches the wires within a few 10 µs frames (DDA set-up, then the frame boundary,
    # then the frame itself).
    for name in ("spi", "uart"):
        assert 10 < link[f"{name}_latency_us"] <= link[f"{name}_latency_max_us"] < 40
    # Vector segments streamed over the UART at the default 1 Mbaud: one 12-byte frame a
    # segment on the line (ten bytes, COBS's one, the zero), 10 bits a byte, and the wait for
    # the last answer of each batch: under 8 333 a second, and at least 5 000 (what 1 mm
    # segments at 5 m/s need).
    stream = link["stream"]
    assert stream["baud"] == 1_000_000 and stream["errors"] == 0
    assert stream["backend"] == backend
    # The ULX3S bitstream's link: 3 Mbaud, the same 12 bytes a segment, at least the 20,000
    # segments a second a photo's dots need, under the line's 25,000.
    ulx3s = link["stream_ulx3s"]
    assert ulx3s["baud"] == 3_000_000 and ulx3s["clock_mhz"] == 24 and ulx3s["errors"] == 0
    assert 20_000 <= ulx3s["segments_per_s"] < 3_000_000 / 10 / 12
    # A strip of the bench's photo (quick mirrors), streamed whole at 3 Mbaud: no underrun
    # foretold or counted there, and some foretold at 1 Mbaud; every segment (a jump after
    # each mark, the job's last one added) taken.
    photo = link["photo"]
    assert photo["baud"] == 3_000_000 and photo["segments"] == 2 * photo["marks"] + 1
    assert photo["underruns"] == photo["foretold_underruns"]["3"] == 0 < \
        photo["foretold_underruns"]["1"]
    assert photo["errors"] == photo["rejected"] == 0 and photo["board_s"] > photo["estimate_s"]
    # The same strip as pixel lines, on the engraver's bitstream at 1 Mbaud: a line a row
    # with a dark cell, far fewer segments, no underrun, the pulses a whole number of cells'.
    pixels = link["photo_pixels"]
    assert pixels["lines"] == "pixels" and pixels["baud"] == 1_000_000
    # (16 rows of pixels, 24 mm wide at 50 µm: 480 × 19 cells, so 19 lines at most.)
    assert 0 < pixels["pixel_lines"] <= 19 and pixels["segments"] * 4 < photo["segments"]
    assert pixels["underruns"] == pixels["errors"] == pixels["rejected"] == 0
    assert pixels["pulses"] > 0 and pixels["pulses"] % pixels["pulses_per_point"] == 0
    assert pixels["board_s"] > pixels["estimate_s"]
    # Both boards' default bitstreams on the compiled board, against real time.
    assert set(result["real_time"]) == {"icebreaker", "ulx3s"}
    assert [f["clock_mhz"] for f in result["real_time"].values()] == [12, 24]
    assert all(f["clocks_per_s"] > 0 for f in result["real_time"].values())
    # Both backends, measured in the same run.
    backends = result["backends"]
    assert backends["compiled_clocks_per_s"] > backends["python_clocks_per_s"] > 0
    assert 5000 <= 0.97 * 1_000_000 / 10 / 12 <= stream["segments_per_s"] < 1_000_000 / 10 / 12
    assert "boards" in result and result["boards"] == {}


def test_suite_needs_a_checkout(tmp_path, capsys):
    """``--suite`` names a checkout with tests: anything else is one line, before the run."""
    import pytest
    with pytest.raises(SystemExit) as stop:
        main(["bench", "--quick", "--suite", str(tmp_path)])
    message = str(stop.value)
    assert "not a galvoscan checkout" in message and "\n" not in message


def test_table_shows_seeds_proofs_and_suite():
    """The benchmark table's rows for the three placer seeds, all proofs and the suite, from
    figures typed here."""
    from galvoscan.bench import table
    board = {"modes": ["spiral"], "correction_nodes": 17, "clock_mhz": 12, "bit_rate_mhz": 2,
             "luts": 4900, "luts_available": 5280, "brams": 15, "dsps": 5, "meets_timing": True,
             "build_s": 200}
    result = {
        "xy2_100": {"frames_per_s": 100000, "idle_clocks": 0},
        "xy2_200": {"frames_per_s": 200000, "idle_clocks": 0},
        "link": {f"{n}_{k}": 1.0 for n in ("spi", "uart")
                 for k in ("frames_per_s", "latency_us", "latency_max_us")},
        "boards": {"icebreaker": {**board, "fmax_mhz": 25.0, "placer": "static"},
                   "icebreaker_seed2": {**board, "fmax_mhz": 24.2},
                   "icebreaker_seed3": {**board, "fmax_mhz": 26.0},
                   "marker": {**board, "modes": ["vector"], "options": ["delays", "player"],
                              "clock_mhz": 24, "fmax_mhz": 25.4},
                   **{label: {**board, "logic": "LUT4s", "luts": 5929, "luts_available": 24288,
                              "clock_mhz": 24, "fmax_mhz": fmax}
                      for label, fmax in (("ulx3s", 54.7), ("ulx3s_seed2", 50.1),
                                          ("ulx3s_seed3", 52.0))}},
        "proofs": {"a": {"prove": {"status": "PASS", "seconds": 10.0}},
                   "b": {"prove": {"status": "PASS", "seconds": 5.0},
                         "cover": {"status": "PASS", "seconds": 20.0}}},
        "proofs_s": 35.0,
        "suite": {"seconds": 600.0, "passed": 800, "skipped": 2},
        "bench_s": 60,
    }
    text = table(result)
    assert "| default build, lowest Fmax of 3 placer seeds | 24.2 MHz (2.02× its 12 MHz) |" \
        in text
    assert "| ULX3S build (every feature), lowest Fmax of 3 placer seeds | 50.1 MHz (2.09× " \
        "its 24 MHz) |" in text
    assert "5929 / 24288 LUT4s, 15 RAMs" in text
    assert "Fmax 25.0 MHz (met), static placer, 200 s |" in text
    assert "Fmax 24.2 MHz (met), heap placer, 200 s |" in text
    assert "| build marker (vector, delays, player; correction 17; 24 MHz, 2 Mbit/s) | " \
           "4900 / 5280 logic cells" in text
    assert "| every proof and cover, one after another | 35 s |" in text
    assert "| test suite (the README's test command, on every core) | 10.0 min, 800 passed, " \
           "2 skipped |" in text


def test_the_production_features_cells_are_their_blocks():
    """Each feature's cells: the sum of its blocks and the blocks under them (figures typed
    here), nothing of another's; the table says them."""
    from galvoscan.bench import feature_cells, table
    blocks = {"top.fly_scale": {"luts": 300, "ffs": 100}, "top.fly": {"luts": 70, "ffs": 0},
              "top.encoder_x": {"luts": 140, "ffs": 50}, "top.encoder_x.sync": {"luts": 0,
                                                                                "ffs": 4},
              "top.flyer": {"luts": 999, "ffs": 999},        # (not the fly's: another name)
              "top.head": {"luts": 56, "ffs": 50}, "top.head.sync": {"luts": 0, "ffs": 2},
              "top.queue_io": {"luts": 267, "ffs": 133}}
    cells = feature_cells(blocks)
    assert cells["marking on the fly"] == {"luts": 510, "ffs": 154}
    assert cells["head status"] == {"luts": 56, "ffs": 52}
    assert cells["I/O in the queue"] == {"luts": 267, "ffs": 133}
    assert "wobble" not in cells
    text = table({"features_ulx3s": cells, "bench_s": 1, "xy2_100": {"frames_per_s": 1,
                                                                        "idle_clocks": 0},
                  "xy2_200": {"frames_per_s": 1, "idle_clocks": 0},
                  "link": {f"{n}_{k}": 1.0 for n in ("spi", "uart")
                           for k in ("frames_per_s", "latency_us", "latency_max_us")}})
    assert "| ULX3S build: I/O in the queue (its blocks, Yosys for the iCE40: LUT4s / " \
           "flip-flops) | 267 / 133 |" in text
