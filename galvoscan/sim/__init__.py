"""Simulation of the system top as a scan head, a laser and a host see it.

Each run builds :class:`~galvoscan.gateware.top.GalvoScanTop`, drives its pins the way a host
does and decodes the XY2-100 wires the way a scan head does:

* :func:`.spiral.replay_spiral` — the spiral from power-up, frame by frame;
* :func:`.vector.replay_job` — a vector job sent through the SPI pins, with the laser pulses
  counted on the DB25 pins and given to the point the head held;
* :class:`.xy2_receiver.XY2Receiver` — the head's decoder, usable on any sampled wires;
* :class:`.link.Timed` and :func:`.link.spi_transfer` — a clock counter beside a design, and
  one SPI frame into its pins;
* :func:`.spiral.write_csv`, :func:`.plots.plot_path`, :func:`.plots.plot_job` — what the CLI
  writes.

The simulated board a host talks to is :mod:`.board`; it runs on either backend behind the
contract of :mod:`.contract`: Amaranth's simulator (:mod:`.board_engine`) or the compiled model
(:mod:`.compiled`, with the C++ board and I/O cell models it compiles in).

Nothing is imported here (the command line's parser reads :mod:`.contract` alone): import
the module you need.
"""
