"""Vector job files: one segment a line, ``jump X Y`` or ``mark X Y`` in galvo units.

Blank lines and everything after ``#`` are ignored. X and Y are integers 0 … 65535 (32768 is
the field centre), decimal or with a ``0x`` prefix.
"""

__all__ = ["JobError", "parse_job", "OPS"]


#: The ``vec_op`` value of each command.
OPS = {"jump": 0, "mark": 1}


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
            if not 0 <= value <= 0xFFFF:
                raise JobError(f"{where}: {value} is outside 0 … 65535 galvo units")
            coordinates.append(value)
        segments.append((op, *coordinates))
    if not segments:
        raise JobError(f"{name}: no segments")
    return segments
