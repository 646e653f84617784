"""Simulation of the system top as a scan head, a laser and a host see it.

Each run builds :class:`~galvoscan.gateware.top.GalvoScanTop`, drives its pins the way a host
does and decodes the XY2-100 wires the way a scan head does:

* :func:`replay_spiral` — the spiral from power-up, frame by frame;
* :func:`replay_job` — a vector job sent through the SPI pins, with the laser pulses counted on
  the DB25 pins and given to the point the head held;
* :class:`XY2Receiver` — the head's decoder, usable on any sampled wires;
* :class:`Timed` and :func:`spi_transfer` — a clock counter beside a design, and one SPI frame
  into its pins;
* :func:`write_csv`, :func:`plot_path`, :func:`plot_job` — what the CLI writes.

The simulated board a host talks to is :mod:`.board`; it runs on either backend behind the
contract of :mod:`.contract`: Amaranth's simulator (:mod:`.board_engine`) or the compiled model
(:mod:`.compiled`, with the C++ board and I/O cell models it compiles in).
"""

from .link import Timed, spi_transfer
from .plots import plot_job, plot_path
from .spiral import SIM_CLOCKS_PER_BIT, replay_spiral, write_csv
from .vector import JobResult, replay_job
from .xy2_receiver import XY2Frame, XY2ProtocolError, XY2Receiver


__all__ = ["SIM_CLOCKS_PER_BIT", "replay_spiral", "write_csv", "plot_path", "plot_job",
           "JobResult", "replay_job", "Timed", "spi_transfer",
           "XY2Frame", "XY2Receiver", "XY2ProtocolError"]
