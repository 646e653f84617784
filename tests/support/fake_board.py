"""A board that is a dict of registers, for the streamer's protocol tests (no simulator)."""

from galvoscan.gateware.host.regmap import BY_NAME, STATUS_BITS
from galvoscan.link.client import ClientError
from galvoscan.outputs.stream import QUEUE_DEPTH


#: The ``caps`` register's bits as its description gives them (bit 0 spiral … bit 9 spi).
CAPS_BITS = {"spiral": 0, "raster": 1, "vector": 2, "laser": 3, "correction": 4, "wobble": 5,
             "delays": 6, "interpolation": 7, "uart": 8, "spi": 9}
#: The registers whose absence a ``caps`` bit reports.
CAPS_REGISTERS = {"wobble": "wob_shape", "delays": "mark_delay", "vector": "vec_op"}


class FakeBoard:
    """Registers in a dict, a queue that drains by ``drain`` segments per read of fifo_free,
    and a script of status flags; every write is logged. Registers in ``missing`` are not in
    its bitstream: a write of one is refused and counted in ``errors`` (not logged), a read of
    one goes unanswered (logged in ``unanswered``: the host would wait out its timeout), and
    ``caps`` says so (``missing`` with "caps": a bitstream from before that register)."""

    def __init__(self, *, drain=64, flags=(), fail_after=None, depth=QUEUE_DEPTH, missing=()):
        self.values = {r.name: r.reset for r in BY_NAME.values()}
        self.values["caps"] = sum(1 << bit for name, bit in CAPS_BITS.items()
                                  if CAPS_REGISTERS.get(name) not in missing)
        self.depth = depth
        self.queue = 0
        self.drain = drain
        self.flags = set(flags)
        self.log = []
        self.fail_after = fail_after
        self.missing = set(missing)
        self.unanswered = []

    def _status(self):
        if self.values["run"]:
            self.queue = max(0, self.queue - self.drain)
        bits = {"armed": self.values["arm"], "laser_ready": self.values["arm"],
                "laser_enable": self.values["arm"], "vector_busy": self.queue > 0}
        bits.update({name: 1 for name in self.flags})
        return sum(1 << STATUS_BITS[name] for name, on in bits.items() if on)

    def write(self, name, value):
        if self.fail_after is not None and len(self.log) >= self.fail_after:
            raise ClientError("no answer from the board")
        if name in self.missing:
            self.values["errors"] = min(self.values["errors"] + 1, 0xFFFF)
            return
        self.log.append((name, value))
        if name == "vec_op":
            assert self.queue < self.depth, "written into a full queue"
            self.queue += 1
        else:
            self.values[name] = value

    def write_many(self, items):
        for name, value in items:
            self.write(name, value)

    #: Frames the client sent again (the real one counts them; none here).
    retries = 0

    def queue_segments(self, segments):
        """One segment a frame, as the real client sends them: logged as the three values
        each carries, in the order the registers' had them."""
        for op_word, x, y in segments:
            self.log += [("vec_x", x), ("vec_y", y)]
            self.write("vec_op", op_word)
        return self.read("fifo_free")

    def read(self, name):
        if name in self.missing:
            self.unanswered.append(name)
            raise ClientError("no answer from the board")
        if name == "status":
            return self._status()
        if name == "fifo_free":
            if self.values["run"]:
                self.queue = max(0, self.queue - self.drain)
            return self.depth - self.queue
        if name == "mode":
            return self.values["mode"]
        return self.values.get(name, 0)


def job(n):
    return [("jump" if i % 10 == 0 else "mark", 1000 + i, 2000 + i) for i in range(n)]
