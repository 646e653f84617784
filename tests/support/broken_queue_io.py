"""Deliberately broken I/O stages of the queue, to show that the queue I/O proof catches each
fault: the real stage with one rule changed."""

from galvoscan.gateware.sources.queue_io import QueueIO


#: Each fault: what it does, and the property it breaks.
QUEUE_IO_FAULTS = {
    "io_to_sequencer": ("an I/O word is shown to the sequencer as a segment",
                        "every command but an I/O word reaches the sequencer; an I/O word "
                        "never"),
    "ignores_busy": ("an I/O word starts while segments before it are still marking",
                     "an I/O word is taken only once the sequencer is idle with it at the head"),
    "any_level": ("a wait for an input ends whatever the input",
                  "a wait for an input ends only at its level (an edge: once away)"),
    "no_edge": ("an edge wait ends at the level, a part already under the sensor taken again",
                "a wait for an input ends only at its level (an edge: once away)"),
    "runs_on": ("a wait that timed out ends when the input comes after all",
                "a wait that timed out holds the queue until a flush"),
}


class BrokenQueueIO(QueueIO):
    def __init__(self, fault):
        if fault not in QUEUE_IO_FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault
        super().__init__(frame_us=250, encoders=True)

    def _to_sequencer(self, valid, io):
        if self.fault == "io_to_sequencer":
            return valid
        return super()._to_sequencer(valid, io)

    def _idle(self):
        if self.fault == "ignores_busy":
            return 1
        return super()._idle()

    def _reached(self, input_now, level, seen_away):
        if self.fault == "any_level":
            return 1
        if self.fault == "no_edge":
            return input_now == level
        return super()._reached(input_now, level, seen_away)

    def _held(self, timed_out):
        if self.fault == "runs_on":
            return 0
        return super()._held(timed_out)
