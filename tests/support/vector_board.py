"""Vector jobs on a simulated board, for the end-to-end tests of vector mode, raster mode,
wobble and the RTC delays: a board built for vector jobs, segments queued through the real
client, the pulses on every frame read off the pins."""

import bisect

from galvoscan.gateware.fields import pack
from galvoscan.gateware.host.regmap import VectorOp
from galvoscan.gateware.sources.vector import PixelVecOpWord
from galvoscan.gateware.top import VECTOR_QUEUE_DEPTH, ScanSettings
from galvoscan.link.client import HostClient

from sim_board import VECTOR_ONLY, SimBoard, SimSPITransport, SimUARTTransport
from vector_model import merge


def jobs_board(clk_freq=4e6, *, vector_queue_depth=VECTOR_QUEUE_DEPTH, backend="compiled",
               **settings):
    """The jobs' build, fresh from power-up: vector mode alone (half the design of the default
    build's to simulate), with the wobble stage, the RTC delays and pixel lines, so that the
    vector, wobble, delay and pixel-line tests share one compiled model; jobs without them
    write :data:`NO_DELAYS` and leave the wobble off, as at power-up."""
    # (The UART at 8 clocks a bit, the fastest it takes: the job link's.)
    return SimBoard.powered_up(backend=backend, clk_freq=clk_freq,
                               baud=round(clk_freq / 8), record_laser=True,
                               mo_lead=0.2e-3, vector_queue_depth=vector_queue_depth,
                               wobble=True, vector_delays=True, pixel_lines=True,
                               **VECTOR_ONLY,
                               settings=ScanSettings(mode="vector", run=False, **settings))


def start_board(clk_freq=4e6, **kwargs):
    """:func:`jobs_board` (``kwargs`` as it takes them) and the real client over its SPI
    pins."""
    board = jobs_board(clk_freq, **kwargs)
    return board, HostClient(SimSPITransport(board, clocks_per_sck=12))


def queue(client, job, *, factors=None):
    """The job's segments, a checked frame each, back to back; ``factors``: each mark's
    polygon_scaled factor (vec_op bits 1 up; RTC delay builds). A ``"line"`` is a mark with
    ``pixels`` set, a ``"pixels"`` word a jump with it (bit 8, pixel-line builds)."""
    words = []
    ops = {"jump": VectorOp.JUMP, "mark": VectorOp.MARK, "line": VectorOp.MARK,
           "pixels": VectorOp.JUMP}
    for index, (op, x_to, y_to) in enumerate(job):
        factor = 0 if factors is None else factors[index]
        words.append((pack(PixelVecOpWord, op=ops[op], pixels=int(op in ("line", "pixels")),
                           corner_frames=factor if op in ("mark", "line") else 0), x_to, y_to))
    if words:
        client.queue_segments(words)


def pulses_per_frame(board, since=0):
    """(position, pulses) per frame read off the pins, frame ``since`` on: frames from the
    tests' XY2 reader, each in force from the end of its frame (the rising SYNC edge that
    starts the next one); pulses are rising PRR edges while modulation is on, given to the
    frame in force before them."""
    frames = [f for _, f in board.xy2_frames()]
    sync = board.sync_pins
    starts = [i for i in range(1, len(sync)) if sync[i] and not sync[i - 1]]
    pins = board.laser_pins
    counts = [0] * len(frames)
    # A pulse goes to frame `since` or later only from the edge that ends the frame after it.
    first = starts[since] if 0 < since < len(starts) else 1
    for clock in range(max(1, first), len(pins)):
        if pins[clock][2] and not pins[clock - 1][2] and pins[clock][1]:
            frame = bisect.bisect_left(starts, clock) - 2
            assert frame >= 0, "a pulse before any frame was sent"
            counts[frame] += 1
    return list(zip(frames, counts))[since:]


def runs_on_the_wires(board):
    return merge(pulses_per_frame(board))


#: Vector mode as Wan et al.'s, on the jobs' build (:func:`start_board`): its RTC delays at 0,
#: with which they change nothing (tests/gateware/sources/test_vector_delays.py checks that).
NO_DELAYS = {"laser_on_delay": 0, "laser_off_delay": 0, "mark_delay": 0}


def job_link(board):
    """The real client over the UART at 8 clocks a bit; the segments go back to back, each
    answered as it lands."""
    link = SimUARTTransport(board)
    return link, HostClient(link)


def set_up_job(board, job, registers, *, always=(), factors=None):
    """Over :func:`job_link`: ``registers`` (``(name, value)`` pairs; those at their reset
    value, on this board fresh from power-up, are left alone unless named in ``always``), the
    laser armed, the job queued meanwhile, and run once the MO lead (0.2 ms) has passed since
    arming; returns the client."""
    link, client = job_link(board)
    regmap = board.top.regmap
    for name, value in registers:
        if value != regmap[name].reset or name in always:
            client.write(name, value)
    client.write("arm", 1)
    armed = board.now
    queue(client, job, factors=factors)
    board.run_for(max(0, armed + 0.3e-3 - board.now))       # MO lead
    client.write("run", 1)
    return client
