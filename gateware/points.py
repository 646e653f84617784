"""Payload layouts of the point streams between blocks.

Two coordinate systems flow through the design:

* **Offsets** come out of the position sources: signed 16-bit, 0 is the field centre, ±32767
  is the full half-field. They are dimensionless until scaled.
* **Field positions** go into the XY2-100 PHY: unsigned 16-bit galvo units, offset binary as
  on the wire, 32768 is the field centre. On a 110 mm field one unit is ≈ 1.68 µm.
"""

from amaranth.hdl import signed, unsigned
from amaranth.lib import data


__all__ = ["OffsetPoint", "FieldPoint", "FIELD_CENTRE", "FIELD_MAX"]


#: Centre of the field in galvo units; where the mirrors park.
FIELD_CENTRE = 0x8000
#: Largest galvo position.
FIELD_MAX = 0xFFFF


#: A point relative to the field centre, as position sources produce it.
OffsetPoint = data.StructLayout({"x": signed(16), "y": signed(16)})

#: An absolute point in galvo units, as the XY2-100 PHY sends it.
FieldPoint = data.StructLayout({"x": unsigned(16), "y": unsigned(16)})
