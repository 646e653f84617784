"""``galvoscan bench``: the quick run's figures against what the protocols allow."""

import json

from galvoscan.cli import main


def test_bench_quick(capsys):
    assert main(["bench", "--quick", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    # XY2-100: 20 bits at 2 Mbit/s, back to back; XY2-200 twice that.
    assert result["frames_per_s"] == 100_000 and result["idle_clocks"] == 0
    assert result["xy2_200"]["frames_per_s"] == 200_000
    assert result["xy2_200"]["idle_clocks"] == 0
    link = result["link"]
    # SPI: 32 bits of two half periods at SCK = 12 MHz / 12, plus half a period before cs_n
    # rises and four with it high: the host this bench plays.
    assert abs(link["spi_frames_per_s"] - 1 / ((2 * 32 + 5) * 0.5e-6)) < 1
    # UART: four 10-bit characters back to back at 115 200 baud.
    assert abs(link["uart_frames_per_s"] - 115_200 / 40) < 1
    # A jump reaches the wires within a few 10 µs frames (DDA set-up, then the frame boundary,
    # then the frame itself).
    for name in ("spi", "uart"):
        assert 10 < link[f"{name}_latency_us"] <= link[f"{name}_latency_max_us"] < 40
    # Vector segments streamed over the UART at the default 1 Mbaud: three 4-byte frames a
    # segment, 10 bits a byte, and a read of fifo_free (a request and its answer) per batch:
    # under 8 333 a second, and at least 5 000 (what 1 mm segments at 5 m/s need).
    stream = link["stream"]
    assert stream["baud"] == 1_000_000 and stream["errors"] == 0
    assert 5000 <= 0.97 * 1_000_000 / 10 / 12 <= stream["segments_per_s"] < 1_000_000 / 10 / 12
    assert "boards" in result and result["boards"] == {}
