# amaranth: UnusedElaboratable=no
"""The command decoder alone (gateware/host/command.py), its register bus answered by a small
register file modelled here, against the README's frame rules: a frame ``address, data[15:8],
data[7:0], 0x64`` is accepted only if it is complete (32 bits), its check byte is 0x64, the
address is a register, the access is allowed (no writes to read-only registers, read requests
carry zero data) and the value is in the register's range; a read is answered ``address, value,
0x64`` on the link it came from; anything else changes nothing and adds one to ``errors``, which
stops at 65535."""

from amaranth.sim import Simulator
from hypothesis import given, settings, strategies as st
import pytest

from galvoscan.gateware.host.command import CommandDecoder


CHECK = 0x64
STATUS = 0x00           # README register table: reading status clears its sticky flags


class RegisterStub:
    """A few registers of each kind: (access, low, high, value). Answers the bus the way the
    RegisterBus docstring says: ``read_ok`` for a register, ``write_ok`` for a writable one with
    the value in range, ``read_data`` its value on the next clock (garbage for no register)."""

    def __init__(self):
        self.regs = {
            0x00: ["ro", 0, 0, 0x0105],
            0x01: ["ro", 0, 0, 0x0000],
            0x04: ["rw", 1, 65535, 3],
            0x09: ["rw", 0, 127, 0],
            0x12: ["rw", 200, 2000, 500],
            0x36: ["rw", 0, 3, 0],
            0x44: ["rw", 0, 1, 0],
        }

    def answer(self, address, data):
        reg = self.regs.get(address)
        read_ok = reg is not None
        write_ok = read_ok and reg[0] == "rw" and reg[1] <= data <= reg[2]
        return write_ok, read_ok, reg[3] if reg else 0xBEEF

    def write(self, address, data):
        self.regs[address][3] = data


def encode(address, data, check=CHECK):
    return (address << 24) | (data << 8) | check


class Model:
    """The rules, one frame at a time."""

    def __init__(self):
        self.stub = RegisterStub()
        self.errors = 0
        self.writes, self.replies, self.refused = [], {"spi": [], "uart": []}, []
        self.status_reads = 0

    def frame(self, link, word, bits, *, reply_free=True):
        address, data, check = word >> 24, (word >> 8) & 0xFFFF, word & 0xFF
        reg = self.stub.regs.get(address & 0x7F)
        ok = False
        if bits == 32 and check == CHECK:
            if address & 0x80:
                if reg is not None and data == 0 and reply_free:
                    self.replies[link].append(encode(address & 0x7F, reg[3]))
                    self.status_reads += (address & 0x7F) == STATUS
                    ok = True
            elif reg is not None and reg[0] == "rw" and reg[1] <= data <= reg[2]:
                self.stub.write(address, data)
                self.writes.append((address, data))
                ok = True
            else:
                self.refused.append(address)
        if not ok:
            self.errors = min(self.errors + 1, 65535)


def run_decoder(offers, *, ready=lambda clock: (1, 1)):
    """Offer frames to the decoder. ``offers`` is a list of lists: the frames of one entry,
    ``(link, word, bits)``, are offered together (at most one per link), each held until
    taken. ``ready(clock)`` gives the reply streams' ready (spi, uart). Returns what happened:
    writes done on the bus (applied to the stub), replies taken off each link, errors, the
    accepted/status_read/write_refused pulses, and the order the frames were taken in."""
    dut = CommandDecoder()
    stub = RegisterStub()
    seen = {"writes": [], "replies": {"spi": [], "uart": []}, "accepted": 0,
            "status_reads": 0, "refused": [], "taken": []}
    streams = {"spi": (dut.spi_frames, dut.spi_replies), "uart": (dut.uart_frames,
                                                                  dut.uart_replies)}

    async def bench(ctx):
        clock = 0
        given = [None]                  # (address, data) given on the bus on the clock before
        last_read = [0xBEEF]             # the value read on the clock before

        async def step(offered):
            nonlocal clock
            spi_ready, uart_ready = ready(clock)
            ctx.set(dut.spi_replies.ready, spi_ready)
            ctx.set(dut.uart_replies.ready, uart_ready)
            address, data = ctx.get(dut.bus.address), ctx.get(dut.bus.write_data)
            _, read_ok, _ = stub.answer(address, data)
            ctx.set(dut.bus.read_ok, read_ok)
            # The access given on the clock before is checked, done and read now (RegisterBus);
            # its value read comes on the next clock.
            write_ok, _, read_data = stub.answer(*given[0]) if given[0] else (0, 0, 0xBEEF)
            ctx.set(dut.bus.write_ok, write_ok)
            ctx.set(dut.bus.read_data, last_read[0])
            # What crosses the edge.
            for link, (_, replies) in streams.items():
                if ctx.get(replies.valid) and ctx.get(replies.ready):
                    seen["replies"][link].append(ctx.get(replies.payload))
            write = ctx.get(dut.bus.write_en) and write_ok and given[0]
            if write:
                seen["writes"].append(given[0])
            seen["accepted"] += ctx.get(dut.accepted)
            seen["status_reads"] += ctx.get(dut.status_read)
            if ctx.get(dut.write_refused):
                seen["refused"].append(given[0][0])
            taken = [link for link in offered
                     if ctx.get(streams[link][0].valid) and ctx.get(streams[link][0].ready)]
            await ctx.tick()
            clock += 1
            if write:
                stub.write(*write)
            given[0] = (address, data)
            last_read[0] = read_data
            return taken

        for group in offers:
            waiting = {}
            for link, word, bits in group:
                frames = streams[link][0]
                ctx.set(frames.payload, {"word": word, "bits": bits})
                ctx.set(frames.valid, 1)
                waiting[link] = True
            while waiting:
                for link in await step(list(waiting)):
                    seen["taken"].append(link)
                    ctx.set(streams[link][0].valid, 0)
                    del waiting[link]
            # A link's frames come at least 32 bits apart: never within the three clocks a
            # read takes to be answered.
            for _ in range(3):
                await step([])
        for _ in range(4):
            await step([])
        seen["errors"] = ctx.get(dut.errors)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    seen["stub"] = stub.regs
    return seen


def check_against_model(offers, **kw):
    seen = run_decoder(offers, **kw)
    model = Model()
    order = iter(seen["taken"])
    for group in offers:
        by_link = {link: (word, bits) for link, word, bits in group}
        for _ in group:
            link = next(order)
            model.frame(link, *by_link[link])
    assert seen["writes"] == model.writes
    assert seen["replies"] == model.replies
    assert seen["errors"] == model.errors
    assert seen["refused"] == model.refused
    assert seen["status_reads"] == model.status_reads
    assert seen["accepted"] == len(model.writes) + sum(map(len, model.replies.values()))
    assert seen["stub"] == model.stub.regs
    return seen, model


def one_by_one(frames):
    return [[f] for f in frames]


# --- single rules ------------------------------------------------------------------------------

@pytest.mark.parametrize("link", ["spi", "uart"])
def test_write_then_read_back(link):
    seen, _ = check_against_model(one_by_one([
        (link, encode(0x04, 0x1234), 32),
        (link, encode(0x84, 0), 32),
        (link, encode(0x80, 0), 32),        # status
    ]))
    assert seen["replies"][link] == [encode(0x04, 0x1234), encode(0x00, 0x0105)]
    assert seen["errors"] == 0 and seen["status_reads"] == 1


@pytest.mark.parametrize("word, bits", [
    (encode(0x04, 5, check=0x65), 32),      # wrong check byte
    (encode(0x04, 5, check=0x00), 32),
    (encode(0x04, 5, check=0xE4), 32),
    (encode(0x84, 0, check=0x46), 32),      # a read with a wrong check byte
    (encode(0x7E, 5), 32),                  # unknown address
    (encode(0xFE, 0), 32),                  # read of an unknown address
    (encode(0x00, 1), 32),                  # write to a read-only register
    (encode(0x01, 0), 32),
    (encode(0x84, 1), 32),                  # read with non-zero data
    (encode(0x84, 0x8000), 32),
    (encode(0x04, 0), 32),                  # out of range (1…65535)
    (encode(0x09, 128), 32),                # out of range (0…127)
    (encode(0x12, 199), 32),                # below range (200…2000)
    (encode(0x12, 2001), 32),
    (encode(0x04, 5), 31),                  # cut short
    (encode(0x04, 5), 33),                  # overlong
    (encode(0x04, 5), 0),
    (encode(0x04, 5), 63),                  # spoilt by a line error
])
@pytest.mark.parametrize("link", ["spi", "uart"])
def test_refused_frames_change_nothing_and_count(link, word, bits):
    seen, _ = check_against_model(one_by_one([(link, word, bits), (link, encode(0x84, 0), 32)]))
    assert seen["errors"] == 1
    assert seen["writes"] == []
    assert seen["replies"][link] == [encode(0x04, 3)]


def test_write_refused_names_the_register():
    """Only a well-formed write the register file refuses raises write_refused."""
    seen, _ = check_against_model(one_by_one([
        ("spi", encode(0x09, 200), 32), ("uart", encode(0x00, 7), 32),
        ("spi", encode(0x09, 200, check=0x11), 32), ("spi", encode(0x89, 5), 32),
        ("spi", encode(0x09, 200), 24)]))
    assert seen["refused"] == [0x09, 0x00]
    assert seen["errors"] == 5


def test_edges_of_a_range_are_accepted():
    seen, _ = check_against_model(one_by_one([
        ("spi", encode(0x12, 200), 32), ("spi", encode(0x92, 0), 32),
        ("uart", encode(0x12, 2000), 32), ("uart", encode(0x92, 0), 32),
        ("spi", encode(0x04, 0xFFFF), 32), ("spi", encode(0x04, 1), 32)]))
    assert seen["errors"] == 0
    assert seen["replies"] == {"spi": [encode(0x12, 200)], "uart": [encode(0x12, 2000)]}


def test_replies_go_back_on_the_link_the_read_came_from():
    seen, _ = check_against_model(one_by_one([
        ("uart", encode(0x04, 77), 32),
        ("spi", encode(0x84, 0), 32), ("uart", encode(0x89, 0), 32),
        ("uart", encode(0x84, 0), 32), ("spi", encode(0x80, 0), 32)]))
    assert seen["replies"] == {"spi": [encode(0x04, 77), encode(0x00, 0x0105)],
                               "uart": [encode(0x09, 0), encode(0x04, 77)]}


@pytest.mark.parametrize("first", ["spi", "uart"])
def test_both_links_at_once(first):
    """Frames on both links in the same clock: both are decoded, SPI first (so a read on the
    UART sees the SPI write of the same clock)."""
    other = "uart" if first == "spi" else "spi"
    seen, _ = check_against_model([
        [(first, encode(0x04, 1000), 32), (other, encode(0x84, 0), 32)],
        [("spi", encode(0x89, 0), 32), ("uart", encode(0x89, 0), 32)],
        [("spi", encode(0x09, 1), 32), ("uart", encode(0x09, 2), 32)],
        [("uart", encode(0x89, 0), 32)],
    ])
    assert seen["taken"][:2] == ["spi", "uart"]
    assert seen["stub"][0x09][3] == 2           # SPI's write first, then UART's
    assert seen["errors"] == 0


@pytest.mark.parametrize("link", ["spi", "uart"])
def test_a_read_whose_answer_cannot_be_queued_is_refused(link):
    """While the link's reply is still waiting to be taken, another read is refused and
    counted; the other link is unaffected."""
    other = "uart" if link == "spi" else "spi"
    blocked = (lambda clock: (0, 1)) if link == "spi" else (lambda clock: (1, 0))
    seen = run_decoder(one_by_one([(link, encode(0x84, 0), 32), (link, encode(0x89, 0), 32),
                                   (other, encode(0x89, 0), 32)]), ready=blocked)
    assert seen["replies"][other] == [encode(0x09, 0)]
    if link == "spi":
        # The first answer waits for the host's next frame; the second read is refused.
        assert seen["errors"] == 1 and seen["accepted"] == 2
    else:
        # The UART port's queue is full (ready low): both reads are refused.
        assert seen["errors"] == 2 and seen["accepted"] == 1


def test_errors_stop_at_65535():
    """A bad frame every clock (SPI, always taken): the count climbs to 65535 and stays."""
    dut = CommandDecoder()
    counts = []

    async def bench(ctx):
        ctx.set(dut.spi_frames.payload, {"word": encode(0x04, 5, check=0), "bits": 32})
        ctx.set(dut.spi_frames.valid, 1)
        # Each frame is counted on the clock after it is taken.
        await ctx.tick().repeat(65535)
        counts.append(ctx.get(dut.errors))
        await ctx.tick()
        counts.append(ctx.get(dut.errors))
        await ctx.tick().repeat(3)
        counts.append(ctx.get(dut.errors))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert counts == [65534, 65535, 65535]


# --- random frames -----------------------------------------------------------------------------

addresses = st.sampled_from([0x00, 0x01, 0x04, 0x09, 0x12, 0x36, 0x44, 0x05, 0x7E, 0x7F])
word = st.one_of(
    st.tuples(addresses, st.booleans(), st.integers(0, 0xFFFF)).map(
        lambda t: encode(t[0] | 0x80 * t[1], t[2] if not t[1] or t[2] % 3 else 0)),
    st.tuples(addresses, st.integers(0, 0xFFFF), st.integers(0, 255)).map(
        lambda t: encode(t[0], t[1], t[2])),
    st.integers(0, 2 ** 32 - 1),
)
frame = st.tuples(st.sampled_from(["spi", "uart"]), word,
                  st.sampled_from([32, 32, 32, 32, 0, 8, 31, 33, 63]))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(frame, min_size=1, max_size=2).map(
    lambda g: list({f[0]: f for f in g}.values())), min_size=1, max_size=12))
def test_random_frames_on_both_links_against_the_model(offers):
    check_against_model(offers)
