"""The SymbiYosys proofs: the real PHY passes with its covers reached; each broken PHY fails
exactly the property it breaks."""

from dataclasses import replace
from functools import partial
from pathlib import Path
import re

import pytest

from galvoscan.formal.proofs import (LASER_PROOF_PARAMETERS, PROOFS, command_path_proof,
                                    correction_link_proof, correction_proof, encoder_proof,
                                    fly_clipped_proof, fly_offset_proof, head_status_proof,
                                    laser_safety_proof, pixel_line_proof, player_proof,
                                    queue_io_proof,
                                    spi_frame_proof, xy2_phy_proof)
from galvoscan.gateware.field.correction_table import CorrectionTable
from galvoscan.gateware.laser.controller import LaserController, clocks_at_least
from galvoscan.formal.runner import run_sby

from broken_command import BROKEN_COMMAND_PATHS, BROKEN_SPI_TARGETS, SPI_TARGET_SOLVERS
from broken_encoder import ENCODER_FAULTS, BrokenDecoder
from broken_status import STATUS_FAULTS, BrokenReceiver
from broken_queue_io import QUEUE_IO_FAULTS, BrokenQueueIO
from broken_fly import GATE_FAULTS, OFFSET_FAULTS, BrokenGate, BrokenOffset
from broken_correction import CORRECTION_FAULTS, WAITING_FAULTS, WritesLateValues
from broken_laser import LASER_FAULTS, TamperedLaser
from broken_player import PLAYER_FAULTS, TamperedPlayer
from broken_phys import FAULTS, Z_FAULTS, TamperedPHY
from broken_vector import VECTOR_FAULTS, TamperedSequencer


pytestmark = [pytest.mark.slow, pytest.mark.toolchain]


def expected_properties(expected):
    """One property's message, or several that a fault may break first (the solver reports
    the shortest counterexample, whichever property that breaks)."""
    return {expected} if isinstance(expected, str) else set(expected)


def failed_properties(result):
    """The Assert messages behind the failures SymbiYosys reports as file:line."""
    messages = set()
    for failure in result.failed:
        found = re.search(r"(\S+\.py):(\d+)", failure)
        if found:
            lines = Path(found[1]).read_text().splitlines()
            start = int(found[2]) - 1
            statement = " ".join(lines[start:start + 6])
            # The first string literal of the statement is its message.
            messages.update(re.findall(r'"([^"]+)"', statement)[:1])
    return messages


@pytest.mark.parametrize("proof", PROOFS, ids=lambda p: p.name)
def test_proof_holds_and_covers_are_reached(proof, tmp_path):
    prove, cover = proof.run(tmp_path)
    print(f"{proof.name}: prove {prove.seconds:.1f} s, cover {cover.seconds:.1f} s")
    assert prove.status == "PASS", prove.failed
    assert cover.status == "PASS", cover.failed
    # An unbounded proof, not only a bounded check.
    assert "successful proof by k-induction" in (prove.workdir / "prove.log").read_text()


@pytest.mark.parametrize("fault", sorted(FAULTS))
def test_broken_phy_fails_the_proof(fault, tmp_path):
    # A bounded check two frames deep finds each fault; only the one about resets needs the
    # reset free (the search is far slower with it).
    resets = fault == "ignores_reset"
    proof = xy2_phy_proof(2, make_phy=partial(TamperedPHY, fault), reset_free=resets,
                          name=f"broken_{fault}")
    bmc, = run_sby(proof.harness(), proof.name, tmp_path, depth=proof.depth,
                   cover_depth=proof.bmc_depth if not resets else 12, tasks=("bmc",))
    assert bmc.status == "FAIL"
    assert expected_properties(FAULTS[fault]) & failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(Z_FAULTS))
def test_broken_z_line_fails_the_proof(fault, tmp_path):
    proof = xy2_phy_proof(2, make_phy=partial(TamperedPHY, fault), reset_free=False,
                          name=f"broken_{fault}", z=True)
    bmc, = run_sby(proof.harness(), proof.name, tmp_path, depth=proof.depth,
                   cover_depth=proof.bmc_depth, tasks=("bmc",))
    assert bmc.status == "FAIL"
    assert expected_properties(Z_FAULTS[fault]) & failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(BROKEN_COMMAND_PATHS))
def test_broken_command_path_fails_the_proof(fault, tmp_path):
    parts, properties = BROKEN_COMMAND_PATHS[fault]
    # Frames come on any clock: a bounded check as deep as the covers finds each fault.
    bmc = command_path_proof(**parts, name=f"broken_{fault}").check(tmp_path)
    assert bmc.status == "FAIL"
    assert expected_properties(properties) & failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(BROKEN_SPI_TARGETS))
def test_broken_spi_target_fails_the_proof(fault, tmp_path):
    make, properties = BROKEN_SPI_TARGETS[fault]
    # One paced frame, any one bit flipped: a bad frame event shows as cs_n rises.
    bmc = spi_frame_proof(make_spi=make, helpers=False, name=f"broken_{fault}").check(
        tmp_path, solver=SPI_TARGET_SOLVERS.get(fault))
    assert bmc.status == "FAIL"
    assert expected_properties(properties) & failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(LASER_FAULTS))
def test_broken_laser_controller_fails_the_proof(fault, tmp_path):
    if fault == "short_lead":
        # The real controller with a lead one clock shorter than the spec demands.
        params = dict(LASER_PROOF_PARAMETERS, mo_lead=1.25e-3)
        assert clocks_at_least(1.25e-3, 4000) == clocks_at_least(1.5e-3, 4000) - 1
        make = lambda: LaserController(**params)
    else:
        make = partial(TamperedLaser, fault, **LASER_PROOF_PARAMETERS)
    proof = laser_safety_proof(make_controller=make, helpers=False, name=f"broken_{fault}")
    if fault == "short_lead":
        # Emission a clock early needs arming and the whole (short) lead first: searched from
        # clock 0, no clock before 13 has a counterexample, and 13 has; those before are not
        # searched again (each a solver call that cannot fail).
        proof = replace(proof, bmc_skip=13)
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert expected_properties(LASER_FAULTS[fault]) & failed_properties(bmc), \
        (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(CORRECTION_FAULTS, key=lambda f: f.__name__),
                         ids=lambda f: f.__name__)
def test_broken_correction_stage_fails_the_proof(fault, tmp_path):
    # A write lost or made late shows when the point it waited for is done, 16 clocks in at
    # the earliest (see correction_proof): the clocks before are not searched, each a solver
    # call over the unrolled point for nothing (the counterexamples are 16 clocks long).
    proof = correction_proof(make_stage=lambda: fault(CorrectionTable.identity(5)),
                             helpers=False, bmc_skip=16 if fault in WAITING_FAULTS else 0,
                             name=f"broken_{fault.__name__}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert expected_properties(CORRECTION_FAULTS[fault]) & failed_properties(bmc), \
        (fault, bmc.failed)


@pytest.mark.parametrize("fault, property", [
    ("stage_writes_late_values",
     "a table write stores what the registers held when cor_write was accepted"),
    ("cor_write_never_refused", "no cor_write is accepted while one waits"),
])
def test_broken_correction_link_fails_the_proof(fault, property, tmp_path):
    """Table writes through both links: a stage that stores the registers as they are when
    the write is made (not when it was asked for), and a top that never refuses a cor_write
    while one waits, each fail with a counterexample."""
    if fault == "stage_writes_late_values":
        # As the stage's: a late value shows when the write waiting for the point is made,
        # 16 clocks in at the earliest; the clocks before are not searched.
        proof = replace(correction_link_proof(
            make_stage=lambda: WritesLateValues(CorrectionTable.identity(5)), helpers=False,
            name=f"broken_{fault}"), bmc_skip=16)
    else:
        proof = correction_link_proof(refuse_while_waiting=False, helpers=False,
                                      name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)


def _player_fault_image(fault):
    """What the flash gives in a broken player's bounded check: an image the player is
    deceived into passing, where the flash's own bytes fail the check."""
    from galvoscan.formal.player import valid_image

    def flip_repeats(image):
        image[14] ^= 0x02
    if fault == "byte_unchecked":
        # Valid as the player sees it (byte 14 changed), not as the flash holds it.
        image = bytearray(valid_image(segments=(), tamper=flip_repeats))
        flip_repeats(image)
        return bytes(image)
    if fault == "magic_not_checked":
        return b"XXXX" + valid_image(segments=())[4:]
    if fault == "length_short":
        # The flash says 20 bytes (the player is told 18, and checks 18 whose CRC is right).
        image = bytearray(valid_image(segments=()))
        image[6] = 20
        return bytes(image) + b"\x00\x00"
    return valid_image(segments=())


@pytest.mark.parametrize("fault", sorted(PLAYER_FAULTS))
def test_broken_player_fails_the_proof(fault, tmp_path):
    proof = player_proof(make_player=lambda: TamperedPlayer(
        fault, max_image_bytes=24, offset=0, crc_bits_per_clock=8), helpers=False,
        image=_player_fault_image(fault), name=f"broken_{fault}")
    if fault == "arms_on_start":
        # (The write comes on the clock after the start.)
        proof = replace(proof, bmc_skip=3, bmc_depth=4)
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert failed_properties(bmc) == {
        "no register written before a whole image passed the check"}, (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(VECTOR_FAULTS))
def test_broken_pixel_lines_fail_the_proof(fault, tmp_path):
    _, harness, property = VECTOR_FAULTS[fault]
    proof = pixel_line_proof(harness, make_sequencer=partial(TamperedSequencer, fault),
                             helpers=False, name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(ENCODER_FAULTS))
def test_broken_encoders_fail_the_proof(fault, tmp_path):
    _, property = ENCODER_FAULTS[fault]
    proof = encoder_proof(make_decoder=partial(BrokenDecoder, fault), name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(STATUS_FAULTS))
def test_broken_status_receivers_fail_the_proof(fault, tmp_path):
    _, property = STATUS_FAULTS[fault]
    proof = head_status_proof(make_receiver=partial(BrokenReceiver, fault), helpers=False,
                              name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(OFFSET_FAULTS))
def test_broken_fly_offsets_fail_the_proof(fault, tmp_path):
    _, property = OFFSET_FAULTS[fault]
    proof = fly_offset_proof(make_stage=partial(BrokenOffset, fault), name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(GATE_FAULTS))
def test_broken_clipped_gates_fail_the_proof(fault, tmp_path):
    _, held = GATE_FAULTS[fault]
    proof = fly_clipped_proof(held=held, make_gate=partial(BrokenGate, fault), helpers=False,
                              name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert "marking passes exactly while the point on the wires was not clipped" in \
        failed_properties(bmc), (fault, bmc.failed)


@pytest.mark.parametrize("fault", sorted(QUEUE_IO_FAULTS))
def test_broken_queue_io_fails_the_proof(fault, tmp_path):
    _, property = QUEUE_IO_FAULTS[fault]
    proof = queue_io_proof(make_stage=partial(BrokenQueueIO, fault), helpers=False,
                           name=f"broken_{fault}")
    bmc = proof.check(tmp_path)
    assert bmc.status == "FAIL"
    assert property in failed_properties(bmc), (fault, bmc.failed)
