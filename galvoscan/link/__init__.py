"""The host link: :mod:`.client`, the host's side of the board's register protocol (frames,
CRC, answers, refusals) over a UART, an FTDI SPI adapter or the simulated board's pins; the leaf
everything that talks to a board sends through.

Layers, lowest first (``tests/test_layout.py`` holds them to it): :mod:`galvoscan.link` →
:mod:`galvoscan.profile` and :mod:`galvoscan.flashing` → :mod:`galvoscan.geometry` →
:mod:`galvoscan.inputs` → :mod:`galvoscan.plan` → :mod:`galvoscan.outputs` →
:mod:`galvoscan.sim`; the CLI above them all.
"""
