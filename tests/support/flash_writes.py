"""What the flash writers' tests write: a random ECP5 bitstream (the ULX3S's 25F, unless told
another part) and a small job image."""

import random

from galvoscan.outputs.image import job_image

from ecp5_jtag import ecp5_bitstream


#: The IDCODEs of the ULX3S's parts the tests name (Lattice's ECP5 family data sheet).
LFE5U_25F = 0x41111043
LFE5U_85F = 0x41113043


def bitstream(size, seed=1, idcode=LFE5U_25F):
    rng = random.Random(seed)
    return ecp5_bitstream(idcode, bytes(rng.getrandbits(8) for _ in range(size)))


def a_job():
    segments = [("jump", 100, 200), ("mark", 3000, 200), ("mark", 3000, 2500)]
    return job_image(segments, {"pitch": 40, "laser_power": 128})
