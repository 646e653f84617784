"""The placer watchdog against a stand-in nextpnr: one that settles, one that spins forever,
one that fails. (The real builds, which use it, are in test_cli.py.)"""

import sys

import pytest

from galvoscan.placer import main, place_and_route


# A stand-in for nextpnr: with --placer static it writes `ITERATIONS` of the static placer's
# iteration lines to its --log (forever if negative) and exits with `STATIC_EXIT`; HeAP runs
# write a line and exit 0. Every run's arguments go to runs.txt beside the log. With --report,
# it reports the Fmax `FMAX` gives for its --seed (30 MHz for any other) against 24 MHz.
FAKE = """\
import itertools, json, sys, time
argv = sys.argv[1:]
log = argv[argv.index("--log") + 1]
with open(log + ".runs.txt", "a") as runs:
    runs.write(" ".join(argv) + "\\n")
if "--report" in argv:
    achieved = {fmax}.get(int(argv[argv.index("--seed") + 1]), 30.0)
    with open(argv[argv.index("--report") + 1], "w") as report:
        json.dump({{"fmax": {{"clk": {{"achieved": achieved, "constraint": 24.0}}}}}}, report)
with open(log, "w") as out:
    out.write("Info: Packing constants..\\n")
    if "--placer" in argv:
        out.write("Info: Running Static placer...\\n")
        count = itertools.count() if {iterations} < 0 else range({iterations})
        for i in count:
            out.write(f"Info: iter={{i}} steplen=1.0 a=1.0 penalty=[0.00]\\n")
            out.write("Info:    update_chains distance 0.00\\n")
            out.flush()
            if {iterations} < 0:
                time.sleep(0.001)
        sys.exit({static_exit})
    out.write("Info: HeAP Placer Time: 1.00s\\n")
"""


def fake_nextpnr(tmp_path, *, iterations, static_exit=0, fmax=None):
    script = tmp_path / "fake_nextpnr"
    script.write_text(f"#!{sys.executable}\n" +
                      FAKE.format(iterations=iterations, static_exit=static_exit,
                                  fmax=repr(fmax or {})))
    script.chmod(0o755)
    return str(script)


def runs(log):
    return [line.split() for line in (log.parent / f"{log.name}.runs.txt").read_text().splitlines()]


ARGS = ["--quiet", "--seed", "1", "--up5k", "--json", "top.json"]


def test_a_static_placement_that_settles_is_kept(tmp_path):
    log = tmp_path / "top.tim"
    nextpnr = fake_nextpnr(tmp_path, iterations=600)
    assert place_and_route([*ARGS, "--log", str(log)], nextpnr=nextpnr,
                           max_iterations=1000, poll_s=0.01) == (0, "static")
    assert runs(log) == [["--placer", "static", *ARGS, "--log", str(log)]]


def test_a_static_placer_that_never_settles_gives_way_to_heap(tmp_path):
    log = tmp_path / "top.tim"
    nextpnr = fake_nextpnr(tmp_path, iterations=-1)
    assert place_and_route([*ARGS, "--log", str(log)], nextpnr=nextpnr,
                           max_iterations=1000, poll_s=0.01) == (0, "heap")
    # The second run is nextpnr's own arguments, untouched: HeAP, its default placer.
    assert runs(log) == [["--placer", "static", *ARGS, "--log", str(log)],
                         [*ARGS, "--log", str(log)]]
    assert "HeAP" in log.read_text() and "iter=" not in log.read_text()


def test_a_failed_static_run_gets_heaps_second_try(tmp_path):
    log = tmp_path / "top.tim"
    nextpnr = fake_nextpnr(tmp_path, iterations=10, static_exit=1)
    assert place_and_route([*ARGS, "--log", str(log)], nextpnr=nextpnr,
                           poll_s=0.01) == (0, "heap")
    assert len(runs(log)) == 2


@pytest.mark.parametrize("argv, message", [
    (ARGS, "--log"),
    ([*ARGS, "--log"], "--log"),
    ([*ARGS, "--log", "x.tim", "--placer", "sa"], "leave --placer out"),
])
def test_arguments_it_cannot_run_with(argv, message, tmp_path):
    with pytest.raises(ValueError, match=message):
        place_and_route(argv, nextpnr=fake_nextpnr(tmp_path, iterations=1))


def test_main_writes_which_placer_placed_it(tmp_path, monkeypatch):
    log = tmp_path / "top.tim"
    nextpnr = fake_nextpnr(tmp_path, iterations=-1)
    monkeypatch.setattr("galvoscan.placer.tool", lambda name: nextpnr)
    monkeypatch.setattr("galvoscan.placer.STATIC_ITERATIONS_MAX", 100)
    assert main([*ARGS, "--log", str(log)]) == 0
    assert (tmp_path / "top.tim.placer").read_text() == "heap 1\n"


@pytest.mark.parametrize("fmax, seeds, placed", [
    ({}, [1], "static 1"),                                  # met at once: one run
    ({1: 23.1}, [1, 2], "static 2"),                        # missed, then met
    ({1: 23.1, 2: 23.5, 3: 23.9}, [1, 2, 3], "static 3"),   # never met: three, the last kept
    ({1: 22.3, 2: 24.9}, [1, 2], "static 2"),               # 7 % short (the marker's seed 1)
    ({1: 21.3}, [1], "static 1"),                           # 11 % short: no seed makes it
])
def test_a_placement_that_misses_its_clock_is_placed_again_with_the_next_seed(
        tmp_path, monkeypatch, fmax, seeds, placed):
    log, report = tmp_path / "top.tim", tmp_path / "top.report.json"
    nextpnr = fake_nextpnr(tmp_path, iterations=10, fmax=fmax)
    monkeypatch.setattr("galvoscan.placer.tool", lambda name: nextpnr)
    assert main([*ARGS, "--report", str(report), "--log", str(log)]) == 0
    assert [int(run[run.index("--seed") + 1]) for run in runs(log)] == seeds
    assert (tmp_path / "top.tim.placer").read_text() == f"{placed}\n"
