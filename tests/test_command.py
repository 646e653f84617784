# amaranth: UnusedElaboratable=no
"""The command decoder alone (gateware/host/command.py), its register bus answered by a small
register file modelled here, against the host link's frame rules (gateware/host/frames.py):
a frame is ``seq, address, data, x, y`` (its CRC checked by the transport, which says whether
it was ``intact``), and every frame is answered ``tag, code, data`` on the link it came from:

* not intact: refused (``check``);
* a read (address bit 7) of a register with zero data, whatever its ``seq``: answered with
  the value, the tag its ``seq``; anything else read is refused (``register``);
* a write carrying the ``seq`` expected (0 after reset): done if the register file takes it,
  then the next ``seq`` (modulo 256) is expected and the answer gives what the register holds
  (for ``vec_op``, which queues the frame's data, x and y together: the queue's free places);
  refused (``register``) if the register file does not take it;
* a write with another ``seq``: refused (``sequence``).

A refused frame changes nothing, adds one to ``errors`` (which stops at 65535) and is answered
``seq, 0x80 | reason, the seq expected``. An answer over SPI waits until taken (a newer one
replaces it); over the UART it is offered once, and lost and counted if the queue is full.

Frames are built with the test-side codec (tests/link_codec.py): the payload a transport hands
the decoder is the first eight bytes of ``command(...)``."""

from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.command import CommandDecoder
from galvoscan.gateware.host.registers import RegisterFile
from galvoscan.gateware.host.regmap import register_map
from link_codec import REASON, command


STATUS = 0x00           # reading status clears its sticky flags
ERRORS = 0x01           # the decoder's errors (read-only)
LINK_SEQ = 0x18         # the decoder's seq (read-only)
VEC_OP = 0x22           # a write queues a segment: data, x and y together
FIFO_FREE = 0x23        # the queue's free places (read-only): what a vec_op write answers
QUEUE = 3               # free places in the stub's queue (nothing drains it)


class RegisterStub:
    """A few registers of each kind: (access, low, high, value). Answers the bus the way the
    RegisterBus docstring says: ``read_ok`` for a register, ``write_ok`` for a writable one with
    the value in range (and, for the queue, a free place), ``read_data`` its value two clocks
    after the access was given (garbage for no register). ``errors`` and ``link_seq`` read what
    :attr:`live` says (the decoder's outputs, or the model's counts)."""

    def __init__(self, free=QUEUE):
        self.regs = {
            STATUS: ["ro", 0, 0, 0x0105],
            ERRORS: ["ro", 0, 0, None],
            0x04: ["rw", 1, 65535, 3],
            0x09: ["rw", 0, 127, 0],
            0x12: ["rw", 200, 2000, 500],
            LINK_SEQ: ["ro", 0, 0, None],
            0x19: ["strobe", 0, 1, 0],      # keepalive: reads 0
            VEC_OP: ["queue", 0, 255, 0],
            FIFO_FREE: ["ro", 0, 0, None],
            0x36: ["rw", 0, 3, 0],
            0x44: ["rw", 0, 1, 0],
        }
        self.free = free
        self.live = {ERRORS: 0, LINK_SEQ: 0}

    def is_register(self, address):
        return address in self.regs

    def write_ok(self, address, data):
        reg = self.regs.get(address)
        return (reg is not None and reg[0] != "ro" and reg[1] <= data <= reg[2]
                and (reg[0] != "queue" or self.free > 0))

    def read(self, address):
        reg = self.regs.get(address)
        if reg is None:
            return 0xBEEF
        if address == FIFO_FREE:
            return self.free
        return self.live[address] if address in self.live else reg[3]

    def write(self, address, data):
        reg = self.regs[address]
        if reg[0] == "queue":
            self.free -= 1
        if reg[0] != "strobe":
            reg[3] = data


def fields(payload):
    """``(seq, address, data, x, y)`` of a payload, by the frame's bytes."""
    b = payload.to_bytes(8, "big")
    return b[0], b[1], (b[2] << 8) | b[3], (b[4] << 8) | b[5], (b[6] << 8) | b[7]


def payload(seq, address, data=0, x=0, y=0):
    """What a transport hands the decoder for a frame: its eight bytes before the CRC."""
    return int.from_bytes(command(seq, address, data, x, y)[:8], "big")


class Near(int):
    """A write's ``seq`` given from the one the board expects then (``Near(-1)``: the one
    before); ``None`` is ``Near(0)``."""

    def __repr__(self):
        return f"Near({int(self)})"


def write(link, seq, address, data, x=0, y=0, intact=True):
    """A write frame; ``seq`` None: the one the board expects then."""
    return (link, (seq, address, data, x, y), intact)


def read(link, address, seq=0, data=0, intact=True):
    return (link, (seq, 0x80 | address, data, 0, 0), intact)


def unpack(answer):
    """``(tag, code, data)`` of an answer, by its bytes (tag first)."""
    b = answer.to_bytes(4, "big")
    return b[0], b[1], (b[2] << 8) | b[3]


class Model:
    """The rules, one frame at a time."""

    def __init__(self, free=QUEUE):
        self.stub = RegisterStub(free)
        self.seq = 0
        self.errors = 0
        self.answers = {"spi": [], "uart": []}
        self.lost = []
        self.writes, self.segments, self.taken = [], [], []
        self.refused = self.accepted = self.status_reads = self.given = 0
        self.held = None            # an SPI answer not taken yet

    def group(self, frames, ready=(1, 1)):
        """Frames offered together, each link's answers taken while its ``ready`` is high:
        SPI goes first. Returns the frames with every ``seq`` None or :class:`Near` made the
        one it says."""
        if ready[0]:
            self.take_held()
        resolved = []
        for link, (seq, *rest), intact in sorted(frames, key=lambda f: f[0] != "spi"):
            if seq is None or isinstance(seq, Near):
                seq = (self.seq + (seq or 0)) % 256
            frame = (link, (seq, *rest), intact)
            self.frame(*frame, ready=ready)
            resolved.append(frame)
        return resolved

    def frame(self, link, frame, intact, *, ready=(1, 1)):
        seq, address, data, x, y = fields(payload(*frame))
        reg = address & 0x7F
        self.taken.append(link)
        if not intact:
            return self.refuse(link, seq, "check", ready)
        if address & 0x80:
            if not self.stub.is_register(reg) or data != 0:
                return self.refuse(link, seq, "register", ready)
            self.given += 1
            self.accepted += 1
            self.status_reads += reg == STATUS
            return self.answer(link, (seq, reg, self.read(reg)), ready)
        if seq != self.seq:
            return self.refuse(link, seq, "sequence", ready)
        self.given += 2             # given, then done (or refused) on the clock after
        if not self.stub.write_ok(reg, data):
            return self.refuse(link, seq, "register", ready)
        self.stub.write(reg, data)
        self.writes.append((reg, data))
        self.seq = (self.seq + 1) % 256
        self.accepted += 1
        if reg == VEC_OP:
            self.segments.append((data, x, y))
        self.answer(link, (seq, reg, self.read(FIFO_FREE if reg == VEC_OP else reg)), ready)

    def read(self, address):
        self.stub.live = {ERRORS: self.errors, LINK_SEQ: self.seq}
        return self.stub.read(address)

    def count(self):
        self.errors = min(self.errors + 1, 65535)

    def refuse(self, link, seq, reason, ready):
        self.count()
        self.refused += 1
        self.answer(link, (seq, 0x80 | REASON[reason], self.seq), ready)

    def answer(self, link, answer, ready):
        if link == "spi":
            self.held = answer
            if ready[0]:
                self.take_held()
        elif ready[1]:
            self.answers["uart"].append(answer)
        else:
            self.lost.append(answer)
            self.count()

    def take_held(self):
        if self.held is not None:
            self.answers["spi"].append(self.held)
            self.held = None


def run_decoder(offers, *, ready=lambda group: (1, 1), gap=6, free=QUEUE):
    """Offer frames to the decoder. ``offers`` is a list of lists: the frames of one entry,
    ``(link, (seq, address, data, x, y), intact)``, are offered together (at most one per
    link), each held until taken; ``gap`` clocks pass after the last is taken before the next
    entry's are offered (6: its answers are out). ``ready(entry)`` gives the answer streams'
    ready (spi, uart) while an entry's frames are offered and answered. Returns what happened:
    answers taken off each link and lost (UART), writes done on the bus (applied to the stub),
    segments queued (data, x, y), errors and seq, the accepted/status_read/refused pulses, the
    clocks ``given`` was high, and the order the frames were taken in."""
    dut = CommandDecoder()
    stub = RegisterStub(free)
    seen = {"answers": {"spi": [], "uart": []}, "lost": [], "writes": [], "segments": [],
            "accepted": 0, "status_reads": 0, "refused": 0, "given": 0, "taken": []}
    streams = {"spi": (dut.spi_frames, dut.spi_replies),
               "uart": (dut.uart_frames, dut.uart_replies)}

    async def bench(ctx):
        before = [None]             # the access (address, data) given on the clock before
        last_read = [0xBEEF]        # the value read on the clock before
        readies = [(1, 1)]

        async def step(offered):
            for (_, replies), r in zip(streams.values(), readies[0]):
                ctx.set(replies.ready, r)
            stub.live = {ERRORS: ctx.get(dut.errors), LINK_SEQ: ctx.get(dut.seq)}
            access = ctx.get(dut.bus.address), ctx.get(dut.bus.write_data)
            ctx.set(dut.bus.read_ok, stub.is_register(access[0]))
            # The access given on the clock before is checked, done and read now (RegisterBus);
            # its value read comes on the next clock.
            write_ok = before[0] is not None and stub.write_ok(*before[0])
            ctx.set(dut.bus.write_ok, write_ok)
            ctx.set(dut.bus.read_data, last_read[0])
            value = stub.read(before[0][0]) if before[0] else 0xBEEF
            # What crosses the edge.
            for link, (_, replies) in streams.items():
                if ctx.get(replies.valid):
                    answer = unpack(ctx.get(replies.payload.as_value()))
                    if ctx.get(replies.ready):
                        seen["answers"][link].append(answer)
                    elif link == "uart":
                        seen["lost"].append(answer)
            write_en = ctx.get(dut.bus.write_en)
            done = write_en and write_ok
            assert not write_en or ctx.get(dut.given)
            if done:
                seen["writes"].append(before[0])
            segment = ctx.get(dut.segment)
            # The segment goes with a vec_op write being done, and only then.
            assert not segment or (write_en and before[0][0] == VEC_OP)
            assert segment or not (done and before[0][0] == VEC_OP)
            if segment and done:
                seen["segments"].append(
                    (before[0][1], ctx.get(dut.segment_x), ctx.get(dut.segment_y)))
            seen["given"] += ctx.get(dut.given)
            seen["accepted"] += ctx.get(dut.accepted)
            seen["status_reads"] += ctx.get(dut.status_read)
            seen["refused"] += ctx.get(dut.refused)
            taken = [link for link in offered
                     if ctx.get(streams[link][0].valid) and ctx.get(streams[link][0].ready)]
            await ctx.tick()
            if done:
                stub.write(*before[0])
            before[0] = access
            last_read[0] = value
            return taken

        for index, group in enumerate(offers):
            readies[0] = ready(index)
            waiting = {}
            for link, frame, intact in group:
                frames = streams[link][0]
                ctx.set(frames.payload, {"payload": payload(*frame), "intact": intact})
                ctx.set(frames.valid, 1)
                waiting[link] = True
            while waiting:
                for link in await step(list(waiting)):
                    seen["taken"].append(link)
                    ctx.set(streams[link][0].valid, 0)
                    del waiting[link]
            for _ in range(gap):
                await step([])
        readies[0] = (1, 1)
        for _ in range(8):
            await step([])
        seen["errors"] = ctx.get(dut.errors)
        seen["seq"] = ctx.get(dut.seq)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    seen["stub"] = stub.regs
    return seen


def check_against_model(offers, *, ready=lambda group: (1, 1), free=QUEUE, **kw):
    """Run the model, then the decoder, on the same frames (every ``seq`` None made the one
    the model expects then, and every :class:`Near` from it), and compare all they did."""
    model = Model(free)
    offers = [model.group(group, ready(index)) for index, group in enumerate(offers)]
    model.take_held()
    seen = run_decoder(offers, ready=ready, free=free, **kw)
    assert seen["taken"] == model.taken
    assert seen["answers"] == model.answers
    assert seen["lost"] == model.lost
    assert seen["writes"] == model.writes
    assert seen["segments"] == model.segments
    assert seen["errors"] == model.errors
    assert seen["seq"] == model.seq
    assert seen["refused"] == model.refused
    assert seen["accepted"] == model.accepted
    assert seen["status_reads"] == model.status_reads
    assert seen["given"] == model.given
    assert seen["stub"] == model.stub.regs
    return seen, model


def one_by_one(frames):
    return [[f] for f in frames]


def refusal(tag, reason, expected):
    return (tag, 0x80 | REASON[reason], expected)


# --- single rules ------------------------------------------------------------------------------

@pytest.mark.parametrize("link", ["spi", "uart"])
def test_write_then_read_back(link):
    seen, _ = check_against_model(one_by_one([
        write(link, 0, 0x04, 0x1234),
        read(link, 0x04, seq=0x5A),
        read(link, STATUS, seq=0xFF),
        write(link, 1, 0x12, 2000),
        read(link, 0x12),
        read(link, LINK_SEQ, seq=7),
    ]))
    assert seen["answers"][link] == [(0, 0x04, 0x1234), (0x5A, 0x04, 0x1234),
                                     (0xFF, STATUS, 0x0105), (1, 0x12, 2000), (0, 0x12, 2000),
                                     (7, LINK_SEQ, 2)]
    assert seen["errors"] == 0 and seen["status_reads"] == 1 and seen["seq"] == 2


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_a_write_is_answered_with_what_the_register_holds(link):
    """A strobe reads 0 after the write; errors read back count what was refused."""
    seen, _ = check_against_model(one_by_one([
        write(link, 0, 0x19, 1),                    # keepalive
        write(link, 9, 0x09, 5),                    # out of sequence
        read(link, ERRORS, seq=3),
        write(link, 1, 0x09, 127),
    ]))
    assert seen["answers"][link] == [(0, 0x19, 0), refusal(9, "sequence", 1), (3, ERRORS, 1),
                                     (1, 0x09, 127)]


@pytest.mark.parametrize("frame, reason", [
    (write("L", 0, 0x04, 5, intact=False), "check"),     # damaged, cut short, run over
    (read("L", 0x04, intact=False), "check"),
    (write("L", 0x01, 0x04, 5, intact=False), "check"),
    (write("L", 0, VEC_OP, 1, 2, 3, intact=False), "check"),
    (write("L", 1, 0x04, 5), "sequence"),
    (write("L", 0xFF, 0x04, 5), "sequence"),
    (write("L", 0, 0x7E, 5), "register"),               # unknown address
    (read("L", 0x7E), "register"),                      # read of an unknown address
    (write("L", 0, STATUS, 1), "register"),             # write to a read-only register
    (write("L", 0, ERRORS, 0), "register"),
    (write("L", 0, LINK_SEQ, 0), "register"),
    (write("L", 0, FIFO_FREE, 0), "register"),
    (read("L", 0x04, data=1), "register"),              # read with non-zero data
    (read("L", 0x04, data=0x8000), "register"),
    (write("L", 0, 0x04, 0), "register"),               # out of range (1…65535)
    (write("L", 0, 0x09, 128), "register"),             # out of range (0…127)
    (write("L", 0, 0x12, 199), "register"),             # below range (200…2000)
    (write("L", 0, 0x12, 2001), "register"),
    (write("L", 0, 0x19, 2), "register"),               # a strobe takes 0 or 1
    (write("L", 0, VEC_OP, 256, 1, 2), "register"),     # a segment out of range
])
@pytest.mark.parametrize("link", ["spi", "uart"])
def test_refused_frames_change_nothing_and_count(link, frame, reason):
    _, body, intact = frame
    seq = body[0]
    seen, _ = check_against_model(one_by_one([
        (link, body, intact),
        read(link, 0x04), read(link, LINK_SEQ),
        write(link, 0, 0x04, 6)]))
    assert seen["errors"] == 1 and seen["refused"] == 1
    assert seen["answers"][link] == [refusal(seq, reason, 0), (0, 0x04, 3), (0, LINK_SEQ, 0),
                                     (0, 0x04, 6)]
    assert seen["writes"] == [(0x04, 6)] and seen["segments"] == []


def test_a_write_out_of_sequence_refuses_every_later_one_until_the_right_seq():
    """A write lost on the line: every later write is refused (reads are taken) until the
    host sends the one expected again."""
    seen, _ = check_against_model(one_by_one([
        write("spi", 0, 0x09, 1),
        write("spi", 2, 0x09, 2),               # the write with seq 1 was lost
        write("spi", 3, 0x09, 3),
        write("uart", 2, 0x09, 4),
        read("spi", 0x09, seq=2),
        write("uart", 1, 0x09, 5),              # the host sends it again
        write("spi", 2, 0x09, 6),
        write("spi", 2, 0x09, 7),               # a repeat: refused
    ]))
    assert seen["answers"] == {
        "spi": [(0, 0x09, 1), refusal(2, "sequence", 1), refusal(3, "sequence", 1),
                (2, 0x09, 1), (2, 0x09, 6), refusal(2, "sequence", 3)],
        "uart": [refusal(2, "sequence", 1), (1, 0x09, 5)]}
    assert seen["writes"] == [(0x09, 1), (0x09, 5), (0x09, 6)]
    assert seen["errors"] == 4 and seen["seq"] == 3


def test_a_write_the_register_file_refuses_does_not_advance_seq():
    seen, _ = check_against_model(one_by_one([
        write("spi", 0, 0x09, 200), write("uart", 0, 0x09, 100), write("spi", 1, 0x09, 99)]))
    assert seen["answers"] == {"spi": [refusal(0, "register", 0), (1, 0x09, 99)],
                               "uart": [(0, 0x09, 100)]}


def test_the_sequence_wraps_at_256():
    frames = [write("spi" if n % 3 else "uart", n % 256, 0x09, n % 128) for n in range(258)]
    frames.insert(256, write("spi", 1, 0x09, 1))        # after 255 comes 0, not 256 nor 1
    seen, _ = check_against_model(one_by_one(frames), gap=0)
    assert seen["seq"] == 2 and seen["errors"] == 1
    assert seen["answers"]["uart"][-1] == (255, 0x09, 255 % 128)
    assert seen["answers"]["spi"][-3:] == [refusal(1, "sequence", 0), (0, 0x09, 0),
                                           (1, 0x09, 1)]


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_reads_take_any_seq_and_do_not_advance_it(link):
    seen, _ = check_against_model(one_by_one(
        [read(link, 0x04, seq=seq) for seq in (0, 1, 0x80, 0xFF, 0x17)] +
        [write(link, 0, 0x04, 9), read(link, LINK_SEQ, seq=0)]))
    assert seen["answers"][link] == [(seq, 0x04, 3) for seq in (0, 1, 0x80, 0xFF, 0x17)] + [
        (0, 0x04, 9), (0, LINK_SEQ, 1)]
    assert seen["seq"] == 1 and seen["errors"] == 0


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_a_segment_write_queues_its_x_and_y_and_answers_the_free_places(link):
    seen, _ = check_against_model(one_by_one([
        write(link, 0, VEC_OP, 0x17, 0x1234, 0xABCD),
        write(link, 1, 0x09, 5, 0x1111, 0x2222),        # x, y of another write: no segment
        write(link, 2, VEC_OP, 0xFF, 0xFFFF, 0),
        write(link, 3, VEC_OP, 0, 0, 0xFFFF),
        write(link, 4, VEC_OP, 1, 5, 6),                # the queue full: refused
        read(link, VEC_OP),
        read(link, FIFO_FREE, seq=9),
    ]), free=3)
    assert seen["segments"] == [(0x17, 0x1234, 0xABCD), (0xFF, 0xFFFF, 0), (0, 0, 0xFFFF)]
    assert seen["answers"][link] == [(0, VEC_OP, 2), (1, 0x09, 5), (2, VEC_OP, 1),
                                     (3, VEC_OP, 0), refusal(4, "register", 4), (0, VEC_OP, 0),
                                     (9, FIFO_FREE, 0)]


@pytest.mark.parametrize("first", ["spi", "uart"])
def test_both_links_at_once(first):
    """Frames on both links in the same clock: both are taken, SPI first (so a read on the
    UART sees the SPI write of the same clock), the UART's held until then."""
    other = "uart" if first == "spi" else "spi"
    seen, _ = check_against_model([
        [write(first, 0, 0x04, 1000), read(other, 0x04)],
        [read("spi", 0x09), read("uart", 0x09, seq=3)],
        [write("spi", 1, 0x09, 1), write("uart", 2, 0x09, 2)],
        [read("uart", 0x09)],
        [write("uart", 3, 0x09, 3), write("spi", 4, 0x09, 4)],
        [read("uart", 0x09)],
    ], gap=0)
    assert seen["taken"][:2] == ["spi", "uart"]
    assert seen["answers"]["uart"][-3] == (0, 0x09, 2)     # SPI's write first, then UART's
    # SPI's write is decided first: it carries the seq after the UART's, so is refused.
    assert seen["answers"]["spi"][-1] == refusal(4, "sequence", 3)
    assert seen["stub"][0x09][3] == 3
    assert seen["errors"] == 1


@pytest.mark.parametrize("gap", [0, 1, 2, 3])
def test_frames_back_to_back(gap):
    """The next frame offered as soon as (or soon after) one is taken: each waits its turn."""
    check_against_model(one_by_one([
        write("spi", 0, 0x04, 1), read("spi", 0x04), write("uart", 1, VEC_OP, 2, 3, 4),
        write("uart", 2, 0x09, 1), read("uart", 0x09), write("spi", 0, 0x09, 1, intact=False),
        read("spi", 0x04, data=1), write("spi", 3, 0x09, 9)]), gap=gap)


def test_an_spi_answer_waits_until_taken_and_a_newer_replaces_it():
    readies = [(0, 1), (0, 1), (0, 1), (1, 1), (0, 1)]
    seen, _ = check_against_model(one_by_one([
        write("spi", 0, 0x04, 7), read("spi", 0x04, seq=1), read("uart", 0x04, seq=2),
        read("spi", STATUS, seq=3), read("spi", 0x09, seq=4)]), ready=lambda g: readies[g])
    assert seen["answers"] == {"spi": [(1, 0x04, 7), (3, STATUS, 0x0105), (4, 0x09, 0)],
                               "uart": [(2, 0x04, 7)]}
    assert seen["errors"] == 0


def test_a_uart_answer_that_finds_the_queue_full_is_lost_and_counted():
    """The write and the read are done all the same; the SPI link is unaffected."""
    readies = [(1, 0), (1, 0), (1, 0), (1, 1), (1, 0), (1, 1)]
    seen, _ = check_against_model(one_by_one([
        write("uart", 0, 0x04, 7), read("uart", 0x04), read("spi", 0x04),
        read("uart", ERRORS), write("uart", 5, 0x04, 8), read("uart", ERRORS, seq=1)]),
        ready=lambda g: readies[g])
    assert seen["lost"] == [(0, 0x04, 7), (0, 0x04, 7), refusal(5, "sequence", 1)]
    assert seen["answers"] == {"spi": [(0, 0x04, 7)],
                               "uart": [(0, ERRORS, 2), (1, ERRORS, 4)]}
    assert seen["refused"] == 1 and seen["writes"] == [(0x04, 7)]


def test_errors_stop_at_65535():
    """A damaged frame always waiting (UART, held: one taken every three clocks), its answer
    lost (the UART queue full): each counts twice, on the clock it is decided and on the one
    its answer is lost. After a few the count is set near the top (as if 65 000 more had come:
    counting them would take the simulator some 10 s); it climbs to 65535 and stays."""
    dut = CommandDecoder()
    counts = []

    async def bench(ctx):
        ctx.set(dut.uart_frames.payload, {"payload": payload(0, 0x04, 5), "intact": 0})
        ctx.set(dut.uart_frames.valid, 1)
        ctx.set(dut.uart_replies.ready, 0)
        for _ in range(4):
            await ctx.tick().repeat(3)
            counts.append(ctx.get(dut.errors))
        ctx.set(dut.errors, 65530)
        for _ in range(5):
            await ctx.tick().repeat(3)
            counts.append(ctx.get(dut.errors))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert counts == [2, 4, 6, 8, 65532, 65534, 65535, 65535, 65535]


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_with_the_real_register_file(link):
    """The decoder on the default build's register file: the stub above answers as it does."""
    dut = CommandDecoder()
    regs = RegisterFile(register_map())
    m = Module()
    m.submodules.decoder, m.submodules.regs = dut, regs
    wiring.connect(m, dut.bus, regs.bus)
    m.d.comb += [regs.link_seq.eq(dut.seq), regs.errors.eq(dut.errors)]
    frames, replies = ((dut.spi_frames, dut.spi_replies) if link == "spi" else
                       (dut.uart_frames, dut.uart_replies))
    answers, segments = [], []

    async def bench(ctx):
        ctx.set(regs.vec_op_ready, 1)
        ctx.set(regs.fifo_free, 41)
        ctx.set(replies.ready, 1)
        for frame, intact in [((0, 0x04, 0x1234), 1), ((0x42, 0x84, 0), 1),
                              ((1, VEC_OP, 1, 0x0102, 0x0304), 1), ((2, 0x02, 3), 1),
                              ((2, 0x13, 60000), 1), ((3, 0x13, 0), 0),
                              ((9, 0x80 | LINK_SEQ, 0), 1), ((9, 0x80 | ERRORS, 0), 1),
                              ((9, 0x93, 0), 1)]:
            ctx.set(frames.payload, {"payload": payload(*frame), "intact": intact})
            ctx.set(frames.valid, 1)
            assert ctx.get(frames.ready)
            await ctx.tick()
            ctx.set(frames.valid, 0)
            for _ in range(8):
                if ctx.get(replies.valid):
                    answers.append(unpack(ctx.get(replies.payload.as_value())))
                if ctx.get(dut.segment) and ctx.get(regs.vec_op_push):
                    segments.append((ctx.get(regs.vec_op), ctx.get(dut.segment_x),
                                     ctx.get(dut.segment_y)))
                await ctx.tick()

    sim = Simulator(m)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert answers == [(0, 0x04, 0x1234), (0x42, 0x04, 0x1234), (1, VEC_OP, 41),
                       refusal(2, "register", 2), (2, 0x13, 60000), refusal(3, "check", 3),
                       (9, LINK_SEQ, 3), (9, ERRORS, 2), (9, 0x13, 60000)]
    assert segments == [(1, 0x0102, 0x0304)]


# --- random frames -----------------------------------------------------------------------------

addresses = st.sampled_from([STATUS, ERRORS, 0x04, 0x09, 0x12, LINK_SEQ, 0x19, VEC_OP, FIFO_FREE,
                             0x36, 0x44, 0x05, 0x7E, 0x7F])
values = st.one_of(st.integers(0, 3), st.sampled_from([127, 128, 199, 200, 255, 256, 2000, 2001]),
                   st.integers(0, 0xFFFF))
seqs = st.one_of(st.none(), st.none(), st.integers(-2, 2).map(Near), st.integers(0, 255))
intact = st.sampled_from([True, True, True, True, False])
links = st.sampled_from(["spi", "uart"])
frame = st.one_of(
    st.builds(write, links, seqs, addresses, values, st.integers(0, 0xFFFF),
              st.integers(0, 0xFFFF), intact),
    st.builds(read, links, addresses, st.integers(0, 255),
              st.one_of(st.just(0), st.just(0), values), intact),
)
offers = st.lists(st.lists(frame, min_size=1, max_size=2).map(
    lambda g: list({f[0]: f for f in g}.values())), min_size=1, max_size=12)


@settings(max_examples=40, deadline=None)
@given(offers, st.lists(st.tuples(st.sampled_from([1, 1, 0]), st.sampled_from([1, 1, 1, 0])),
                        min_size=12, max_size=12), st.integers(1, 4))
def test_random_frames_on_both_links_against_the_model(offers, readies, free):
    check_against_model(offers, ready=lambda g: readies[g], free=free)


@settings(max_examples=25, deadline=None)
@given(offers, st.integers(0, 6))
def test_random_frames_back_to_back_against_the_model(offers, gap):
    check_against_model(offers, gap=gap)
