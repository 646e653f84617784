"""Every proof galvoscan has, in one list: what ``galvoscan prove`` and the tests run."""

from dataclasses import dataclass
from typing import Callable

from ..gateware.phy.xy2_100 import FRAME_BITS, XY2Transmitter
from .command import CommandPathSpec, SPIFrameSpec
from .correction import CorrectionLinkSpec, CorrectionSpec
from ..gateware.field.correction import FieldCorrection
from ..gateware.field.correction_table import CorrectionTable
from .laser import LaserSafetySpec
from ..gateware.laser.controller import LaserController, clocks_at_least
from .xy2_100 import XY2TransmitterSpec
from .player import PlayerSpec
from .vector import FreeDDASequencer, PixelLineSpec
from .encoder import QuadratureSpec
from .fly import ClippedOnWiresSpec, FlyOffsetSpec
from ..gateware.fly.offset import ClippedOnWires, FlyOffset
from .xy2_status import XY2StatusSpec
from .queue_io import QueueIOSpec
from ..gateware.sources.queue_io import QueueIO
from ..gateware.phy.xy2_status import XY2StatusReceiver
from ..gateware.fly.encoder import QuadratureDecoder
from ..gateware.player.player import JobPlayer


__all__ = ["Proof", "PROOFS", "xy2_phy_proof", "spi_frame_proof", "command_path_proof", "laser_safety_proof",
           "correction_proof", "correction_link_proof", "player_proof", "pixel_line_proof", "encoder_proof",
           "head_status_proof", "fly_offset_proof", "fly_clipped_proof", "queue_io_proof",
           "LASER_PROOF_PARAMETERS"]


@dataclass(frozen=True)
class Proof:
    """A spec harness and the depths SymbiYosys needs for it."""
    name: str
    description: str
    harness: Callable[[], object]   # builds a fresh harness
    depth: int                      # k-induction depth (system clocks)
    cover_depth: int
    cover_skip: int = 0             # clocks before any cover can be reached
    #: How deep the broken designs' bounded checks look (default: as deep as the covers).
    bmc_depth: int = None
    #: Builds the harness the covers are searched in, where that is a restriction of the
    #: proof's (the reset tied off, say) that the solver searches far faster; None: the same.
    cover_harness: Callable[[], object] = None
    #: Clocks the bounded check does not look at (no counterexample can be that short).
    bmc_skip: int = 0
    #: Builds the harness the bounded check searches, where that is a restriction of the
    #: proof's: a counterexample found in it is one in the proof's harness too. None: the same.
    bmc_harness: Callable[[], object] = None
    #: Search the covers and the bounded check on the state unrolled into plain bit-vectors
    #: (:func:`~.runner.run_sby`'s ``unrolled``): for a search of a few clocks after a long
    #: ``cover_skip``.
    unrolled: bool = False

    def __post_init__(self):
        if self.bmc_depth is None:
            object.__setattr__(self, "bmc_depth", self.cover_depth)

    #: What :meth:`run_task` runs, in the order reported.
    TASKS = ("prove", "cover")

    def run_task(self, task, workdir):
        """Run one of :attr:`TASKS` ("prove" or "cover"): its :class:`ProofResult`.

        Each task has its own folder (``workdir/name`` and ``workdir/name_covers``), so the
        two may run at the same time."""
        from .runner import run_sby
        if task == "prove":
            result, = run_sby(self.harness(), self.name, workdir, depth=self.depth,
                              cover_depth=self.cover_depth, tasks=("prove",))
        elif task == "cover":
            harness = self.cover_harness or self.harness
            result, = run_sby(harness(), f"{self.name}_covers", workdir, depth=self.depth,
                              cover_depth=self.cover_depth, cover_skip=self.cover_skip,
                              tasks=("cover",), unrolled=self.unrolled)
            result.name = self.name         # reported as this proof's cover
        else:
            raise ValueError(f"unknown task {task!r}; known: {', '.join(self.TASKS)}")
        return result

    def run(self, workdir):
        """Prove it and reach its covers: the prove and cover :class:`ProofResult`."""
        return tuple(self.run_task(task, workdir) for task in self.TASKS)

    def check(self, workdir, *, solver=None):
        """A bounded check to ``bmc_depth`` (the broken designs' test): its
        :class:`ProofResult`, FAIL with a counterexample where an assertion can be broken.
        ``solver``: smtbmc's (:func:`~.runner.run_sby`'s; default Yices)."""
        from .runner import SOLVER, run_sby
        harness = self.bmc_harness or self.harness
        bmc, = run_sby(harness(), self.name, workdir, depth=self.depth,
                       cover_depth=self.bmc_depth, cover_skip=self.bmc_skip, tasks=("bmc",),
                       unrolled=self.unrolled, solver=solver or SOLVER)
        return bmc


def xy2_phy_proof(clocks_per_bit, *, make_phy=None, reset_free=True, name=None, z=False):
    """The XY2-100 transmitter proof at ``clocks_per_bit`` system clocks per bit.

    ``make_phy(clk_freq=…, bit_rate=…)`` builds the design under proof (the real transmitter
    by default; the tests pass deliberately broken ones).

    The black-box spec remembers the last position taken for as long as no new one comes, and
    the bits of the frame it has sampled so far; helper invariants tie each bit of its state
    to the PHY's (the position latched, the shift registers, the counters), so k-induction
    needs only a few clocks at any divider, resets included (without them it had to see a
    whole frame: 125 clocks at 6 clocks a bit). The cover needs two frames.

    With ``z``, the transmitter drives the Z line too, and the spec checks it as X and Y.
    """
    make_phy = XY2Transmitter if make_phy is None else make_phy
    bit_rate = 2_000_000
    frame = FRAME_BITS * clocks_per_bit

    def harness(reset_free=reset_free):
        phy = make_phy(clk_freq=clocks_per_bit * bit_rate, bit_rate=bit_rate,
                       **({"z": True} if z else {}))
        return XY2TransmitterSpec(phy, clocks_per_bit=clocks_per_bit, reset_free=reset_free)

    return Proof(
        name=name or f"xy2_100_{clocks_per_bit}x" + ("_z" if z else ""),
        description=f"XY2-100 PHY at {clocks_per_bit} system clocks per bit: clock, edges, "
                    f"20-bit frames, SYNC, parity, control bits, latched data"
                    + (", the Z line's too" if z else "") + "; from power-up"
                    + (" and after any reset, mid-frame included" if reset_free else ""),
        harness=harness,
        # The helpers are inductive on their own (depth 1 passes); 3 leaves a little room.
        depth=3,
        # Two frames with new data need no reset: searched with it tied off, they are found
        # in seconds rather than minutes.
        cover_depth=2 * frame + 10, cover_harness=lambda: harness(reset_free=False))


def spi_frame_proof(*, make_spi=None, helpers=True, name="spi_frames"):
    """The SPI target, pins and reset free: an intact frame is 80 bits whose CRC holds, and
    carries them.

    Helper invariants tie the target's registers to the spec's, so a short induction is
    enough. The covers and the broken designs' bounded check search one good frame from a
    paced host, any one bit flipped (:class:`SPIFrameSpec`'s ``one_frame``, a restriction of
    the free pins): its 80 bits rise at clocks 1, 3, … 159 and it ends as cs_n rises, so no
    cover and no fault that needs the frame shows before clock 160.

    Only the last clock is searched. What the covers and the faults reach holds from then on:
    a frame event waits until it is taken, and the spec's consumer may never take it, while
    cs_n, once high, stays high. Each clock searched is a query over the whole unrolled frame,
    and the clocks where nothing is reachable yet are the dear ones: with z3, searching clocks
    158 … 167 took 2 min 45 s for the broken target that ignores the length, a minute for
    clock 158 alone, against some 15 s for the last clock only."""
    kwargs = {"helpers": helpers}
    if make_spi is not None:
        kwargs["make_spi"] = make_spi
    return Proof(
        name=name,
        description="SPI target, pins and reset free: a frame is intact only with exactly 80 "
                    "SCK edges and a CRC-16 that holds, and carries its bits",
        harness=lambda: SPIFrameSpec(**kwargs),
        # The spec's synchroniser stages and SCK edge detector are its own: a few clocks of
        # induction see them agree with the target's.
        depth=8,
        cover_depth=168, cover_skip=167,
        cover_harness=lambda: SPIFrameSpec(**kwargs, reset_free=False, one_frame=True),
        bmc_depth=168, bmc_skip=167,
        bmc_harness=lambda: SPIFrameSpec(**kwargs, one_frame=True),
        unrolled=True)


def command_path_proof(*, make_decoder=None, make_feed=None, name="command_path"):
    """Both links' frame events → decoder → register file, reset free: no write without an
    intact write frame in sequence, segments whole, every refusal counted, the watchdog fed by
    progress only. A frame comes on any clock, so the covers and the faults are a few clocks
    deep."""
    kwargs = {}
    if make_decoder is not None:
        kwargs["make_decoder"] = make_decoder
    if make_feed is not None:
        kwargs["make_feed"] = make_feed
    return Proof(
        name=name,
        description="command path, both links' frames free, reset free: a register is written "
                    "only by an intact write frame with the expected sequence number; a "
                    "segment is queued whole; every refused frame is counted; only progress "
                    "feeds the watchdog",
        harness=lambda: CommandPathSpec(**kwargs),
        depth=6,
        cover_depth=10)


#: The laser controller as proved: a 4 kHz clock makes 1 ms four clocks, so the 1.5 ms lead is 6
#: clocks and the latch timings one clock each, and the cover of real emission is a few dozen
#: clocks deep. The logic is the same at any size; the 5 ms lead at 12 MHz is simulated.
LASER_PROOF_PARAMETERS = dict(clk_freq=4000, mo_lead=1.5e-3, latch_setup=0.25e-3,
                              latch_pulse=0.25e-3, alarms=2, head=True)


def laser_safety_proof(*, make_controller=None, lead_clocks=None, helpers=True,
                       name="laser_safety"):
    """laser_enable, interlock, alarms, watchdog, MO lead, reset and faults of the controller.

    The watchdog's counters are tied to the spec's count of silent clocks, and the lead
    counter to the spec's count of clocks MO has been on, by helper invariants, so a short
    induction covers any watchdog time (all 16 bits are free)."""
    make_controller = make_controller or (lambda: LaserController(**LASER_PROOF_PARAMETERS))
    clk_freq = LASER_PROOF_PARAMETERS["clk_freq"]
    if lead_clocks is None:
        lead_clocks = clocks_at_least(LASER_PROOF_PARAMETERS["mo_lead"], clk_freq)

    return Proof(
        name=name,
        description="laser: laser_enable only when armed, fault-free, interlock closed, no "
                    "alarm, and every output low without it; interlock/alarm latch faults; "
                    "watchdog fires in time; a fault keeps every output off until cleared and "
                    "re-armed; MO lead; outputs low after reset until armed",
        harness=lambda: LaserSafetySpec(make_controller(), lead_clocks=lead_clocks,
                                        ms_clocks=round(clk_freq / 1000),
                                        alarms=LASER_PROOF_PARAMETERS["alarms"],
                                        head=LASER_PROOF_PARAMETERS["head"],
                                        helpers=helpers),
        depth=10, cover_depth=30)


#: The player proof's image: the header and one segment, 24 bytes.
PLAYER_PROOF_IMAGE_BYTES = 24


def player_proof(*, make_player=None, helpers=True, image=None, name="player_check"):
    """The job player writes (and arms) only after a whole image has passed its check.

    On an image of at most 24 bytes at address 0 (the counters' width does not enter the
    property) with a CRC core of a byte a clock (the board's takes eight; both are simulated
    against zlib). Helper invariants tie the player's word count, length, expected CRC and
    CRC register to the spec's, so a short induction is enough. The covers (a whole image
    checked; the first write after it) are searched with the flash giving a valid image
    (``image``: the header alone, by default), and so are the broken players' bounded
    checks, each with the image its fault lets through. Those searches look at the last clock
    only: the spec latches what they look for in that mode, and nothing can be reached before
    the header's nine words are in."""
    from .player import valid_image
    make_player = make_player or (lambda: JobPlayer(
        max_image_bytes=PLAYER_PROOF_IMAGE_BYTES, offset=0, crc_bits_per_clock=8))
    image = valid_image(segments=()) if image is None else image
    # (The helper invariants are for the induction: the restricted searches go without.)
    restricted = lambda: PlayerSpec(make_player(), helpers=False, image=image)
    return Proof(
        name=name,
        description="player: no register written, arm included, until a whole image (magic, "
                    "version, length, CRC-32 of every byte) has passed the check since the "
                    "start",
        harness=lambda: PlayerSpec(make_player(), helpers=helpers),
        depth=8, cover_depth=52, bmc_depth=52, cover_skip=51, bmc_skip=51,
        cover_harness=restricted, bmc_harness=restricted, unrolled=True)


def correction_proof(*, make_stage=None, helpers=True, bmc_skip=0, name="correction_writes"):
    """The correction stage: no torn point, no lost write, the stream rules.

    Proved on a 5 × 5 table (the RAM's size does not enter the properties). Helper invariants
    tie a point's age to its step and a waiting write to the point it waits for, so a short
    induction is enough (each step unrolls the multiplier once more); the covers need a write
    and a point, about 21 clocks.

    The broken stages' bounded checks offer every point at (0, 0) (``points_at_origin``, a
    restriction of the free inputs, so their counterexamples hold with free points). A write
    lost or made late shows when the point it waited for is done, 16 clocks in at the
    earliest; 20 leaves room, and such faults' checks may skip (``bmc_skip``) the clocks
    before it.
    """
    make_stage = make_stage or (lambda: FieldCorrection(CorrectionTable.identity(5)))
    return Proof(
        name=name,
        description="correction: no table write while a point is made; a requested write "
                    "is made within 16 clocks; a presented point holds until taken",
        harness=lambda: CorrectionSpec(make_stage(), helpers=helpers),
        depth=4, cover_depth=24, bmc_depth=20, bmc_skip=bmc_skip,
        bmc_harness=lambda: CorrectionSpec(make_stage(), helpers=helpers,
                                           points_at_origin=True))


def correction_link_proof(*, make_stage=None, helpers=True, refuse_while_waiting=True,
                          name="correction_link"):
    """Table writes from either link: the values at the frame are the values written.

    The decoder, register file and correction stage (5 × 5) with frames free on both links.
    Helper invariants tie a waiting write to its frame's registers and to the point it waits
    for, so a short induction is enough. The broken designs' bounded checks offer every point
    at (0, 0), as :func:`correction_proof`'s do.
    """
    def harness(points_at_origin=False):
        return CorrectionLinkSpec(make_stage=make_stage, helpers=helpers,
                                  refuse_while_waiting=refuse_while_waiting,
                                  points_at_origin=points_at_origin)

    return Proof(
        name=name,
        description="correction writes through both links: a table write stores what the "
                    "registers held when its cor_write frame was accepted; one waits at a "
                    "time, and is made within 17 clocks",
        harness=harness,
        depth=4, cover_depth=24, bmc_depth=20,
        bmc_harness=lambda: harness(points_at_origin=True))


def pixel_line_proof(harness, *, make_sequencer=None, helpers=True, name=None):
    """Pixel words and bits only ever keep the laser off (:mod:`.vector`'s ``harness``:
    ``"words"`` or ``"dark_lines"``), on the vector sequencer as built with pixel lines and
    the delays, its interpolator free. Helper invariants on its slot, held point and pixel
    bits make the induction a few clocks deep; a line's first point is held within ten."""
    make_sequencer = make_sequencer or FreeDDASequencer
    said = {"words": "pixel words and jumps alone never light the laser",
            "dark_lines": "pixel lines whose bits are 0 never light the laser: not a point, "
                          "not the first, not a corner hold, not past the words"}[harness]
    return Proof(
        name=name or f"pixel_lines_{harness}",
        description=f"vector sequencer with pixel lines (any line the DDA steps): {said}",
        harness=lambda: PixelLineSpec(make_sequencer(), harness=harness, helpers=helpers),
        depth=4, cover_depth=14, bmc_depth=16)


def encoder_proof(*, make_decoder=None, name="encoder_count"):
    """A quadrature decoder's count and illegal count against the spec's own (any lines, any
    clears, any reset): the spec's registers equal the decoder's, so the induction is one
    clock deep whatever the counts hold."""
    make_decoder = make_decoder or QuadratureDecoder
    return Proof(
        name=name,
        description="encoder: the count moves one edge a clock at most, the way the lines "
                    "went, never wraps; two-edge steps are counted as illegal and move "
                    "nothing; clear and reset zero both",
        harness=lambda: QuadratureSpec(make_decoder()),
        depth=2, cover_depth=12)


def head_status_proof(*, make_receiver=None, helpers=True, name="head_status"):
    """The status receiver at 4 clocks a bit (its fewest): frames taken and refused as the
    spec samples them, the status word only from a good frame, a lost head read as 0. Helper
    invariants tie the receiver's bit and tick counters and bits to the spec's one counter, so
    the induction is a few clocks deep, not a frame (80 clocks)."""
    make_receiver = make_receiver or (lambda: XY2StatusReceiver(clocks_per_bit=4))
    return Proof(
        name=name,
        description="head status: a frame is taken only with code 001 and even parity, and "
                    "gives its data bits; every other is refused; the status changes on "
                    "nothing else; 8 refused frames in a row make the head missing, read as 0",
        harness=lambda: XY2StatusSpec(make_receiver(), helpers=helpers),
        # (A broken receiver's bounded check sees a whole frame: 80 clocks after its strobe.)
        depth=4, cover_depth=90, bmc_depth=90)


def fly_offset_proof(*, make_stage=None, name="fly_offset"):
    """The fly offset stage: a point moved by the belt's offset is held in the field, never
    wrapped, and flagged when held (a combinational stage: one clock is the whole proof)."""
    make_stage = make_stage or FlyOffset
    return Proof(
        name=name,
        description="fly offset: each axis is the point plus its offset held within 0 … "
                    "65535, never wrapped; clipped exactly when held",
        harness=lambda: FlyOffsetSpec(make_stage()),
        depth=1, cover_depth=2)


def fly_clipped_proof(*, held=True, make_gate=None, helpers=True, name=None):
    """The gate that keeps the laser off while a point held at the field's edge is on the
    wires, with the correction stage between (``held``) or without."""
    make_gate = make_gate or (lambda: ClippedOnWires(held=held))
    return Proof(
        name=name or f"fly_clipped_{'held' if held else 'direct'}",
        description="fly: marking passes exactly while the point on the wires was not held at "
                    "the field's edge: a clipped point never fires",
        harness=lambda: ClippedOnWiresSpec(make_gate(), helpers=helpers),
        depth=3, cover_depth=6)


def queue_io_proof(*, make_stage=None, helpers=True, name="queue_io"):
    """I/O in the queue: an I/O word never reaches the sequencer and starts only once it is
    idle; a wait ends only at its input's level; a time-out holds the queue until a flush;
    the outputs change only as the words say. With 4 frames a ms (``frame_us`` 250: the
    timer's length does not enter the properties) and the encoders' words built."""
    make_stage = make_stage or (lambda: QueueIO(frame_us=250, encoders=True))
    return Proof(
        name=name,
        description="queue I/O: an I/O word never reaches the sequencer and starts only once "
                    "it is idle; a wait for an input ends only at its level (an edge wait: "
                    "after being away); a timed-out wait holds the queue until a flush, one "
                    "without a limit never times out; outputs change only by their words",
        harness=lambda: QueueIOSpec(make_stage(), helpers=helpers),
        depth=4, cover_depth=12)


PROOFS = [
    # The smallest divider, as simulated, with the reset free.
    xy2_phy_proof(2),
    # The iCEBreaker's 12 MHz system clock, from power-up and after any reset (with the helper
    # invariants the induction is a few clocks deep, so the free reset costs nothing).
    xy2_phy_proof(6),
    # With the Z line (the ULX3S's build), at the smallest divider.
    xy2_phy_proof(2, z=True),
    spi_frame_proof(),
    command_path_proof(),
    laser_safety_proof(),
    # As built with vector mode: the PRR clock runs free and leads pulse_ahead (MO gates it).
    laser_safety_proof(
        make_controller=lambda: LaserController(**LASER_PROOF_PARAMETERS, lookahead=3),
        name="laser_safety_free_prr"),
    correction_proof(),
    correction_link_proof(),
    player_proof(),
    pixel_line_proof("words"),
    pixel_line_proof("dark_lines"),
    encoder_proof(),
    head_status_proof(),
    fly_offset_proof(),
    fly_clipped_proof(held=True),
    fly_clipped_proof(held=False),
    queue_io_proof(),
]
