"""What the link can carry of a job, known before any byte is sent: the segments a second the
serial line brings into the board's queue (:func:`link_segments_per_s`), and where a planned
job would outrun it (:func:`expected_underruns`), followed segment by segment as
:class:`~.stream.JobStreamer` will send it. ``mark`` warns from it; ``bench`` holds it to the
simulated board's counters.
"""

from ..geometry.speed import segment_seconds
from ..link.client import frame_seconds
from .queue_words import job_segments
from .stream import DEFAULT_BATCH, QUEUE_DEPTH


__all__ = ["link_segments_per_s", "expected_underruns"]


def link_segments_per_s(baud, *, batch=None):
    """Segments a second the serial link carries at ``baud``: their frames back to back
    (:func:`~galvoscan.link.client.frame_seconds`), and a read of ``fifo_free`` (a frame of
    the same length) for every ``batch`` segments (default: the streamer's), which the
    streamer makes when the queue is full. (Measured through the simulated board's UART:
    8,271 a second at 1 Mbaud and 24,864 at 3 Mbaud, docs/bench.json; this gives 8,268 and
    24,806.)"""
    batch = batch or DEFAULT_BATCH
    return 1 / (frame_seconds(baud) * (1 + 1 / batch))


def expected_underruns(job, baud, *, queue_depth=QUEUE_DEPTH, batch=None):
    """Marks of ``job`` (a planned :class:`~galvoscan.plan.vector_job.VectorJob`; a job of
    layers, each layer's, streamed in turn) that will find the board's queue empty when it is
    streamed at ``baud``: ``[(layer label or None, underruns)]`` for those that have any.

    The streamer's own course, segment by segment: the link brings a segment every
    ``1 / link_segments_per_s(baud)`` s, but no sooner than a place is free in the
    ``queue_depth``-place queue; the board starts once the first batches are in (as
    :meth:`~.stream.JobStreamer.stream` does) and takes each segment no sooner than it has
    come and the last one is done, a segment taking its
    :func:`~galvoscan.geometry.speed.segment_seconds`. A mark whose end finds the next segment
    not yet come is an underrun, as the board counts them. Those times leave out the mark and
    polygon delays, so a board takes segments no faster than this supposes: an underrun may
    be foretold that does not happen, hardly ever the other way round."""
    period = 1 / link_segments_per_s(baud, batch=batch)
    batch = batch or DEFAULT_BATCH
    layers = [(layer.label, layer.job) for layer in job.layers] if job.layers else [(None, job)]
    found = []
    for label, part in layers:
        registers = part.registers
        segments = job_segments(part.segments)
        seconds = segment_seconds(segments, pitch_units=registers["pitch"],
                                  pulses_per_point=registers["pulses_per_point"],
                                  prr_hz=registers["laser_prr"] * 100.0,
                                  jump_delay_us=registers["jump_delay"])
        # The board runs once the batch that leaves less than a batch free is in.
        first = min(len(segments), batch * -(-(queue_depth - batch + 1) // batch), queue_depth)
        taken = []              # when each segment left the queue (its place free again)
        came = done = 0.0       # when the last segment came; when the board was done with it
        underruns = 0
        for k, op_seconds in enumerate(seconds):
            room = taken[k - queue_depth] if k >= queue_depth else 0.0
            came = max(came, room) + period
            if k == 0:
                done = first * period      # (the first ones come one after the other)
            elif came > done and segments[k - 1][0] != "jump":
                underruns += 1
            taken.append(max(done, came))
            done = taken[k] + op_seconds
        if underruns:
            found.append((label, underruns))
    return found
