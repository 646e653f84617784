"""Jobs on a machine, in user units (mm, mm/s, %, kHz).

- :mod:`.profile` (with :mod:`.profile_keys`, :mod:`.profile_template`): the machine profile,
  what a job needs that the board's registers do not hold;
- :mod:`.drawing`: SVG and DXF drawings read into paths in mm (the DXF reader in :mod:`.dxf`);
- :mod:`.plan`: placement in the field, hatching, path order; :mod:`.speed`: pitch and pulses
  per point, time (re-exported by :mod:`.plan`);
- :mod:`.vector_job`: a drawing (or a ``.job``) made into checked vector segments and register
  values for one machine; :mod:`.area`: a cleaning job (spiral or raster over a rectangle);
- :mod:`.preview`: the preview picture;
- :mod:`.stream`: running a job on a board over the host link, safely to its end.

Nothing heavy is imported here: import the submodule you need.
"""
