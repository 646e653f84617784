"""Run a vector job on the simulated system top, as a host would, and read what comes out.

The job goes in through the SPI pins, streamed by the host's job streamer (batches, the queue
topped up as ``fifo_free`` allows) on the simulated board; the XY2-100 wires are decoded as a
scan head would; the laser's pulses are counted on the DB25 pins and given to the point the
head holds when they fire. Simulated at the board's 12 MHz (6 clocks per XY2 bit), so the
timing is the board's.
"""

from ..gateware.host.regmap import BY_NAME
from ..gateware.top import ScanSettings
from ..link.client import HostClient
from ..outputs.stream import JobStreamer
from .board import SimSPITransport, SimulatedBoard
from .xy2_receiver import frame_of_each_pulse


__all__ = ["JobResult", "replay_job"]


class JobResult:
    """What the head and the laser saw.

    Attributes
    ----------
    frames : list of (int, int, int)
        ``(x, y, pulses)`` per XY2-100 frame from power-up: the position, and the pulses that
        fell while the head held it.
    points : list of (int, int, int, int)
        ``(x, y, pulses, frames)`` per run of frames at one position.
    clk_freq : float
    """

    def __init__(self, frames, clk_freq):
        self.frames = frames
        self.clk_freq = clk_freq
        points = []
        for x, y, pulses in frames:
            if points and points[-1][:2] == [x, y]:
                points[-1][2] += pulses
                points[-1][3] += 1
            else:
                points.append([x, y, pulses, 1])
        self.points = [tuple(p) for p in points]

    def marked(self):
        """Points that got at least one pulse."""
        return [p for p in self.points if p[2] > 0]


def replay_job(job, *, prr_hz=60e3, pulses_per_point=1, pitch=60, jump_delay=500,
               clk_freq=12e6, mo_lead=5e-3, progress=None, correction="identity", vcd=None,
               backend="python", say=None):
    """Simulate ``job`` (a list of ``(op, x, y)``) and return a :class:`JobResult`.

    The job is run as ``mark`` runs one: the host's job streamer over the SPI pins, in the
    board's own time, on a :class:`~galvoscan.sim.board.SimulatedBoard` of ``backend``
    (``say`` is told about a compile). ``vcd``, a path, writes a waveform of the whole run
    (the Python backend); ``progress`` is called with the number of new frames as they reach
    the head.
    """
    prr = round(prr_hz / 100)
    if not BY_NAME["laser_prr"].low <= prr <= BY_NAME["laser_prr"].high:
        raise ValueError(f"PRR must be from 20 to 200 kHz, not {prr_hz:g} Hz")
    for name, value in (("pulses_per_point", pulses_per_point), ("pitch", pitch),
                        ("jump_delay", jump_delay)):
        reg = BY_NAME[name]
        if not isinstance(value, int) or not reg.low <= value <= reg.high:
            raise ValueError(f"{name} must be an integer from {reg.low} to {reg.high}, "
                             f"not {value!r}")
    if vcd and backend == "compiled":
        raise ValueError("a waveform (vcd) needs the Python backend")
    registers = {"laser_prr": prr, "pulses_per_point": pulses_per_point, "pitch": pitch,
                 "jump_delay": jump_delay, "laser_power": 128,
                 # The longest watchdog: the simulated host is slow, not silent.
                 "watchdog": BY_NAME["watchdog"].high}
    board = SimulatedBoard(clk_freq=clk_freq, baud=None, backend="python" if vcd else backend,
                           say=say,
                           vcd=vcd, mo_lead=mo_lead,
                           settings=ScanSettings(mode="vector", run=False),
                           correction=correction)
    try:
        client = HostClient(SimSPITransport(board))
        streamer = JobStreamer(client, poll_s=0)
        if progress is not None:
            seen = [0]

            def frames_so_far(_done):
                progress(len(board.frames) - seen[0])
                seen[0] = len(board.frames)
            streamer.progress = frames_so_far
        report = streamer.run_vector(list(job), registers, timeout_s=1e9)
        board.run_for(50e-6)                     # the last frames reach the head
        errors, rejected = report.counters.get("errors"), report.counters.get("vec_rejected")
        if errors or rejected:
            raise RuntimeError(f"the board refused {errors} frames ({rejected} segments)")
        counts = [0] * len(board.frames)
        for k, _ in frame_of_each_pulse(board.sync_rises, board.pulses, len(board.frames)):
            counts[k] += 1
        return JobResult([(x, y, n) for (_, x, y), n in zip(board.frames, counts)], clk_freq)
    finally:
        board.close()
