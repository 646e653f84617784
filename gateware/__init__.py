"""galvoscan gateware: reusable Amaranth cores, independent of any board.

Data flow (README "What it does")::

    sources/ (spiral …) ──▶ field/ (scale, offset, saturation) ──▶ phy/ (XY2-100) ──▶ galvos

`top.GalvoScanTop` wires them together with board-independent port names, as one
`build_config.BuildConfig` says (a build's options, their rules, its capabilities and
register map). Top-level modules below the top (`fields`, `limits`, `points`, `settings`,
`clocking`) are leaves the subpackages share; nothing below imports the top.
"""
