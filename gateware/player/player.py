"""The job player: runs a job image from the flash as a host would, on each start."""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import enum, stream, wiring
from amaranth.lib.wiring import In, Out

from ..host.fields import Mode, PlayerResult, PlayerState
from ..host.registers import RegisterBus
from ..host.regmap import BY_NAME
from .crc32 import CRC32
from .image_format import (CRC_BYTES, FORMAT_VERSION, HEADER_BYTES, HEADER_WORDS, JOB_OFFSET,
                           MAGIC_WORDS, MAX_IMAGE_BYTES, PLAYER_OWNED, SEGMENT_WORDS, Word)


__all__ = ["JobPlayer"]


class _Section(enum.Enum, shape=2):
    HEADER = 0
    SETTINGS = 1
    SEGMENTS = 2


class JobPlayer(wiring.Component):
    """Plays the job image at :data:`~.image_format.JOB_OFFSET` on each start.

    On :attr:`start` it reads the whole image and checks it: magic, version, length (even,
    within the flash, ending on a whole segment), repeats, that no setting addresses a
    register of :data:`~.image_format.PLAYER_OWNED`, and the CRC-32 of every byte. An image
    that fails writes nothing and arms nothing; it is counted in :attr:`refused` and named in
    :attr:`result`. One that passes is read again and played as a host plays a job
    (:class:`~galvoscan.jobs.stream.JobStreamer`): vector mode is selected, stopped, and the
    image's settings written; its segments go into the queue as ``vec_x``, ``vec_y``,
    ``vec_op`` writes until it is full (or the job is all in); then ``arm`` is set, the MO
    lead waited out (``laser_ready``) and ``run`` set, and the rest of the segments follow as
    the queue frees up. Each time the queue has run dry, the segments are played again, for
    the image's repeats; then ``arm`` is cleared, the queue emptied (``vec_flush``) and
    ``run`` cleared.

    Every register it writes goes through the register file's own checks, on the clocks
    :attr:`grant` gives it (those without a host frame): a refused write stops the job. It
    stops in the same way (laser first) when the laser faults while armed, or when a host
    writes ``arm``, ``run`` or ``mode`` (:attr:`host_took_over`).

    Parameters
    ----------
    max_image_bytes : int
        The largest image taken (:data:`~.image_format.MAX_IMAGE_BYTES`; a proof takes a
        small one).
    offset : int
        The image's flash address.

    Interface attributes
    --------------------
    read_address : ``Out(24)``; read_start, read_stop : ``Out(1)``;
    read_data : ``In(stream.Signature(8))``; read_idle : ``In(1)``
        To the flash reader (:class:`~..flash.spi_flash.SPIFlashReader`).
    bus : ``Out(RegisterBus())``; grant : ``In(1)``
        Writes to the register file, given on a clock ``grant`` is high (the arbiter's).
    start : ``In(1)``
        A press of the start input (ignored while busy).
    queue_ready, queue_empty, vector_busy : ``In(1)``
        The vector queue can take a segment; holds none; the sequencer is at work.
    laser_ready : ``In(1)``
        Armed and past the MO lead, with the laser enabled.
    fault : ``In(1)``
        A laser fault is latched.
    host_took_over : ``In(1)``
        A host has just written ``arm``, ``run`` or ``mode``.
    state : ``Out(PlayerState)``; result : ``Out(PlayerResult)``
        What it is doing, and how the last start ended (``NONE`` while it runs).
    refused : ``Out(8)``
        Images refused since reset (stops at 255).
    armed : ``Out(1)``
        It has set ``arm`` in this start (its check passed).
    alive : ``Out(1)``
        Progress, for the laser's watchdog: a write of its own done, or the machine at work
        while the player waits on it (the MO lead, a full queue, the queue running dry).
    """

    def __init__(self, *, max_image_bytes=MAX_IMAGE_BYTES, offset=JOB_OFFSET):
        if not isinstance(max_image_bytes, int) or max_image_bytes % 2 or \
                not HEADER_BYTES <= max_image_bytes <= MAX_IMAGE_BYTES:
            raise ValueError(f"max_image_bytes must be an even number from {HEADER_BYTES} to "
                             f"{MAX_IMAGE_BYTES}, not {max_image_bytes!r}")
        if not isinstance(offset, int) or offset < 0 or offset + max_image_bytes > 1 << 24:
            raise ValueError(f"an image of {max_image_bytes} bytes at {offset!r} does not fit "
                             f"24-bit flash addresses")
        self.max_image_bytes = max_image_bytes
        self.offset = offset
        super().__init__({
            "read_address": Out(24), "read_start": Out(1), "read_stop": Out(1),
            "read_data": In(stream.Signature(8)), "read_idle": In(1),
            "bus": Out(RegisterBus()), "grant": In(1),
            "start": In(1), "queue_ready": In(1), "queue_empty": In(1), "vector_busy": In(1),
            "laser_ready": In(1), "fault": In(1), "host_took_over": In(1),
            "state": Out(PlayerState), "result": Out(PlayerResult), "refused": Out(8),
            "armed": Out(1), "alive": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.crc = crc = CRC32()
        words_max = self.max_image_bytes // 2

        # --- its writes to the register file, one at a time ----------------------------------
        # A write waits for a clock the arbiter grants, and is done (or refused) on the next.
        write_address = Signal(7)
        write_value = Signal(16)
        write_waiting = Signal()        # given, not yet granted
        write_checking = Signal()       # granted: done or refused on this clock
        write_refused = Signal()        # the last write was refused
        write_free = ~write_waiting & ~write_checking
        m.d.comb += [self.bus.address.eq(write_address), self.bus.write_data.eq(write_value),
                     self.bus.write_en.eq(write_checking)]
        with m.If(write_waiting & self.grant):
            m.d.sync += [write_waiting.eq(0), write_checking.eq(1)]
        wrote = Signal()                # a write of its own done: progress
        waiting_on_machine = Signal()   # waiting for the machine, which is at work
        m.d.comb += [wrote.eq(write_checking & self.bus.write_ok),
                     self.alive.eq(wrote | waiting_on_machine)]
        with m.If(write_checking):
            m.d.sync += [write_checking.eq(0), write_refused.eq(~self.bus.write_ok)]

        def write(register, value):
            address = BY_NAME[register].address if isinstance(register, str) else register
            m.d.sync += [write_address.eq(address), write_value.eq(value),
                         write_waiting.eq(1), write_refused.eq(0)]

        # --- the image: bytes into words and into the CRC -------------------------------------
        live = Signal()                 # the second reading, which writes
        section = Signal(_Section)
        header_word = Signal(range(HEADER_WORDS))
        byte_high = Signal()            # the next byte is a word's high byte
        low_byte = Signal(8)
        word = Signal(16)
        word_valid = Signal()
        take_byte = Signal()
        # The CRC reads its own four bytes as zero.
        header_byte = Cat(byte_high, header_word)
        in_crc_field = (section == _Section.HEADER) & \
            (header_byte >= CRC_BYTES.start) & (header_byte < CRC_BYTES.stop)
        m.d.comb += [
            self.read_data.ready.eq(take_byte),
            crc.data.eq(Mux(in_crc_field, 0, self.read_data.payload)),
            crc.strobe.eq(self.read_data.valid & take_byte),
        ]
        with m.If(self.read_data.valid & take_byte):
            m.d.sync += byte_high.eq(~byte_high)
            with m.If(byte_high):
                m.d.sync += [word.eq(Cat(low_byte, self.read_data.payload)), word_valid.eq(1)]
            with m.Else():
                m.d.sync += low_byte.eq(self.read_data.payload)

        remaining = Signal(range(words_max + 1))    # words of the image still to come
        length_low = Signal(15)         # the length's low word, in words
        expected_crc = Signal(32)
        repeats = Signal(16)
        repeats_left = Signal(16)
        settings = Signal(16)           # (address, value) pairs
        settings_done = Signal(16)
        setting_address = Signal(7)
        setting_value_next = Signal()   # the next settings word is a value
        segment_word = Signal(range(SEGMENT_WORDS))
        segment_words = Signal(range(words_max + 1))    # words of segments in the image
        result = Signal(PlayerResult)   # how this start ends
        segments_at = Signal(24)
        m.d.comb += segments_at.eq(self.offset + HEADER_BYTES + (settings << 2))

        def begin(address, *, segments_only=False):
            """Read from ``address``, from a word's start, after a clock with the reader
            stopped."""
            m.d.comb += self.read_stop.eq(1)
            m.d.sync += [self.read_address.eq(address), byte_high.eq(0), word_valid.eq(0),
                         segment_word.eq(0)]
            if not segments_only:
                m.d.sync += [section.eq(_Section.HEADER), header_word.eq(0),
                             remaining.eq(HEADER_WORDS), settings_done.eq(0),
                             setting_value_next.eq(0)]
                m.d.comb += crc.clear.eq(1)
            m.next = "READ"

        def stop(code):
            """End this start with ``code``: refused if nothing was written yet, else through
            the laser-first stop."""
            m.d.sync += result.eq(code)
            with m.If(live):
                m.next = "STOP"
            with m.Else():
                m.next = "REFUSE"

        owned = Cat(setting_address == BY_NAME[name].address
                    for name in PLAYER_OWNED if name in BY_NAME).any()

        with m.FSM() as fsm:
            with m.State("IDLE"):
                m.d.sync += [live.eq(0), self.armed.eq(0)]
                with m.If(self.start):
                    m.d.sync += [self.result.eq(PlayerResult.NONE),
                                 result.eq(PlayerResult.NONE)]
                    begin(self.offset)

            with m.State("READ"):
                m.d.comb += self.read_start.eq(1)
                with m.If(self.read_idle):
                    m.next = "PARSE"
                self._guard(m, live, result)

            with m.State("PARSE"):
                # A word is taken once the last write is done (and, for vec_op, once the queue
                # has room); the next word's bytes come meanwhile.
                queue_wait = live & (section == _Section.SEGMENTS) & (segment_word == 2) & \
                    ~self.queue_ready
                m.d.comb += [take_byte.eq(~word_valid),
                             waiting_on_machine.eq(live & (section == _Section.SEGMENTS) &
                                                   self.armed & ~self.queue_ready)]
                ended = (section != _Section.HEADER) & (remaining == 0)
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & word_valid & ~queue_wait & ~ended):
                    m.d.sync += [word_valid.eq(0), remaining.eq(remaining - 1)]
                    self._word(m, live, section, header_word, word, remaining, length_low,
                               expected_crc, repeats, settings, settings_done,
                               setting_address, setting_value_next, segment_word,
                               segment_words, owned, write, stop, words_max)
                with m.Elif(write_free & ended):
                    # The last word is in: it must end the settings, or a segment.
                    with m.If((section != _Section.SEGMENTS) | (segment_word != 0)):
                        stop(PlayerResult.BAD_HEADER)
                    with m.Elif(live):
                        m.d.comb += self.read_stop.eq(1)
                        m.next = "DRAIN"
                    with m.Else():
                        m.d.comb += self.read_stop.eq(1)
                        m.next = "VERDICT"
                # As a host does: the queue filled (or the job all in) before the laser is armed
                # and the mode run.
                with m.If(live & (section == _Section.SEGMENTS) & ~self.armed & write_free &
                          ~write_refused & (queue_wait | ended)):
                    m.next = "ARM"
                self._guard(m, live, result)

            with m.State("VERDICT"):
                with m.If(~crc.busy):
                    with m.If(crc.crc == expected_crc):
                        # Checked: vector mode, stopped, then the image read again and played.
                        m.d.sync += [live.eq(1), repeats_left.eq(repeats)]
                        write("run", 0)
                        m.next = "SELECT"
                    with m.Else():
                        stop(PlayerResult.BAD_CRC)
                self._guard(m, live, result)

            with m.State("SELECT"):
                with m.If(write_free):
                    write("mode", Mode.VECTOR.value)
                    begin(self.offset)
                self._guard(m, live, result)

            with m.State("ARM"):
                write("arm", 1)
                m.d.sync += self.armed.eq(1)
                m.next = "LEAD"
                self._guard(m, live, result)

            with m.State("LEAD"):
                m.d.comb += waiting_on_machine.eq(1)
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & self.laser_ready):
                    write("run", 1)
                    m.next = "PARSE"
                self._guard(m, live, result)

            with m.State("DRAIN"):
                m.d.comb += waiting_on_machine.eq(self.vector_busy | ~self.queue_empty)
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & self.queue_empty & ~self.vector_busy):
                    with m.If(repeats_left > 1):
                        m.d.sync += [repeats_left.eq(repeats_left - 1),
                                     remaining.eq(segment_words)]
                        begin(segments_at, segments_only=True)
                    with m.Else():
                        m.d.sync += result.eq(PlayerResult.DONE)
                        m.next = "STOP"
                self._guard(m, live, result)

            # The stop of a job that has written: laser off first (whatever write is under
            # way), then the queue emptied and the mode stopped.
            with m.State("STOP"):
                m.d.comb += self.read_stop.eq(1)
                write("arm", 0)
                m.next = "FLUSH"
            with m.State("FLUSH"):
                with m.If(write_free):
                    write("vec_flush", 1)
                    m.next = "HALT"
            with m.State("HALT"):
                with m.If(write_free):
                    write("run", 0)
                    m.next = "END"
            with m.State("END"):
                m.d.comb += self.read_stop.eq(1)
                with m.If(write_free):
                    m.d.sync += self.result.eq(result)
                    m.next = "IDLE"

            with m.State("REFUSE"):
                # Refused in the check, before any write: counted.
                m.d.comb += self.read_stop.eq(1)
                m.d.sync += self.result.eq(result)
                with m.If(self.refused != 255):
                    m.d.sync += self.refused.eq(self.refused + 1)
                m.next = "IDLE"

        m.d.comb += self.state.eq(Mux(fsm.ongoing("IDLE"), PlayerState.IDLE,
                                      Mux(live, PlayerState.RUNNING, PlayerState.CHECKING)))
        return m

    def _guard(self, m, live, result):
        """In a state of a start under way: whatever the state does, a host's write of
        ``arm``, ``run`` or ``mode``, or a fault while armed, ends the start (in the check,
        where nothing has been written, the host's write just ends it)."""
        with m.If(self.host_took_over):
            m.d.sync += result.eq(PlayerResult.HOST)
            with m.If(live):
                m.next = "STOP"
            with m.Else():
                m.next = "END"
        with m.Elif(self.armed & self.fault):
            m.d.sync += result.eq(PlayerResult.FAULT)
            m.next = "STOP"

    def _word(self, m, live, section, header_word, word, remaining, length_low, expected_crc,
              repeats, settings, settings_done, setting_address, setting_value_next,
              segment_word, segment_words, owned, write, stop, words_max):
        """What one word of the image does, in the check and in the playing."""
        def enter_segments():
            m.d.sync += [section.eq(_Section.SEGMENTS), segment_words.eq(remaining - 1)]

        with m.Switch(section):
            with m.Case(_Section.HEADER):
                m.d.sync += header_word.eq(header_word + 1)
                with m.Switch(header_word):
                    with m.Case(Word.MAGIC_LOW):
                        with m.If(word != MAGIC_WORDS[0]):
                            stop(PlayerResult.NO_IMAGE)
                    with m.Case(Word.MAGIC_HIGH):
                        with m.If(word != MAGIC_WORDS[1]):
                            stop(PlayerResult.NO_IMAGE)
                    with m.Case(Word.VERSION):
                        with m.If(word != FORMAT_VERSION):
                            stop(PlayerResult.BAD_VERSION)
                    with m.Case(Word.LENGTH_LOW):
                        m.d.sync += length_low.eq(word[1:])
                        with m.If(word[0]):
                            stop(PlayerResult.BAD_HEADER)
                    with m.Case(Word.LENGTH_HIGH):
                        words = Cat(length_low, word)
                        with m.If((words > words_max) | (words < HEADER_WORDS)):
                            stop(PlayerResult.BAD_HEADER)
                        # The words after this one.
                        m.d.sync += remaining.eq(words - (Word.LENGTH_HIGH + 1))
                    with m.Case(Word.CRC_LOW):
                        m.d.sync += expected_crc[:16].eq(word)
                    with m.Case(Word.CRC_HIGH):
                        m.d.sync += expected_crc[16:].eq(word)
                    with m.Case(Word.REPEATS):
                        m.d.sync += repeats.eq(word)
                        with m.If(word == 0):
                            stop(PlayerResult.BAD_HEADER)
                    with m.Case(Word.SETTINGS):
                        m.d.sync += settings.eq(word)
                        with m.If(word == 0):
                            enter_segments()
                        with m.Else():
                            m.d.sync += section.eq(_Section.SETTINGS)
            with m.Case(_Section.SETTINGS):
                with m.If(~setting_value_next):
                    m.d.sync += [setting_address.eq(word[:7]), setting_value_next.eq(1)]
                    with m.If(word[7:] != 0):
                        stop(PlayerResult.BAD_SETTING)
                with m.Else():
                    m.d.sync += [setting_value_next.eq(0), settings_done.eq(settings_done + 1)]
                    with m.If(owned):
                        stop(PlayerResult.BAD_SETTING)
                    with m.Elif(live):
                        write(setting_address, word)
                    with m.If(settings_done + 1 == settings):
                        enter_segments()
            with m.Case(_Section.SEGMENTS):
                with m.Switch(segment_word):
                    for index, name in enumerate(("vec_x", "vec_y", "vec_op")):
                        with m.Case(index):
                            with m.If(live):
                                write(name, word)
                            m.d.sync += segment_word.eq((index + 1) % SEGMENT_WORDS)
