"""The serial number a job marks (``{serial}`` in ``--text`` and ``--data``): a counter kept
beside the machine profile, advanced only when a part has been marked to its end.

The counter is a small TOML file, ``next = N`` and ``step = K``, named after the profile
(``galvoscan.toml`` → ``galvoscan.serial.toml``; the default profile's in the working folder).
It is written whole to a new file and moved over the old, so a crash mid-write leaves the old
number, never a torn one; a part that stops early (a fault, Ctrl-C) does not advance it.
"""

import os
from dataclasses import dataclass
from pathlib import Path
import string

try:
    import tomllib  # novermin: tomli below where it is missing
except ModuleNotFoundError:                      # Python < 3.11
    import tomli as tomllib

from ..geometry.field import PlanError


__all__ = ["SerialCounter", "counter_path", "load_counter", "uses_serial"]


#: Serial numbers run from 0 to this (a marked number of at most twelve digits).
MAX_SERIAL = 10 ** 12 - 1


def uses_serial(*texts):
    """Whether any of ``texts`` holds a ``{serial}`` field."""
    for text in texts:
        if text:
            try:
                if any(field and field.split(".")[0].split("[")[0] == "serial"
                       for _, field, _, _ in string.Formatter().parse(text)):
                    return True
            except ValueError:          # unbalanced braces: format() says so later
                return False
    return False


def counter_path(profile_source):
    """The counter file beside the profile at ``profile_source`` (None: ./galvoscan.toml's)."""
    source = Path(profile_source) if profile_source else Path("galvoscan.toml")
    return source.with_name(source.stem + ".serial.toml")


@dataclass
class SerialCounter:
    """The next serial number and the step between parts, and where they are kept."""
    path: Path
    next: int = 1
    step: int = 1

    def numbers(self, parts):
        """The serials of the next ``parts`` parts (none is taken until it is marked)."""
        numbers = [self.next + k * self.step for k in range(parts)]
        if max(numbers) > MAX_SERIAL or min(numbers) < 0:
            raise PlanError(f"serials {numbers[0]} … {numbers[-1]} leave 0 … {MAX_SERIAL}")
        return numbers

    def check_writable(self):
        """Refuse (one line) a counter that could not be kept, before any part is marked: a
        number taken and not kept would be marked again on the next part."""
        try:
            if self.path.exists():
                with open(self.path, "a", encoding="utf-8"):
                    pass
            else:
                scratch = self.path.with_name(self.path.name + ".new")
                scratch.write_text("", encoding="utf-8")
                scratch.unlink()
        except OSError as error:
            raise PlanError(f"{self.path}: the serial counter cannot be written "
                            f"({error.strerror or error}): nothing was sent") from None

    def advance(self):
        """One part marked to its end: the next number is taken, and kept."""
        self.next += self.step
        text = f"# galvoscan's serial counter: the next part's number\nnext = {self.next}\n" \
               f"step = {self.step}\n"
        scratch = self.path.with_name(self.path.name + ".new")
        try:
            scratch.write_text(text, encoding="utf-8")
            os.replace(scratch, self.path)
        except OSError as error:
            raise PlanError(f"{self.path}: the part was marked, but the counter could not be "
                            f"written ({error.strerror or error}): the next is {self.next}; "
                            f"give --serial-start {self.next}") from None


def load_counter(profile_source, *, start=None, step=None):
    """The counter beside the profile (``start``/``step``: the command line's, which replace
    the kept ones); one line (:class:`~galvoscan.geometry.field.PlanError`) for a damaged file."""
    path = counter_path(profile_source)
    kept = {}
    if path.exists():
        try:
            kept = tomllib.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
            raise PlanError(f"{path}: not a serial counter ({' '.join(str(error).split())}); "
                            f"fix it or remove it (then --serial-start N)") from None
    unknown = set(kept) - {"next", "step"}
    if unknown:
        raise PlanError(f"{path}: unknown key {sorted(unknown)[0]!r} (it keeps next and step)")
    values = {"next": kept.get("next", 1) if start is None else start,
              "step": kept.get("step", 1) if step is None else step}
    for key, value in values.items():
        if isinstance(value, bool) or not isinstance(value, int) or \
                not (0 if key == "next" else 1) <= value <= MAX_SERIAL:
            raise PlanError(f"{path}: {key} = {value!r} is not a whole number from "
                            f"{0 if key == 'next' else 1} to {MAX_SERIAL}")
    return SerialCounter(path=path, **values)
