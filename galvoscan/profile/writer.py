"""A machine profile changed a key at a time and written back, its comments and layout kept:
:class:`ProfileDocument`.

The file is held as `tomlkit <https://tomlkit.readthedocs.io>`_ holds TOML: every comment,
blank line and key in its place, so that a key changed here is the only line that differs when
it is written back (``galvoscan machine init``'s comments explain every key; a person's own
notes are kept too). Each change is checked by galvoscan's own profile reader
(:func:`~galvoscan.profile.machine.parse_profile`, the one ``--machine`` and the meerk40t
device read a file with): a bad value, or one that does not agree with another key (a default
PRR outside the laser's range), is a :class:`~galvoscan.profile.keys.ProfileError` of one line,
and the document is left as it was. Nothing is written until :meth:`ProfileDocument.save` is
called.

A value as a person types it (:meth:`ProfileDocument.set_text`) is read as a TOML value, as the
file would hold it: ``70``, ``0.05``, ``true``, ``[20, 80]``, ``"/dev/ttyUSB1"``; a text or
path key takes a word without quotes too (``/dev/ttyUSB1``).
"""

import contextlib
import os
import tempfile
from pathlib import Path

try:
    import tomllib  # novermin: tomli below where it is missing
except ModuleNotFoundError:                      # Python < 3.11
    import tomli as tomllib

import tomlkit
from tomlkit.exceptions import TOMLKitError

from .keys import SECTIONS, ProfileError, _num, _shown, _unknown_key, _unknown_section
from .machine import DEFAULT_PROFILE_NAME, parse_profile, read_profile_text
from .template import profile_text


__all__ = ["ProfileDocument", "profile_key"]


def profile_key(name):
    """The :class:`~galvoscan.settings.schema.ProfileKey` that ``name`` (``section.key``, as
    ``laser.prr_khz``) names; a :class:`ProfileError` (one line, the nearest name suggested)
    if there is none."""
    section, dot, key = str(name).partition(".")
    if not dot:
        raise ProfileError(f"{_shown(name, bare=True)}: a key is named with its section, as "
                           f"laser.prr_khz or field.size_mm")
    if section not in SECTIONS:
        raise _unknown_section(section, {}, "the profile")
    found = {k.name: k for k in SECTIONS[section]}.get(key)
    if found is None:
        raise _unknown_key(key, section, "the profile")
    return found


class ProfileDocument:
    """A machine profile's TOML text, held with its comments, changed a key at a time.

    Parameters
    ----------
    text : str
        The profile as its file holds it.
    path : path
        Where it is from (or is to be written): what messages name, and what a relative
        ``[field] correction`` is relative to.

    Attributes
    ----------
    profile : :class:`~galvoscan.profile.machine.MachineProfile`
        The profile the text is, checked; after each change, the changed one.
    path : :class:`~pathlib.Path`
    changed : bool
        A key was set since the text was read or last saved.
    """

    def __init__(self, text, path=DEFAULT_PROFILE_NAME):
        self.path = Path(path)
        self.profile = parse_profile(text, path=self.path)
        try:
            self._document = tomlkit.parse(text)
        except TOMLKitError as error:      # (what tomllib reads, tomlkit should too)
            raise ProfileError(f"{self.path}: not valid TOML: "
                               f"{' '.join(str(error).split())}") from None
        self.changed = False

    @classmethod
    def load(cls, path):
        """The profile file at ``path``."""
        return cls(read_profile_text(path), path)

    @classmethod
    def default(cls, path=DEFAULT_PROFILE_NAME):
        """The default profile as ``galvoscan machine init`` writes it, to be saved at
        ``path``."""
        return cls(profile_text(), path)

    def text(self):
        """The profile's TOML text now, comments and all."""
        return tomlkit.dumps(self._document)

    def value(self, name):
        """``section.key``'s value in the profile in use (its default if the file leaves it
        out)."""
        key = profile_key(name)
        return getattr(getattr(self.profile, key.section), key.name)

    def value_text(self, name):
        """``section.key``'s value in the profile in use as the file writes it (``110``,
        ``[20, 200]``, ``true``, ``"/dev/ttyUSB1"``); ``none`` for a key with no value."""
        value = self.value(name)
        if value is None:
            return "none"
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, (int, float)):
            return _num(value)
        if isinstance(value, tuple):
            return "[" + ", ".join(_num(v) for v in value) + "]"
        return tomlkit.item(str(value)).as_string()

    def set(self, name, value):
        """Set ``section.key`` to ``value`` (as TOML holds it: a number, a bool, a string, a
        list), checked by the profile reader with every other key; a ProfileError (one line)
        leaves the document as it was."""
        key = profile_key(name)
        document = tomlkit.parse(self.text())          # a copy: changed only if it reads
        if key.section not in document:
            document.add(key.section, tomlkit.table())
        table = document[key.section]
        try:
            item = tomlkit.item(value)
        except (TOMLKitError, TypeError, ValueError):
            raise ProfileError(f"[{key.section}] {key.name}: {_shown(value)} is not a value a "
                               f"profile holds") from None
        old = table.get(key.name)
        if old is not None and hasattr(old, "trivia"):
            # The comment on its line stays with it.
            item.trivia.comment_ws = old.trivia.comment_ws
            item.trivia.comment = old.trivia.comment
        table[key.name] = item
        text = tomlkit.dumps(document)
        self.profile = parse_profile(text, path=self.path)
        self._document = document
        self.changed = True

    def set_text(self, name, text):
        """Set ``section.key`` to ``text`` as a person types it: a TOML value (``70``,
        ``true``, ``[20, 80]``, ``"COM3"``), or for a text or path key a word without
        quotes (anything else that is not TOML is refused as the key's reader refuses
        text)."""
        text = str(text).strip()
        try:
            value = tomllib.loads(f"value = {text}")["value"]
        except tomllib.TOMLDecodeError:
            value = text            # (a word: a text key's, or refused as the key's kind)
        self.set(name, value)

    def save(self, path=None):
        """Write the text to ``path`` (None: where it was read from), checked first as the
        profile it is there (a relative correction table must be found from that folder);
        then the document is that file's. Written whole or not at all."""
        path = self.path if path is None else Path(path)
        text = self.text()
        profile = parse_profile(text, path=path)
        folder = path.parent if str(path.parent) else Path(".")
        try:
            mode = path.stat().st_mode & 0o777 if path.exists() else 0o644
            handle, temporary = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.",
                                                 suffix=".tmp")
        except OSError as error:
            raise ProfileError(f"{path}: cannot write it: {error.strerror or error}") \
                from None
        try:
            with os.fdopen(handle, "w", encoding="utf-8", newline="") as file:
                file.write(text)
            os.chmod(temporary, mode)
            os.replace(temporary, path)
        except OSError as error:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
            raise ProfileError(f"{path}: cannot write it: {error.strerror or error}") \
                from None
        self.path, self.profile, self.changed = path, profile, False
