"""What stops a flash write: :class:`FlashingError`, raised by every part of the writer (the
bitstream checks, the boards' USB, the JTAG, the flash) and said by ``galvoscan flash`` in one
line; and the one line for a dependency pip did not install."""


__all__ = ["FlashingError", "missing_dependency"]


class FlashingError(Exception):
    """What stops a write, in one line."""


def missing_dependency(error):
    """The one line for ``error``, an :class:`ImportError` of a package the writer needs."""
    return f"flashing needs {error.name} (pip install galvoscan installs it)"
