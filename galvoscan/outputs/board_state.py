"""The board's state read off its registers and said in words: what ``galvoscan status``
prints, what the meerk40t device says in its console (:meth:`BoardState.summary`) and shows in
meerk40t's status bar (:meth:`BoardState.short`, the same words, fewer), and what the job
streamer refuses on.

The scan head's part comes from a bitstream with the head status receiver (``caps`` bit
``head``): the head's status word as RTC5/RTC6's ``get_head_status`` reads it (Power OK, Temp
OK, PosAck per axis; a missing head reads 0), whether the laser obeys it (``head_check``), the
latched head fault, and the status frames refused.
"""

from dataclasses import dataclass

from ..gateware.host.regmap import Capabilities, HeadState, HeadStatus, Status


__all__ = ["HeadReading", "BoardState", "read_head", "read_board_state", "LATCHED_FAULTS"]


#: The latched faults of ``status``, by the names its ``fault_*`` flags have.
LATCHED_FAULTS = ("interlock", "watchdog", "alarm", "link")

#: The head's bits a person reads, and how they are said.
_HEAD_WORDS = (("power_ok", "Power OK"), ("temp_ok", "Temp OK"), ("pos_ack_x", "PosAck X"),
               ("pos_ack_y", "PosAck Y"))


@dataclass(frozen=True)
class HeadReading:
    """The scan head as the board last heard it.

    Attributes
    ----------
    word : int
        The ``head`` register: the head's status word (0 while no head answers).
    missing : bool
        No good status frame in the last 8 (``head_state`` bit 0).
    fault : bool or None
        The latched head fault (None: a build without the laser has none).
    check : bool or None
        ``head_check``: the laser obeys the head (None: no laser).
    refused : int
        Status frames refused since reset (``head_bad``).
    """
    word: int
    missing: bool
    fault: object
    check: object
    refused: int

    @property
    def bits(self):
        return HeadStatus.from_bits(self.word)

    def problem(self):
        """What keeps this head from marking, in words, or None: no answer, or Temp OK or
        Power OK low."""
        if self.missing:
            return "no answer on its STATUS line"
        low = [said for name, said in _HEAD_WORDS[:2] if not getattr(self.bits, name)]
        return f"{' and '.join(low)} low" if low else None

    def short(self):
        """A few words for a status bar: ``head ok``, ``head missing`` or what is low (``head:
        Temp OK low``); its latched fault is among the board's (:meth:`BoardState.latched`)."""
        if self.missing:
            return "head missing"
        problem = self.problem()
        return f"head: {problem}" if problem else "head ok"

    def describe(self):
        """One line: the bits set, the word, the check and the fault."""
        if self.missing:
            said = "missing (no answer on its STATUS line; reads 0)"
        else:
            on = [said for name, said in _HEAD_WORDS if getattr(self.bits, name)]
            off = [said for name, said in _HEAD_WORDS[:2] if not getattr(self.bits, name)]
            said = ", ".join(on + [f"no {x}" for x in off]) or "no bit set"
        parts = [f"{said} (word 0x{self.word:04X})"]
        if self.check is not None:
            parts.append("the laser obeys it" if self.check else
                         "only reported (head_check 0)")
        if self.fault:
            parts.append("head fault latched (`galvoscan send fault_clear=1` clears it once "
                         "the head is well)")
        parts.append(f"{self.refused} status frame{'s' if self.refused != 1 else ''} refused")
        return "; ".join(parts)

    def as_dict(self):
        return {"word": self.word, "missing": self.missing, "fault": self.fault,
                "check": self.check, "refused": self.refused,
                **{name: bool(getattr(self.bits, name)) for name, _ in _HEAD_WORDS}}


@dataclass(frozen=True)
class BoardState:
    """The board's flags (``status``) and its head (None: a build without the receiver)."""
    flags: object
    head: object = None

    def latched(self):
        """The latched faults' names, the head's with them."""
        names = [name for name in LATCHED_FAULTS if getattr(self.flags, f"fault_{name}")]
        if self.head is not None and self.head.fault:
            names.append("head")
        return names

    def busy(self):
        """What keeps the board busy, in words (segments queued, or the flash's job playing),
        or None: it is ready."""
        if self.flags.vector_busy:
            return "segments queued"
        if self.flags.player_busy:
            return "playing the flash's job"
        return None

    def _conditions(self):
        """The words the console's line and the status bar share after busy or ready."""
        flags = self.flags
        return ["armed" if flags.armed else "disarmed",
                "interlock open" if flags.interlock_open else "interlock closed",
                *(["laser alarm"] if flags.alarm else [])]

    def summary(self):
        """One line: busy or ready, armed, the interlock, an alarm, the latched faults."""
        busy, latched = self.busy(), self.latched()
        return ", ".join([
            f"busy ({busy})" if busy else "ready", *self._conditions(),
            (f"latched fault: {', '.join(latched)} (`galvoscan send fault_clear=1` clears it)"
             if latched else "no fault latched")])

    def short(self, activity=None):
        """The state in a few words, for a status bar: busy or ready (``activity``: what the
        host knows the board is doing, in their place: ``busy`` while its job runs, whatever
        the queue holds), armed, the interlock, an alarm, the head (:meth:`HeadReading.short`:
        a bitstream with the receiver) and the latched faults (``fault: interlock``)."""
        latched = self.latched()
        return ", ".join([
            activity or ("busy" if self.busy() else "ready"), *self._conditions(),
            *([] if self.head is None else [self.head.short()]),
            *([f"fault: {', '.join(latched)}"] if latched else [])])

    def lines(self):
        """What ``galvoscan status`` prints."""
        lines = [f"board: {self.summary()}"]
        if self.head is not None:
            lines.append(f"head: {self.head.describe()}")
        return lines

    def as_dict(self):
        return {"flags": {name: bool(self.flags[name]) for name, _ in Status},
                "latched": self.latched(),
                "head": None if self.head is None else self.head.as_dict()}


def read_head(client, caps=None):
    """The head's :class:`HeadReading` off ``client`` (a
    :class:`~galvoscan.link.client.HostClient`), or None on a bitstream without the receiver.
    ``caps``: the ``caps`` flags, if already read."""
    if caps is None:
        caps = Capabilities.from_bits(client.read("caps"))
    if not caps.head:
        return None
    word = client.read("head")
    refused = client.read("head_bad")
    if caps.laser:
        state = HeadState.from_bits(client.read("head_state"))
        return HeadReading(word=word, missing=bool(state.missing), fault=bool(state.fault),
                           check=bool(client.read("head_check")), refused=refused)
    # (Without the laser the word is all there is; a missing head reads 0.)
    return HeadReading(word=word, missing=word == 0, fault=None, check=None, refused=refused)


def read_board_state(client):
    """The :class:`BoardState` off ``client``."""
    flags = Status.from_bits(client.read("status"))
    return BoardState(flags=flags, head=read_head(client))
