"""The machine profile (a TOML file): what a job needs to know about the machine that the
board's registers do not hold.

- :mod:`.keys`: every key, its unit, range and check, and :class:`~.keys.ProfileError`;
- :mod:`.machine`: :class:`~.machine.MachineProfile`, its sections and derived numbers,
  :func:`~.machine.load_profile`;
- :mod:`.template`: the commented file ``galvoscan machine init`` writes, from the defaults.
"""
