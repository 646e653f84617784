"""Readers: what a user gives, made into :class:`~galvoscan.geometry.drawing.Drawing` s (or
segments) in mm, every fault one line.

- :mod:`.drawings`: :func:`~.drawings.load_drawing`, SVG, DXF or G-code by suffix, the checks
  they share;
- :mod:`.svg` (with :mod:`.svg_screen`, which screens a file first), :mod:`.dxf` and
  :mod:`.gcode` (a layer for each S and F): the formats; :mod:`.reading`: the chord limits
  and wording the readers share;
- :mod:`.text`: outline and Hershey fonts; :mod:`.codes`: QR, DataMatrix, Code 128;
  :mod:`.photo`: dithered photos; :mod:`.serial`: the serial-number counter;
- :mod:`.job_file`: ``.job`` files of segments in galvo units.
"""
