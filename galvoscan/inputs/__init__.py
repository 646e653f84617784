"""Readers: what a user gives, made into :class:`~galvoscan.geometry.drawing.Drawing` s (or
segments) in mm, every fault one line.

- :mod:`.drawings`: :func:`~.drawings.load_drawing`, SVG or DXF by suffix, the checks both share;
- :mod:`.svg` (with :mod:`.svg_screen`, which screens a file first) and :mod:`.dxf`: the two
  formats; :mod:`.reading`: the chord limits and wording both readers share;
- :mod:`.text`: outline and Hershey fonts; :mod:`.codes`: QR, DataMatrix, Code 128;
  :mod:`.photo`: dithered photos; :mod:`.serial`: the serial-number counter;
- :mod:`.job_file`: ``.job`` files of segments in galvo units.
"""
