"""The spiral's interpolation switched, and its dwell changed, while it runs: written through the
SPI pins with the real client, read off the XY2-100 wires, against the tests' model
(spiral_model.py). A change takes effect at a point boundary, within the time the write takes
and one point more; the test finds the boundaries that explain the wires, and there must be
some."""

from hypothesis import HealthCheck, given, settings, strategies as st

from galvoscan.link.client import HostClient
from galvoscan.gateware.sources.spiral_table import SpiralTable
from galvoscan.gateware.top import ScanSettings

from sim_board import SimBoard, SimSPITransport
from spiral_model import PARK, between, scaled, spiral_offsets


FRAME_S = 10e-6


def point_frames(p, q, dwell, interp):
    """The frames of one point (offsets ``p`` to ``q``), centred, gain 1."""
    return [(scaled(between(p[0], q[0], k, dwell) if interp else p[0], 32768, 32768),
             scaled(between(p[1], q[1], k, dwell) if interp else p[1], 32768, 32768))
            for k in range(dwell)]


def explained(frames, offsets, epochs, windows):
    """Whether the frames (from power-up) are the model's with setting ``epochs[j]`` from some
    point boundary within ``windows[j]`` (frame indices) on, for each j ≥ 1."""
    if frames[:2] != [PARK, PARK]:
        return False
    todo, seen = [(2, 0, 0)], set()
    while todo:
        state = todo.pop()
        if state in seen:
            continue
        seen.add(state)
        frame, point, epoch = state
        if frame >= len(frames):
            return epoch == len(epochs) - 1
        choices = [epoch]
        while choices[-1] + 1 < len(epochs) and \
                windows[choices[-1] + 1][0] <= frame <= windows[choices[-1] + 1][1]:
            choices.append(choices[-1] + 1)
        for chosen in choices:
            dwell, interp = epochs[chosen]
            want = point_frames(offsets[point], offsets[point + 1], dwell, interp)
            got = frames[frame:frame + dwell]
            if got == want[:len(got)]:
                todo.append((frame + dwell, point + 1, chosen))
    return False


def frame_index(board, t):
    """Index of the first frame that ends after ``t``."""
    return sum(1 for end, _ in board.xy2_frames() if end <= t)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 5), st.integers(0, 1),
       st.lists(st.tuples(st.sampled_from(["spiral_interp", "dwell"]), st.integers(0, 5),
                          st.floats(0.1e-3, 0.4e-3)), min_size=1, max_size=3))
def test_switching_interpolation_and_dwell_while_running(dwell, interp, writes):
    table = SpiralTable()
    board = SimBoard(table=table, modes=("spiral",), correction=None,
                     settings=ScanSettings(dwell=dwell, spiral_interp=interp))
    client = HostClient(SimSPITransport(board))
    board.run_for(0.2e-3)
    epochs, windows = [(dwell, interp)], [None]
    for name, value, then in writes:
        value = max(1, value) if name == "dwell" else value % 2
        before = board.now
        client.write(name, value)
        dwell, interp = (value, interp) if name == "dwell" else (dwell, value)
        epochs.append((dwell, interp))
        longest = max(d for d, _ in epochs)
        windows.append((frame_index(board, before),
                        frame_index(board, board.now) + 2 * longest + 3))
        board.run_for(then)
    frames = [frame for _, frame in board.xy2_frames()]
    offsets = spiral_offsets(table.x, table.y, len(frames) + 1, x_range=(0, 127),
                             y_range=(1, 126))
    assert explained(frames, offsets, epochs, windows)
