"""galvoscan's settings, each declared once with its name, kind, unit, range, default and help
(:mod:`.schema`), and the ones a job is marked at (:mod:`.laser`). The command line, job files,
layers, the machine profile and the docs' tables derive from them; this package imports nothing
from :mod:`galvoscan.cli`."""
