"""The job player: runs a job image from the flash as a host would, on each start.

Three stages::

    flash reader ─▶ image reader ─▶ state machine ─▶ register writer ─▶ bus arbiter
     (bytes)        (words, CRC)    (check, play)    (one write a time)

:class:`~.image_reader.ImageReader` puts the flash's bytes into words and a CRC-32;
:class:`JobPlayer`, the state machine, checks the words and plays them; it asks
:class:`~.register_writer.RegisterWriter` for each register write.
"""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import enum, stream, wiring
from amaranth.lib.wiring import In, Out

from ..fields import Mode, PlayerResult, PlayerState
from ..host.registers import RegisterBus
from ..host.regmap import BY_NAME
from .image_reader import ImageReader
from .register_writer import TARGETS, RegisterWriter
from .image_format import (FORMAT_VERSION, HEADER_BYTES, HEADER_WORDS, JOB_OFFSET,
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
    (:class:`~galvoscan.outputs.stream.JobStreamer`): vector mode is selected, stopped, and the
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
    crc_bits_per_clock : int
        The CRC core's (:class:`~.crc32.CRC32`): 1 on the board; the proof's 8 make its
        covers short.

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

    def __init__(self, *, max_image_bytes=MAX_IMAGE_BYTES, offset=JOB_OFFSET,
                 crc_bits_per_clock=1):
        if not isinstance(max_image_bytes, int) or max_image_bytes % 2 or \
                not HEADER_BYTES <= max_image_bytes <= MAX_IMAGE_BYTES:
            raise ValueError(f"max_image_bytes must be an even number from {HEADER_BYTES} to "
                             f"{MAX_IMAGE_BYTES}, not {max_image_bytes!r}")
        if not isinstance(offset, int) or offset < 0 or offset + max_image_bytes > 1 << 24:
            raise ValueError(f"an image of {max_image_bytes} bytes at {offset!r} does not fit "
                             f"24-bit flash addresses")
        self.max_image_bytes = max_image_bytes
        self.offset = offset
        self._reader = ImageReader(crc_bits_per_clock=crc_bits_per_clock)
        self._writer = RegisterWriter()
        # The reader's, by the names the proof's helper invariants use (formal/player.py).
        self._crc = self._reader.crc_core
        self._byte_high = self._reader.byte_high
        self._word_valid = self._reader.words.valid
        self._word = self._reader.words.payload
        words_max = max_image_bytes // 2
        # Made here, so that the proof's helper invariants can name them (formal/player.py).
        self._live = Signal(name="live")                # the second reading, which writes
        self._position = Signal(range(words_max + 1), name="position")
        self._length = Signal(range(words_max + 1), name="length")
        self._expected_crc = Signal(32, name="expected_crc")
        self._parsing = Signal(name="parsing")          # reading the image through
        self._writing = Signal(name="writing")          # a write given, not yet done
        self._playing = Signal(name="playing")          # in a state of the playing only
        self._section = Signal(_Section, name="section")
        self._ended = Signal(name="ended")
        self._took = Signal(name="took")
        self._reading = Signal(name="reading")          # starting a read
        self._repeating = Signal(name="repeating")      # reading the segments again
        self._repeats_left = Signal(16, name="repeats_left")
        self._settings_left = Signal(8, name="settings_left")    # (address, value) pairs to come
        self._setting_address = Signal(7, name="setting_address")
        self._setting_value_next = Signal(name="setting_value_next")  # the next is a value
        self._segment_word = Signal(range(SEGMENT_WORDS), name="segment_word")
        self._segments_from = Signal(range(words_max + 1), name="segments_from")  # 1st segment
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
        m.submodules.reader = reader = self._reader

        # --- the image, a word at a time ---------------------------------------------------------
        live = self._live
        section = self._section
        position = self._position       # words taken since the image's start
        length = self._length           # the image's length, in words
        word = self._word               # the word being taken, while word_valid
        word_valid = self._word_valid
        expected_crc = self._expected_crc
        repeats_left = self._repeats_left
        setting_address = self._setting_address
        setting_value_next = self._setting_value_next
        segment_word = self._segment_word
        segments_from = self._segments_from
        repeating = self._repeating     # reading the segments again
        result = self.result            # how this start ends (NONE while it runs)

        # --- its writes to the register file, one at a time -------------------------------------
        m.submodules.writer = writer = self._writer
        write_free, write_refused = writer.free, writer.refused
        m.d.comb += [
            self._writing.eq(~write_free),
            writer.word.eq(word), writer.setting_address.eq(setting_address),
            writer.grant.eq(self.grant),
        ]
        wiring.connect(m, writer.bus, wiring.flipped(self.bus))
        waiting_on_machine = Signal()   # waiting for the machine, which is at work
        m.d.comb += self.alive.eq(writer.wrote | waiting_on_machine)

        def write(target, value=0):
            m.d.comb += [writer.request.valid.eq(1),
                         writer.request.payload.target.eq(TARGETS.index(target)),
                         writer.request.payload.constant.eq(value)]

        # Bytes from the flash into words (low byte first), and into the CRC, which reads its
        # own four bytes as zero. A word's bytes come while ``position`` is its index.
        in_crc_field = (section == _Section.HEADER) & \
            ((position[:4] == Word.CRC_LOW) | (position[:4] == Word.CRC_HIGH))
        wiring.connect(m, wiring.flipped(self.read_data), reader.data)
        m.d.comb += [
            reader.zero_byte.eq(in_crc_field),
            # The image from its start, or (a repeat) from its first segment.
            self.read_address.eq(self.offset + Mux(repeating, segments_from << 1, 0)),
        ]

        def begin(*, repeat=False):
            """Read the image (or, a repeat, its segments), after a clock with the reader
            stopped."""
            m.d.comb += [self.read_stop.eq(1), reader.clear.eq(1)]
            m.d.sync += [segment_word.eq(0), repeating.eq(repeat)]
            if repeat:
                m.d.sync += position.eq(segments_from)
            else:
                m.d.sync += [section.eq(_Section.HEADER), position.eq(0),
                             setting_value_next.eq(0)]
                m.d.comb += reader.crc_clear.eq(1)
            m.next = "READ"

        def stop(code):
            """End this start with ``code``: refused if nothing was written yet, else through
            the laser-first stop."""
            m.d.sync += result.eq(code)
            with m.If(live):
                m.next = "STOP"
            with m.Else():
                m.next = "REFUSE"

        # A host's write of arm, run or mode, or a fault while armed, ends a start, whatever
        # state it is in: latched here, acted on by the states that wait (the others pass
        # within a few clocks).
        abort = Signal()
        with m.If(self.host_took_over | (self.armed & self.fault)):
            m.d.sync += abort.eq(1)
        with m.If(~abort):
            with m.If(self.host_took_over):
                m.d.sync += result.eq(PlayerResult.HOST)
            with m.Elif(self.armed & self.fault):
                m.d.sync += result.eq(PlayerResult.FAULT)

        owned = Cat(setting_address == BY_NAME[name].address
                    for name in PLAYER_OWNED if name in BY_NAME).any()
        # The image's end, a clock after the word that reached it was taken (a register:
        # the compare is off the paths into the word's handling); no byte is taken on that
        # clock, so none past the end reaches the CRC.
        ended = self._ended
        took = self._took
        m.d.sync += [ended.eq((section != _Section.HEADER) & (position == length)),
                     took.eq(0)]

        with m.FSM() as fsm:
            with m.State("IDLE"):
                m.d.sync += [live.eq(0), self.armed.eq(0), abort.eq(0)]
                with m.If(self.start):
                    m.d.sync += result.eq(PlayerResult.NONE)
                    begin()

            with m.State("READ"):
                m.d.comb += [self.read_start.eq(1), self._reading.eq(1)]
                with m.If(self.read_idle):
                    m.next = "PARSE"

            with m.State("PARSE"):
                # A word is taken once the last write is done (and, for vec_op, once the queue
                # has room); the next word's bytes come once it is taken.
                queue_wait = live & (section == _Section.SEGMENTS) & (segment_word == 2) & \
                    ~self.queue_ready
                # (In the check, a byte waits for the CRC to take the last one.)
                m.d.comb += [reader.enable.eq(write_free & ~took & ~ended),
                             reader.wait_crc.eq(~live),
                             self._parsing.eq(~live),
                             waiting_on_machine.eq(queue_wait & self.armed)]
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & word_valid & ~queue_wait & ~ended):
                    m.d.comb += reader.words.ready.eq(1)
                    m.d.sync += [position.eq(position + 1), took.eq(1)]
                    self._take_word(m, owned=owned, write=write, stop=stop)
                with m.Elif(write_free & ended):
                    # The last word is in: it must end the settings, or a segment.
                    m.d.comb += self.read_stop.eq(1)
                    with m.If((section != _Section.SEGMENTS) | (segment_word != 0)):
                        stop(PlayerResult.BAD_HEADER)
                    with m.Elif(live):
                        m.next = "DRAIN"
                    with m.Else():
                        m.next = "VERDICT"
                # As a host does: the queue filled (or the job all in) before the laser is armed
                # and the mode run.
                with m.If(live & (section == _Section.SEGMENTS) & ~self.armed & write_free &
                          ~write_refused & (queue_wait | ended)):
                    m.next = "ARM"
                self._guard(m, live, abort)

            with m.State("VERDICT"):
                m.d.comb += self._parsing.eq(1)
                with m.If(~reader.crc_busy):
                    with m.If(reader.crc == expected_crc):
                        # Checked: vector mode, stopped, then the image read again and played.
                        m.d.sync += live.eq(1)
                        write("run", 0)
                        m.next = "SELECT"
                    with m.Else():
                        stop(PlayerResult.BAD_CRC)

            with m.State("SELECT"):
                with m.If(write_free):
                    write("mode", Mode.VECTOR.value)
                    begin()

            with m.State("ARM"):
                write("arm", 1)
                m.d.sync += self.armed.eq(1)
                m.next = "LEAD"

            with m.State("LEAD"):
                m.d.comb += waiting_on_machine.eq(1)
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & self.laser_ready):
                    write("run", 1)
                    m.next = "PARSE"
                self._guard(m, live, abort)

            with m.State("DRAIN"):
                m.d.comb += waiting_on_machine.eq(self.vector_busy | ~self.queue_empty)
                with m.If(write_free & write_refused):
                    stop(PlayerResult.REFUSED)
                with m.Elif(write_free & self.queue_empty & ~self.vector_busy):
                    with m.If(repeats_left[1:] != 0):       # (more than one left)
                        m.d.sync += repeats_left.eq(repeats_left - 1)
                        begin(repeat=True)
                    with m.Else():
                        m.d.sync += result.eq(PlayerResult.DONE)
                        m.next = "STOP"
                self._guard(m, live, abort)

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
                    m.next = "IDLE"

            with m.State("REFUSE"):
                # Refused in the check, before any write: counted.
                m.d.comb += self.read_stop.eq(1)
                with m.If(self.refused != 255):
                    m.d.sync += self.refused.eq(self.refused + 1)
                m.next = "IDLE"

        m.d.comb += self._playing.eq(Cat(fsm.ongoing(state) for state in (
            "SELECT", "ARM", "LEAD", "DRAIN", "STOP", "FLUSH", "HALT")).any())
        m.d.comb += self.state.eq(Mux(fsm.ongoing("IDLE"), PlayerState.IDLE,
                                      Mux(live, PlayerState.RUNNING, PlayerState.CHECKING)))
        return m

    def _guard(self, m, live, abort):
        """In a state that waits: whatever the state does, an abort ends the start, through
        the laser-first stop (in the check, where nothing has been written, at once)."""
        with m.If(abort):
            with m.If(live):
                m.next = "STOP"
            with m.Else():
                m.next = "END"

    def _take_word(self, m, *, owned, write, stop):
        """What one word of the image does, in the check and in the playing: ``owned``, the
        setting being read addresses a register the player drives; ``write`` and ``stop``, the
        state machine's."""
        live, section, position, length = self._live, self._section, self._position, \
            self._length
        word, expected_crc, repeats_left = self._word, self._expected_crc, self._repeats_left
        settings_left, setting_address = self._settings_left, self._setting_address
        setting_value_next, segment_word = self._setting_value_next, self._segment_word
        segments_from = self._segments_from
        words_max = self.max_image_bytes // 2
        def enter_segments():
            m.d.sync += [section.eq(_Section.SEGMENTS), segments_from.eq(position + 1)]

        with m.Switch(section):
            with m.Case(_Section.HEADER):
                with m.Switch(position[:4]):
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
                        # In words: the low word's bits 15:1, as far as `length` holds them
                        # (a small build's: the rest must be clear).
                        low = min(15, len(length))
                        m.d.sync += length[:low].eq(word[1:1 + low])
                        with m.If(word[0] | (word[1 + low:] != 0 if low < 15 else 0)):
                            stop(PlayerResult.BAD_HEADER)
                    with m.Case(Word.LENGTH_HIGH):
                        # The high word's bits above the counters' must be clear, and only the
                        # low bits are compared.
                        high = max(0, len(length) - 15)
                        words = Cat(length[:15], word[:high]) if high else length
                        if high:
                            m.d.sync += length[15:].eq(word)
                        with m.If((word[high:] != 0) | (words > words_max) |
                                  (words < HEADER_WORDS)):
                            stop(PlayerResult.BAD_HEADER)
                    with m.Case(Word.CRC_LOW):
                        m.d.sync += expected_crc[:16].eq(word)
                    with m.Case(Word.CRC_HIGH):
                        m.d.sync += expected_crc[16:].eq(word)
                    with m.Case(Word.REPEATS):
                        m.d.sync += repeats_left.eq(word)
                        with m.If(word == 0):
                            stop(PlayerResult.BAD_HEADER)
                    with m.Case(Word.SETTINGS):
                        m.d.sync += settings_left.eq(word)
                        with m.If(word[8:] != 0):
                            stop(PlayerResult.BAD_HEADER)
                        with m.Elif(word == 0):
                            enter_segments()
                        with m.Else():
                            m.d.sync += section.eq(_Section.SETTINGS)
            with m.Case(_Section.SETTINGS):
                with m.If(~setting_value_next):
                    m.d.sync += [setting_address.eq(word[:7]), setting_value_next.eq(1)]
                    with m.If(word[7:] != 0):
                        stop(PlayerResult.BAD_SETTING)
                with m.Else():
                    m.d.sync += [setting_value_next.eq(0), settings_left.eq(settings_left - 1)]
                    with m.If(owned):
                        stop(PlayerResult.BAD_SETTING)
                    with m.Elif(live):
                        write(None)
                    with m.If(settings_left == 1):
                        enter_segments()
            with m.Case(_Section.SEGMENTS):
                with m.Switch(segment_word):
                    for index, name in enumerate(("vec_x", "vec_y", "vec_op")):
                        with m.Case(index):
                            with m.If(live):
                                write(name)
                            m.d.sync += segment_word.eq((index + 1) % SEGMENT_WORDS)
