"""galvoscan as a meerk40t device (``pip install 'galvoscan[meerk40t]'``): meerk40t's planned
cutcode marked through galvoscan's planner (:mod:`galvoscan.api`) on a galvoscan board or the
simulated one. :mod:`.plugin` is what meerk40t's ``meerk40t.extension`` entry point loads."""
