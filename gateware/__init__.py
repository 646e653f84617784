"""galvoscan gateware: reusable Amaranth cores, independent of any board.

Data flow (README "What it does")::

    sources/ (spiral …) ──▶ field/ (scale, offset, saturation) ──▶ phy/ (XY2-100) ──▶ galvos

`top.GalvoScanTop` wires them together with board-independent port names.
"""
