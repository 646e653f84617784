"""Vector job files: one segment a line, ``jump X Y`` or ``mark X Y`` in galvo units.

Blank lines and everything after ``#`` are ignored. X and Y are integers in the range of the
``vec_x`` / ``vec_y`` registers (0 … 65535, 32768 is the field centre), decimal or with a ``0x``
prefix.
"""

from ..gateware.host.regmap import BY_NAME, VectorOp


__all__ = ["JobError", "parse_job", "OPS"]


#: The ``vec_op`` value of each command word.
OPS = {op.label: op for op in VectorOp}


class JobError(ValueError):
    """A job file that cannot be run; the message names the line."""


def parse_job(text, *, name="job"):
    """The segments of a job file: a list of ``(op, x, y)`` with ``op`` "jump" or "mark"."""
    segments = []
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        where = f"{name}, line {number}"
        op = words[0].lower()
        if op not in OPS:
            raise JobError(f"{where}: unknown command {words[0]!r} (jump or mark)")
        if len(words) != 3:
            raise JobError(f"{where}: {op} takes X and Y, not {len(words) - 1} values")
        coordinates = []
        for word in words[1:]:
            try:
                value = int(word, 0)
            except ValueError:
                raise JobError(f"{where}: {word!r} is not an integer") from None
            reg = BY_NAME["vec_x"]              # vec_y has the same range
            if not reg.low <= value <= reg.high:
                raise JobError(f"{where}: {value} is outside {reg.low} … {reg.high} galvo units")
            coordinates.append(value)
        segments.append((op, *coordinates))
    if not segments:
        raise JobError(f"{name}: no segments")
    return segments
