"""Geometry in field mm, below every reader and planner.

- :mod:`.drawing`: :class:`~.drawing.Drawing` (polylines in mm, Y up), its path styles and error;
- :mod:`.field`: placement in the field, field mm and galvo units, the field check,
  :class:`~.field.PlanError`;
- :mod:`.hatch`: even-odd hatch lines; :mod:`.fill`: hatch sets, line orders, contours;
- :mod:`.order`: path order that cuts jumps; :mod:`.corners`: corner dwell frames;
- :mod:`.speed`: pitch and pulses per point for a speed, and a job's time.
"""
