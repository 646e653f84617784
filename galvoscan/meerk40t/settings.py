"""The machine profile's keys as the galvoscan device's settings in meerk40t, and what the
device's ``galvoscan_profile`` console command says of them.

Every key of galvoscan's one declaration of the profile (:data:`galvoscan.profile.keys.SECTIONS`:
its section, kind, unit, range and help) is a setting of meerk40t's (a "choice": what its
property panels show and set), named ``section_key`` (``field_size_mm``, ``laser_prr_khz``)
on a :class:`ProfileSettings`: read, the value in the profile in use; set, checked by
galvoscan's profile reader (:class:`~galvoscan.profile.writer.ProfileDocument`), a bad value one
line on meerk40t's console and the profile unchanged. The change is the device's at once and
the file's only when ``galvoscan_profile save`` writes it.
"""

from ..profile.keys import SECTIONS, _num
from ..profile.writer import profile_key


__all__ = ["ProfileSettings", "profile_choices", "key_line", "ATTRIBUTES"]

#: The setting each profile key is (``section_key``), and back.
ATTRIBUTES = {f"{key.section}_{key.name}": f"{key.section}.{key.name}"
              for keys in SECTIONS.values() for key in keys}

#: The type meerk40t shows a key of each kind as (a pair as text: ``20, 200``).
_TYPES = {"number": float, "integer": int, "bool": bool, "text": str, "path": str, "pair": str,
          "choice": str}


def _range(key):
    if key.kind not in ("number", "integer", "pair"):
        return ""
    unit = f" {key.unit}" if key.unit else ""
    return f"{_num(key.low)} … {_num(key.high)}{unit}"


class ProfileSettings:
    """The device's profile keys as attributes (``field_size_mm``) for meerk40t's settings:
    ``device`` holds the :class:`~galvoscan.profile.writer.ProfileDocument` and is told of
    each change (its ``set_profile_key``)."""

    def __init__(self, device):
        object.__setattr__(self, "_device", device)

    def __getattr__(self, attribute):
        name = ATTRIBUTES.get(attribute)
        if name is None:
            raise AttributeError(attribute)
        key = profile_key(name)
        value = self._device.profile_document.value(name)
        if key.kind == "pair":
            return ", ".join(_num(v) for v in value)
        if value is None:
            return ""
        return _TYPES[key.kind](value)

    def __setattr__(self, attribute, value):
        name = ATTRIBUTES.get(attribute)
        if name is None:
            raise AttributeError(attribute)
        key = profile_key(name)
        if key.kind == "pair":
            # As shown: "20, 200" (or as the file writes it, "[20, 200]").
            text = str(value).strip()
            self._device.set_profile_key(name, text if text.startswith("[") else f"[{text}]")
        else:
            self._device.set_profile_key(name, value, typed=True)


def profile_choices(settings, _):
    """meerk40t's choices (its settings' descriptions) for every profile key, on
    ``settings`` (a :class:`ProfileSettings`), a section of them a profile section."""
    choices = []
    for number, (section, keys) in enumerate(SECTIONS.items(), 1):
        for key in keys:
            span = _range(key)
            choices.append({
                "attr": f"{section}_{key.name}", "object": settings,
                "default": getattr(settings, f"{section}_{key.name}"),
                "type": _TYPES[key.kind],
                "label": f"{key.name}" + (f" ({key.unit})" if key.unit else ""),
                "tip": _(key.help) + (f" ({span})" if span else ""),
                "page": _("Machine profile"),
                "section": f"_{number:02d}_[{section}]",
            })
    return choices


def key_line(document, name):
    """One key as ``galvoscan_profile list`` says it: ``[field] size_mm = 110 (1 … 2000
    mm)``."""
    key = profile_key(name)
    span = _range(key)
    return f"[{key.section}] {key.name} = {document.value_text(name)}" + \
        (f" ({span})" if span else "")
