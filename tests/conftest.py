import gc

import pytest


def pytest_configure(config):
    """Before any worker starts: compile the YoWASP tools once, if this machine has not yet.
    Otherwise each worker whose first tests run Yosys (the two full builds, the proofs) compiles
    it at the same time: measured on 2 cores, two compiles side by side took 93 s each, one
    alone 37 s."""
    if not hasattr(config, "workerinput"):          # (pytest-xdist's controller, or no xdist)
        from galvoscan.toolchain import prepare
        prepare()


@pytest.fixture(autouse=True)
def collect_garbage():
    """Collect after each test, so Amaranth's UnusedElaboratable warning (raised when an unused
    component is garbage-collected) fails the test that left it, not a later one at random.

    What survives a test's collection is frozen (``gc.freeze``: left out of every later
    collection), so each collection looks only at what that test made. A full collection over
    the simulators the workers keep built (SimBoard.powered_up) took up to 0.7 s a test, 210 s
    of the suite in all."""
    yield
    gc.collect()
    gc.freeze()


#: The suite's longest tests, in seconds as `--durations` measured them: started first, so
#: that `-n auto --dist loadgroup` (which hands tests out in this order, as workers get free)
#: gives each worker its share of the long ones and the two finish together. Only an order:
#: a name missing here runs after these, as collected.
LONGEST_FIRST = {
    "tests/sim/test_netlist.py::test_the_ulx3s_builds_netlist_behaves_as_its_design": 88,
    "tests/sim/test_netlist.py::test_the_default_builds_netlist_behaves_as_its_design": 69,
    "tests/platforms/test_ulx3s.py::test_build_ulx3s": 68,
    "tests/test_bench.py::test_bench_quick": 56,
    "tests/cli/test_cli.py::test_build_icebreaker": 52,
    "tests/sim/test_compiled.py::test_a_vector_job_with_delays_and_wobble_is_the_same_on_both_backends[ulx3s]": 32,
    "tests/sim/test_netlist.py::test_the_ram_and_multiplier_models_do_what_yosys_does[None]": 30,
    "tests/sim/test_compiled.py::test_the_job_player_from_the_flash_is_the_same_on_both_backends[ulx3s]": 29,
    "tests/link/test_link_faults.py::test_a_fault_on_spi": 24,
    "tests/cli/test_cli.py::test_sim_vector_waits_in_the_boards_time[python-True]": 23,
    "tests/link/test_link_faults.py::test_a_fault_on_the_uart_at_3_mbaud": 23,
    "tests/cli/test_standalone.py::test_standalone_plays_the_stored_job_and_refuses_a_damaged_one": 23,
    "tests/cli/test_cli.py::test_build_that_misses_timing_is_one_line_and_writes_no_bitstream": 21,
    "tests/sim/test_compiled.py::test_a_vector_job_with_delays_and_wobble_is_the_same_on_both_backends[vector]": 21,
    "tests/test_api.py::test_first_job_example": 21,
    "tests/cli/test_board.py::test_send_and_read_a_served_simulated_board": 21,
    "tests/link/test_link_faults.py::test_a_fault_on_the_uart": 19,
    "tests/gateware/player/test_player.py::test_plays_the_image_as_the_streamer_streams_it": 18,
    "tests/formal/test_formal.py::test_broken_spi_target_fails_the_proof[target_ignores_length]": 17,
    "tests/link/test_link_faults.py::test_the_first_trials_cases[uart-3mbaud]": 16,
    "tests/sim/test_compiled.py::test_mark_on_the_simulated_board_marks_the_same_on_both_backends": 16,
    "tests/link/test_link_faults.py::test_a_fault_on_the_reference_simulator": 15,
    "tests/sim/test_compiled.py::test_random_spi_frames_with_the_machine_toggling": 14,
    "tests/cli/test_cli.py::test_build_icestick": 13,
    "tests/sim/test_compiled.py::test_a_foreign_or_damaged_cached_model_is_never_used": 13,
    "tests/outputs/test_stream.py::test_ctrl_c_mid_job_turns_the_laser_pins_off_within_a_frame": 13,
    "tests/sim/test_netlist.py::test_the_ulx3s_netlists_player_reads_the_flash_through_usrmclk": 13,
    "tests/gateware/sources/test_dda.py::test_special_lines": 12,
    "tests/cli/test_mark.py::test_a_photo_streams_with_no_underrun_where_the_link_keeps_up[icebreaker]": 10,
    "tests/sim/test_compiled.py::test_random_byte_streams_with_the_machine_toggling": 10,
    "tests/outputs/test_stream.py::test_framing_traces_the_box_with_the_guide_laser_and_the_laser_off": 10,
    "tests/link/test_client.py::test_uart_rates[12000000.0-115200]": 10,
    "tests/cli/test_mark.py::test_a_photo_streams_with_no_underrun_where_the_link_keeps_up[ulx3s]": 9,
    "tests/plan/test_preview.py::test_a_photos_preview_shows_its_dose[shading]": 8,
}


def pytest_collection_modifyitems(items):
    # (A stable sort; "@group" is what --dist loadgroup adds to an xdist_group's test ids.)
    items.sort(key=lambda item: -LONGEST_FIRST.get(item.nodeid.split("@")[0], 0))


@pytest.fixture(scope="session")
def icebreaker_build(tmp_path_factory):
    """The default iCEBreaker bitstream (every mode, correction), started with a model lens
    table, built once for the tests that look at it (each of them in the xdist group
    ``icebreaker_build``, so that one worker builds it): ``(folder, report, table file)``."""
    import contextlib
    import io
    import json
    from galvoscan.cli import main
    folder = tmp_path_factory.mktemp("icebreaker")
    table = folder / "lens.json"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["correct", "model", "--field", "110", "--focal", "160",
                     "-o", str(table)]) == 0
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["build", "--board", "icebreaker", "--build-dir", str(folder),
                     "--correction", str(table), "--json"])
    return folder, code, json.loads(out.getvalue()), table


@pytest.fixture(scope="session")
def ulx3s_build(tmp_path_factory):
    """``galvoscan build --board ulx3s`` (every feature), built once for the tests that look
    at it (each in the xdist group ``ulx3s_build``, so that one worker builds it):
    ``(folder, exit code, report)``."""
    import contextlib
    import io
    import json
    from galvoscan.cli import main
    folder = tmp_path_factory.mktemp("ulx3s")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["build", "--board", "ulx3s", "--build-dir", str(folder), "--json"])
    return folder, code, json.loads(out.getvalue())
