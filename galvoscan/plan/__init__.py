"""Planning: drawings made into jobs for one machine.

- :mod:`.objects`: a job's settings, the objects it marks (a code's, a photo's);
- :mod:`.vector_job`: objects placed, hatched, ordered, in galvo units, checked and timed;
- :mod:`.layers`: settings of their own for parts of a drawing, :mod:`.layer_keys` the keys a
  layer is given them by (and ``mark``'s fill options read by); :mod:`.wobble`: wobble registers;
- :mod:`.area`: a cleaning job (spiral or raster over a rectangle);
- :mod:`.test_grid`: the speed × power test grid; :mod:`.preview`: the preview picture.
"""
