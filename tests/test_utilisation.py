"""Cells by block (galvoscan/utilisation.py), on a small build whose blocks' DSPs and RAMs the
the docs state: one DSP per axis in the scale stage, the two spiral tables in block RAM."""

import pytest

from galvoscan.gateware.top import GalvoScanTop
from galvoscan.utilisation import block_utilisation


@pytest.mark.toolchain
def test_blocks_of_a_spiral_only_build(tmp_path):
    top = GalvoScanTop(clk_freq=12e6, modes=("spiral",), correction=None, laser=False,
                       links=("spi",))
    blocks = block_utilisation(top, workdir=tmp_path)
    assert {"top.phy", "top.spiral", "top.scale", "top.registers", "top.spi"} <= set(blocks)
    assert blocks["top.scale"]["dsps"] == 2
    assert blocks["top.spiral"]["rams"] == 2
    assert sum(b["dsps"] for b in blocks.values()) == 2
    # Largest first, and every block counted has something in it.
    luts = [b["luts"] for b in blocks.values()]
    assert luts == sorted(luts, reverse=True)
    assert all(any(b.values()) for b in blocks.values())
    assert not any("$" in name for name in blocks)
