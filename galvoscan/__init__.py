"""galvoscan host side: command line, simulation replay, build and proof runners."""
