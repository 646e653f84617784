"""What a transport (SPI, UART) hands the command decoder: one event per attempted frame."""

from amaranth.lib import data


__all__ = ["CommandFrame", "FRAME_BITS", "BROKEN"]


#: Bits in a complete command frame.
FRAME_BITS = 32
#: ``bits`` value of a frame spoilt by a line error (a UART byte with a bad stop bit).
BROKEN = 63

#: The bits received, most significant first in ``word``, and how many there were: 32 for a
#: complete frame, fewer when it was cut short, more (up to 33) when it ran over, ``BROKEN``
#: when a line error spoilt it. Only complete frames are decoded.
CommandFrame = data.StructLayout({"word": 32, "bits": 6})
