"""What feeds the laser's watchdog: progress, not chatter."""

from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


__all__ = ["ProgressFeed"]


class ProgressFeed(wiring.Component):
    """Tells the laser controller's watchdog that a job goes on: a segment the host queued, a
    ``keepalive`` the host wrote, or the job player's next word. Reading registers is no sign
    of that (a host may poll ``status`` while the board does the wrong thing), nor is a write
    of any other register.

    The news goes out a clock late: a flip-flop takes the register file's checks off the path
    into the laser's timers.

    Interface attributes
    --------------------
    segment : ``In(1)``
        The decoder's write done this clock is a segment (``vec_op``).
    pushed : ``In(1)``
        ``vec_op_push``: the queue took a segment this clock.
    keepalive : ``In(1)``
        The ``keepalive`` strobe.
    player : ``In(1)``
        The job player's sign of life.
    alive : ``Out(1)``
        To the laser controller's ``alive``.
    """

    segment: In(1)
    pushed: In(1)
    keepalive: In(1)
    player: In(1)
    alive: Out(1)

    def elaborate(self, platform):
        m = Module()
        m.d.sync += self.alive.eq((self.segment & self.pushed) | self.keepalive | self.player)
        return m
