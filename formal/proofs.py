"""Every proof galvoscan has, in one list: what ``galvoscan prove`` and the tests run."""

from dataclasses import dataclass
from typing import Callable

from ..gateware.phy.xy2_100 import FRAME_BITS, XY2Transmitter
from .command import CommandPathSpec
from .correction import CorrectionSpec
from ..gateware.field.correction import FieldCorrection
from ..gateware.field.correction_table import CorrectionTable
from .laser import LaserSafetySpec
from ..gateware.laser.controller import LaserController, clocks_at_least
from .xy2_100 import XY2TransmitterSpec


__all__ = ["Proof", "PROOFS", "xy2_phy_proof", "command_path_proof", "laser_safety_proof",
           "correction_proof", "LASER_PROOF_PARAMETERS"]


@dataclass(frozen=True)
class Proof:
    """A spec harness and the depths SymbiYosys needs for it."""
    name: str
    description: str
    harness: Callable[[], object]   # builds a fresh harness
    depth: int                      # k-induction depth (system clocks)
    cover_depth: int
    cover_skip: int = 0             # clocks before any cover can be reached


def xy2_phy_proof(clocks_per_bit, *, make_phy=None, name=None):
    """The XY2-100 transmitter proof at ``clocks_per_bit`` system clocks per bit.

    ``make_phy(clk_freq=…, bit_rate=…)`` builds the design under proof (the real transmitter
    by default; the tests pass deliberately broken ones).

    The black-box spec remembers the last position taken for as long as no new one comes, so
    k-induction has to see three whole frames before it can tie that memory to the PHY's own:
    the depth is three frames and a few clocks. The cover needs two frames.
    """
    make_phy = XY2Transmitter if make_phy is None else make_phy
    bit_rate = 2_000_000
    frame = FRAME_BITS * clocks_per_bit

    def harness():
        phy = make_phy(clk_freq=clocks_per_bit * bit_rate, bit_rate=bit_rate)
        return XY2TransmitterSpec(phy, clocks_per_bit=clocks_per_bit)

    return Proof(
        name=name or f"xy2_100_{clocks_per_bit}x",
        description=f"XY2-100 PHY at {clocks_per_bit} system clocks per bit: clock, edges, "
                    f"20-bit frames, SYNC, parity, control bits, latched data",
        harness=harness,
        depth=3 * frame + 5,
        cover_depth=2 * frame + 10)


def command_path_proof(*, make_spi=None, make_decoder=None, name="command_path"):
    """SPI pins → decoder → register file: no write without a complete frame with 0x64.

    Helper invariants make a short induction enough. A write needs a whole 32-bit frame through
    the synchronisers, 67 clocks at the least, so covers are not searched before clock 66.
    """
    kwargs = {}
    if make_spi is not None:
        kwargs["make_spi"] = make_spi
    if make_decoder is not None:
        kwargs["make_decoder"] = make_decoder
    return Proof(
        name=name,
        description="command path: a register is written only by a complete SPI frame with "
                    "check byte 0x64; cs_n released mid-frame discards it",
        harness=lambda: CommandPathSpec(**kwargs),
        depth=8, cover_depth=74, cover_skip=66)


#: The laser controller as proved: a 4 kHz clock makes 1 ms four clocks, so the 1.5 ms lead is 6
#: clocks and the latch timings one clock each, and the cover of real emission is a few dozen
#: clocks deep. The logic is the same at any size; the 5 ms lead at 12 MHz is simulated.
LASER_PROOF_PARAMETERS = dict(clk_freq=4000, mo_lead=1.5e-3, latch_setup=0.25e-3,
                              latch_pulse=0.25e-3)


def laser_safety_proof(*, make_controller=None, lead_clocks=None, name="laser_safety"):
    """Interlock, MO lead, reset and fault latching of the laser controller."""
    make_controller = make_controller or (lambda: LaserController(**LASER_PROOF_PARAMETERS))
    if lead_clocks is None:
        lead_clocks = clocks_at_least(LASER_PROOF_PARAMETERS["mo_lead"],
                                      LASER_PROOF_PARAMETERS["clk_freq"])

    return Proof(
        name=name,
        description="laser: interlock open => no MO/modulation/PRR; modulation only after the "
                    "MO lead; outputs low after reset until armed; faults latched until cleared",
        harness=lambda: LaserSafetySpec(make_controller(), lead_clocks=lead_clocks),
        depth=20, cover_depth=30)


def correction_proof(*, make_stage=None, name="correction_writes"):
    """The correction stage: no torn point, no lost write, the stream rules.

    Proved on a 5 × 5 table (the RAM's size does not enter the properties). A point takes 15
    clocks, so the induction looks 20 deep; the covers need a write and a point, about 20.
    """
    make_stage = make_stage or (lambda: FieldCorrection(CorrectionTable.identity(5)))
    return Proof(
        name=name,
        description="correction: no table write while a point is made; a requested write "
                    "is made within 15 clocks; a presented point holds until taken",
        harness=lambda: CorrectionSpec(make_stage()),
        depth=20, cover_depth=24)


PROOFS = [
    # The smallest divider, as simulated.
    xy2_phy_proof(2),
    # The iCEBreaker's 12 MHz system clock.
    xy2_phy_proof(6),
    command_path_proof(),
    laser_safety_proof(),
    # As built with vector mode: the PRR clock runs free and leads pulse_ahead (MO gates it).
    laser_safety_proof(
        make_controller=lambda: LaserController(**LASER_PROOF_PARAMETERS, lookahead=3),
        name="laser_safety_free_prr"),
    correction_proof(),
]
