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
``seq, 0x80 | reason, the seq expected``.

And the decoder's timing, clock by clock, counted from the clock a frame is taken (T):

* a frame is taken only while the decoder is free: idle, not on the clock it offers an
  answer, and not while the UART port sends one (``uart_replies.ready`` low); SPI first;
* T+1: the access (address, data) is given on the bus, for every frame; the verdict is made;
* T+2: a refusal made then (not intact, a read refused, a write out of sequence) pulses
  ``refused``, its answer offered at T+3; a read is read (``status_read`` for status), its
  answer offered at T+4 (``accepted`` at T+3); a write in sequence is done (``write_en``, and
  ``segment`` with the frame's x and y for ``vec_op``) while its register is given again to
  be read back: taken by the register file, its answer is offered at T+5 (``accepted`` at
  T+4), refused, ``refused`` pulses at T+3 and its answer is offered at T+4;
* an answer is offered (``valid``) for exactly one clock, on the link its frame came from,
  and held until the next frame is taken. The UART port takes every one (no frame was taken
  while it was busy); an SPI answer the target does not take on that clock is lost and
  counted in ``errors`` (a refused frame whose answer is lost counts twice).

Frames are built with the test-side codec (tests/support/link_codec.py): the payload a transport hands
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


def spi_ready(spec, offset):
    """Whether the SPI target can take an answer ``offset`` clocks after the frame in hand was
    taken: ``spec`` 1 or 0 for always or never, or a string of bits by offset (``"11101"``:
    not 3 clocks after), 1 beyond its end."""
    if isinstance(spec, int):
        return bool(spec)
    return offset >= len(spec) or spec[offset] == "1"


def record(link):
    """What one frame did, from the clock it was taken (offsets from it): the access given on
    the clock after (address, data), every clock ``given`` was high (offset, address), the
    ``write_en`` clocks, the writes done (offset, address, data), the ``segment`` clocks
    (offset, x, y), the ``status_read``, ``refused`` and ``accepted`` clocks, and the answers
    offered (offset, link, (tag, code, data), taken)."""
    return {"link": link, "access": None, "given": [], "write_en": [], "written": [],
            "segment": [], "status_read": [], "refused": [], "accepted": [], "offers": []}


class Model:
    """The rules, one frame at a time, with the clocks each step is due on."""

    def __init__(self, free=QUEUE):
        self.stub = RegisterStub(free)
        self.seq = 0
        self.errors = 0
        self.frames = []            # a record() of each frame, in the order taken
        self.answers = {"spi": [], "uart": []}
        self.lost = []
        self.writes, self.segments, self.taken = [], [], []

    def group(self, frames, ready=(1, 0)):
        """Frames offered together (SPI goes first), ``ready`` the group's (SPI target's
        readiness, UART port's busy clocks). Returns the frames with every ``seq`` None or
        :class:`Near` made the one it says."""
        resolved = []
        for link, (seq, *rest), intact in sorted(frames, key=lambda f: f[0] != "spi"):
            if seq is None or isinstance(seq, Near):
                seq = (self.seq + (seq or 0)) % 256
            frame = (link, (seq, *rest), intact)
            self.frame(*frame, ready=ready)
            resolved.append(frame)
        return resolved

    def frame(self, link, frame, intact, *, ready=(1, 0)):
        seq, address, data, x, y = fields(payload(*frame))
        reg = address & 0x7F
        self.taken.append(link)
        done = record(link)
        self.frames.append(done)
        # T+1: the access is given, whatever is decided.
        done["access"] = (reg, data)
        done["given"].append((1, reg))
        if not intact:
            return self.refuse(done, seq, "check", 2, ready)
        if address & 0x80:
            if not self.stub.is_register(reg) or data != 0:
                return self.refuse(done, seq, "register", 2, ready)
            # T+2: read; T+3: accepted, the value comes; T+4: the answer.
            if reg == STATUS:
                done["status_read"].append(2)
            done["accepted"].append(3)
            return self.answer(done, (seq, reg, self.read(reg)), 4, ready)
        if seq != self.seq:
            return self.refuse(done, seq, "sequence", 2, ready)
        # T+2: done or refused by the register file, the register given again to read back.
        back = FIFO_FREE if reg == VEC_OP else reg
        done["given"].append((2, back))
        done["write_en"].append(2)
        if reg == VEC_OP:
            done["segment"].append((2, x, y))
        if not self.stub.write_ok(reg, data):
            return self.refuse(done, seq, "register", 3, ready)
        self.stub.write(reg, data)
        done["written"].append((2, reg, data))
        self.writes.append((reg, data))
        if reg == VEC_OP:
            self.segments.append((data, x, y))
        self.seq = (self.seq + 1) % 256
        # T+3: read back; T+4: accepted, the value comes; T+5: the answer.
        done["accepted"].append(4)
        self.answer(done, (seq, reg, self.read(back)), 5, ready)

    def read(self, address):
        self.stub.live = {ERRORS: self.errors, LINK_SEQ: self.seq}
        return self.stub.read(address)

    def count(self):
        self.errors = min(self.errors + 1, 65535)

    def refuse(self, done, seq, reason, when, ready):
        self.count()
        done["refused"].append(when)
        self.answer(done, (seq, 0x80 | REASON[reason], self.seq), when + 1, ready)

    def answer(self, done, answer, when, ready):
        link = done["link"]
        taken = link == "uart" or spi_ready(ready[0], when)
        done["offers"].append((when, link, answer, taken))
        if taken:
            self.answers[link].append(answer)
        else:
            self.lost.append(answer)
            self.count()


def run_decoder(offers, *, ready=lambda group: (1, 0), gap=6, free=QUEUE):
    """Offer frames to the decoder. ``offers`` is a list of lists: the frames of one entry,
    ``(link, (seq, address, data, x, y), intact)``, are offered together (at most one per
    link), each held until taken; ``gap`` clocks pass after the last is taken before the next
    entry's are offered. ``ready(entry)`` is ``(spi, busy)`` for the entry's frames: the SPI
    target's ``ready`` (see :func:`spi_ready`: by clocks since the frame in hand was taken)
    and the clocks the UART port stays busy (``ready`` low) after taking an answer.

    Checked on every clock: a frame is taken exactly when the decoder is free (SPI first), an
    answer is held from the clock it is offered to the clock the next frame is taken, a UART
    answer is never offered while the port is busy, ``errors`` goes up (to 65535) on the clock
    after a refusal or a lost answer and at no other time, ``write_en`` and ``segment`` come
    with ``given``. Returns what happened: a :func:`record` of each frame taken, answers taken
    off each link and lost (SPI), writes done on the bus (applied to the stub), segments
    queued (data, x, y), errors and seq, the order the frames were taken in and the clocks."""
    dut = CommandDecoder()
    stub = RegisterStub(free)
    seen = {"answers": {"spi": [], "uart": []}, "lost": [], "writes": [], "segments": [],
            "frames": [], "taken": [], "takes": []}
    streams = {"spi": (dut.spi_frames, dut.spi_replies),
               "uart": (dut.uart_frames, dut.uart_replies)}

    async def bench(ctx):
        s = {"clock": 0, "group": 0, "before": None, "last_read": 0xBEEF, "busy_until": -1,
             "held": None, "errors": 0, "counted": False}
        idle = record(None)         # what happens before the first frame: nothing

        async def step(offered):
            clock = s["clock"]
            if seen["takes"]:
                taken_at, group = seen["takes"][-1]
                done, offset = seen["frames"][-1], clock - taken_at
                spi, busy = ready(group)
            else:
                done, offset, spi, busy = idle, clock, 1, 0
            ctx.set(dut.spi_replies.ready, spi_ready(spi, offset))
            ctx.set(dut.uart_replies.ready, clock > s["busy_until"])
            # errors: one up on the clock after a refusal or a lost answer, else unchanged.
            errors = ctx.get(dut.errors)
            assert errors == min(s["errors"] + s["counted"], 65535), clock
            stub.live = {ERRORS: errors, LINK_SEQ: ctx.get(dut.seq)}
            access = ctx.get(dut.bus.address), ctx.get(dut.bus.write_data)
            ctx.set(dut.bus.read_ok, stub.is_register(access[0]))
            # The access given on the clock before is checked, done and read now (RegisterBus);
            # its value read comes on the next clock.
            before = s["before"]
            write_ok = before is not None and stub.write_ok(*before)
            ctx.set(dut.bus.write_ok, write_ok)
            ctx.set(dut.bus.read_data, s["last_read"])
            value = stub.read(before[0]) if before else 0xBEEF
            # The answers.
            lost = False
            for link, (_, replies) in streams.items():
                answer = ctx.get(replies.payload.as_value())
                if ctx.get(replies.valid):
                    taken = bool(ctx.get(replies.ready))
                    assert link == "spi" or taken, "a UART answer offered while the port is busy"
                    done["offers"].append((offset, link, unpack(answer), taken))
                    (seen["answers"][link] if taken else seen["lost"]).append(unpack(answer))
                    lost |= not taken
                    if link == "uart":
                        s["busy_until"] = clock + busy
                    s["held"] = (link, answer)
                elif s["held"] and s["held"][0] == link:
                    assert answer == s["held"][1], f"the answer is held ({clock})"
            # The rest of what crosses the edge.
            given = ctx.get(dut.given)
            if given:
                done["given"].append((offset, access[0]))
            if offset == 1:
                done["access"] = access
            write_en = ctx.get(dut.bus.write_en)
            assert not write_en or given
            written = write_en and write_ok
            if write_en:
                done["write_en"].append(offset)
            if written:
                done["written"].append((offset, *before))
                seen["writes"].append(before)
            segment = ctx.get(dut.segment)
            # The segment goes with a vec_op write, and only then.
            assert not segment or (write_en and before[0] == VEC_OP)
            assert segment or not (write_en and before[0] == VEC_OP)
            if segment:
                done["segment"].append((offset, ctx.get(dut.segment_x), ctx.get(dut.segment_y)))
                if written:
                    seen["segments"].append(
                        (before[1], ctx.get(dut.segment_x), ctx.get(dut.segment_y)))
            refused = ctx.get(dut.refused)
            for name, signal in (("status_read", dut.status_read), ("refused", dut.refused),
                                 ("accepted", dut.accepted)):
                if ctx.get(signal):
                    done[name].append(offset)
            s["errors"], s["counted"] = errors, bool(refused or lost)
            # A frame is taken when the decoder is free: its last answer offered on an earlier
            # clock (or none taken yet), and the UART port not busy. SPI first.
            offers = done["offers"]
            free = ((not seen["takes"] or (offers and offers[-1][0] < offset))
                    and ctx.get(dut.uart_replies.ready))
            valid = [link for link in ("spi", "uart") if ctx.get(streams[link][0].valid)]
            expected = valid[:1] if free else []
            taken = [link for link in offered
                     if ctx.get(streams[link][0].valid) and ctx.get(streams[link][0].ready)]
            assert taken == expected, clock
            if taken:
                seen["takes"].append((clock, s["group"]))
                seen["frames"].append(record(taken[0]))
                s["held"] = None
            await ctx.tick()
            s["clock"] += 1
            if written:
                stub.write(*before)
            s["before"] = access
            s["last_read"] = value
            return taken

        for index, group in enumerate(offers):
            s["group"] = index
            waiting = {}
            for link, frame, intact in group:
                frames = streams[link][0]
                ctx.set(frames.payload, {"payload": payload(*frame), "intact": intact})
                ctx.set(frames.valid, 1)
                waiting[link] = True
            start = s["clock"]
            while waiting:
                assert s["clock"] - start < 100, "a frame never taken"
                for link in await step(list(waiting)):
                    seen["taken"].append(link)
                    ctx.set(streams[link][0].valid, 0)
                    del waiting[link]
            for _ in range(gap):
                await step([])
        # Until the last answer is out and the UART port done, and a few clocks more.
        for _ in range(100):
            if not seen["frames"] or seen["frames"][-1]["offers"]:
                break
            await step([])
        for _ in range(max(3, s["busy_until"] - s["clock"] + 3)):
            await step([])
        seen["errors"] = ctx.get(dut.errors)
        seen["seq"] = ctx.get(dut.seq)
        assert idle == record(None), "nothing happens before the first frame"

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    seen["stub"] = stub.regs
    return seen


def check_against_model(offers, *, ready=lambda group: (1, 0), free=QUEUE, **kw):
    """Run the model, then the decoder, on the same frames (every ``seq`` None made the one
    the model expects then, and every :class:`Near` from it), and compare all they did, frame
    by frame and clock by clock."""
    model = Model(free)
    offers = [model.group(group, ready(index)) for index, group in enumerate(offers)]
    seen = run_decoder(offers, ready=ready, free=free, **kw)
    assert seen["taken"] == model.taken
    for index, (did, expected) in enumerate(zip(seen["frames"], model.frames)):
        assert (index, did) == (index, expected)
    assert len(seen["frames"]) == len(model.frames)
    assert seen["answers"] == model.answers
    assert seen["lost"] == model.lost
    assert seen["writes"] == model.writes
    assert seen["segments"] == model.segments
    assert seen["errors"] == model.errors
    assert seen["seq"] == model.seq
    assert seen["stub"] == model.stub.regs
    return seen, model


def one_by_one(frames):
    return [[f] for f in frames]


def refusal(tag, reason, expected):
    return (tag, 0x80 | REASON[reason], expected)


def total(seen, name):
    """Clocks ``name`` was high, over every frame."""
    return sum(len(done[name]) for done in seen["frames"])


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
    other = "uart" if link == "spi" else "spi"
    assert seen["answers"][other] == [] and seen["lost"] == []
    assert seen["errors"] == 0 and total(seen, "status_read") == 1 and seen["seq"] == 2
    # Writes: given twice (the access, then the read back), answered 5 clocks after taken;
    # reads: given once, answered 4 clocks after.
    assert [len(done["given"]) for done in seen["frames"]] == [2, 1, 1, 2, 1, 1]
    assert [done["offers"][0][0] for done in seen["frames"]] == [5, 4, 4, 5, 4, 4]
    assert [done["accepted"] for done in seen["frames"]] == [[4], [3], [3], [4], [3], [3]]


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
    assert seen["errors"] == 1 and total(seen, "refused") == 1
    assert seen["answers"][link] == [refusal(seq, reason, 0), (0, 0x04, 3), (0, LINK_SEQ, 0),
                                     (0, 0x04, 6)]
    assert seen["writes"] == [(0x04, 6)] and seen["segments"] == []
    # Refused on deciding (T+2, answered at T+3), the access given once; a write in sequence
    # goes to the register file, which refuses it (T+3, answered at T+4), given twice.
    by_the_file = intact and not body[1] & 0x80 and seq == 0
    done = seen["frames"][0]
    assert done["access"] == (body[1] & 0x7F, body[2])
    assert len(done["given"]) == (2 if by_the_file else 1)
    assert done["refused"] == [3 if by_the_file else 2]
    assert done["offers"] == [(4 if by_the_file else 3, link, refusal(seq, reason, 0), True)]
    assert done["accepted"] == [] and done["written"] == []


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
    # The write of vec_op reads fifo_free back; the segment goes with it (the one the queue
    # refuses too), x and y from the frame.
    assert [done["given"] for done in seen["frames"][:5]] == [
        [(1, VEC_OP), (2, FIFO_FREE)], [(1, 0x09), (2, 0x09)], [(1, VEC_OP), (2, FIFO_FREE)],
        [(1, VEC_OP), (2, FIFO_FREE)], [(1, VEC_OP), (2, FIFO_FREE)]]
    assert [done["segment"] for done in seen["frames"]] == [
        [(2, 0x1234, 0xABCD)], [], [(2, 0xFFFF, 0)], [(2, 0, 0xFFFF)], [(2, 5, 6)], [], []]


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
    # Each answer on its own link only.
    assert all(offer[1] == done["link"] for done in seen["frames"] for offer in done["offers"])


@pytest.mark.parametrize("gap", [0, 1, 2, 3])
def test_frames_back_to_back(gap):
    """The next frame offered as soon as (or soon after) one is taken: each waits its turn."""
    check_against_model(one_by_one([
        write("spi", 0, 0x04, 1), read("spi", 0x04), write("uart", 1, VEC_OP, 2, 3, 4),
        write("uart", 2, 0x09, 1), read("uart", 0x09), write("spi", 0, 0x09, 1, intact=False),
        read("spi", 0x04, data=1), write("spi", 3, 0x09, 9)]), gap=gap)


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_an_answer_is_offered_for_one_clock_and_held_until_the_next_frame_is_taken(link):
    """Frames always waiting: each is taken on the clock after the answer to the one before
    is offered (not on that clock), and that answer is held until then (the harness checks
    the holding on every clock; here also over a long pause)."""
    seen, _ = check_against_model(one_by_one([
        write(link, 0, 0x04, 7),                        # done: answered at T+5
        read(link, 0x04, seq=1),                        # answered at T+4
        write(link, 5, 0x04, 8),                        # out of sequence: answered at T+3
        write(link, 1, 0x09, 200),                      # the file refuses it: at T+4
        read(link, 0x04, seq=2),
    ]), gap=0)
    delays = [done["offers"][0][0] for done in seen["frames"]]
    assert delays == [5, 4, 3, 4, 4]
    clocks = [clock for clock, _ in seen["takes"]]
    assert [b - a for a, b in zip(clocks, clocks[1:])] == [d + 1 for d in delays[:-1]]
    assert all(len(done["offers"]) == 1 for done in seen["frames"])
    # A pause: the answer stays on the link for 40 clocks.
    check_against_model(one_by_one([read(link, 0x04, seq=3), read(link, 0x09)]), gap=40)


def test_an_spi_answer_the_target_cannot_take_is_lost_and_counted():
    """Offered for one clock only: an SPI answer the target does not take then is lost (the
    write or read is done all the same) and counted; a refusal lost counts twice. The
    target's readiness on the other clocks makes no difference."""
    readies = [(0, 0), ("11110", 0), ("11101", 0), ("000", 0), ("1110", 0), (0, 0), (1, 0)]
    seen, _ = check_against_model(one_by_one([
        write("spi", 0, 0x04, 7),                       # lost
        read("spi", 0x04, seq=1),                       # lost (offered at T+4)
        read("spi", 0x04, seq=2),                       # taken
        write("spi", 1, 0x09, 3),                       # taken (offered at T+5)
        write("spi", 0, 0x09, 1, intact=False),         # refused, lost: counted twice
        read("uart", ERRORS, seq=3),                   # SPI not ready: no matter
        read("spi", ERRORS, seq=4),
    ]), ready=lambda g: readies[g])
    assert seen["lost"] == [(0, 0x04, 7), (1, 0x04, 7), refusal(0, "check", 2)]
    assert seen["answers"] == {"spi": [(2, 0x04, 7), (1, 0x09, 3), (4, ERRORS, 4)],
                               "uart": [(3, ERRORS, 4)]}
    assert seen["writes"] == [(0x04, 7), (0x09, 3)] and seen["seq"] == 2
    assert total(seen, "refused") == 1 and seen["errors"] == 4


def test_no_frame_is_taken_while_the_uart_port_sends_an_answer():
    """The UART port busy for 9 clocks after taking an answer: the next frame, on either link,
    waits until it is done; every UART answer is taken (the harness checks it never meets a
    busy port)."""
    readies = [(1, 9), (1, 0), (1, 3), (1, 3), (1, 0)]
    seen, _ = check_against_model(one_by_one([
        write("uart", 0, 0x04, 7), read("spi", 0x04), read("uart", 0x04, seq=1),
        write("uart", 1, 0x09, 2), read("spi", 0x09)]), ready=lambda g: readies[g], gap=0)
    clocks = [clock for clock, _ in seen["takes"]]
    delays = [done["offers"][0][0] for done in seen["frames"]]
    # After a UART answer (offered at T + delay), the next is taken once the port is done.
    assert [b - a for a, b in zip(clocks, clocks[1:])] == [5 + 9 + 1, 4 + 1, 4 + 3 + 1,
                                                           5 + 3 + 1]
    assert delays == [5, 4, 4, 5, 4]
    assert seen["lost"] == [] and seen["errors"] == 0
    assert seen["answers"] == {"spi": [(0, 0x04, 7), (0, 0x09, 2)],
                               "uart": [(0, 0x04, 7), (1, 0x04, 7), (1, 0x09, 2)]}


def test_errors_stop_at_65535():
    """A damaged frame always waiting (SPI: one taken every four clocks), its answer lost
    (the target never ready): each counts twice, on the clock after it is refused and on the
    clock after its answer is lost. After a few the count is set near the top (as if 65 000
    more had come: counting them would take the simulator some 10 s); it climbs to 65535 and
    stays."""
    dut = CommandDecoder()
    counts = []

    async def bench(ctx):
        ctx.set(dut.spi_frames.payload, {"payload": payload(0, 0x04, 5), "intact": 0})
        ctx.set(dut.spi_frames.valid, 1)
        ctx.set(dut.spi_replies.ready, 0)
        ctx.set(dut.uart_replies.ready, 1)
        for _ in range(4):
            await ctx.tick().repeat(4)
            counts.append(ctx.get(dut.errors))
        ctx.set(dut.errors, 65530)
        for _ in range(5):
            await ctx.tick().repeat(4)
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
        ctx.set(dut.spi_replies.ready, 1)
        ctx.set(dut.uart_replies.ready, 1)
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
# The SPI target's readiness (always, never, or by clocks since the frame was taken) and the
# clocks the UART port is busy after taking an answer.
readiness = st.tuples(
    st.one_of(st.just(1), st.just(1), st.just(0),
              st.lists(st.sampled_from("01"), min_size=6, max_size=6).map("".join)),
    st.sampled_from([0, 0, 1, 2, 5]))


@settings(max_examples=40, deadline=None)
@given(offers, st.lists(readiness, min_size=12, max_size=12), st.integers(1, 4),
       st.integers(0, 3))
def test_random_frames_on_both_links_against_the_model(offers, readies, free, gap):
    check_against_model(offers, ready=lambda g: readies[g], free=free, gap=gap)


@settings(max_examples=25, deadline=None)
@given(offers, st.integers(0, 6))
def test_random_frames_back_to_back_against_the_model(offers, gap):
    check_against_model(offers, gap=gap)
