"""The content ``mark`` and ``store`` make themselves, beside or instead of a drawing: text
(``--text``), codes (``--code``) and photos (``--image``), each a :class:`~galvoscan.plan.objects.MarkObject` of
the job."""

from ..api import Code, Photo, Text, fields, mark_object
from ..inputs.codes import CodeKind
from ..geometry.drawing import DrawingError
from ..inputs.photo import Dither
from ..geometry.field import PlanError
from ..inputs.serial import load_counter, uses_serial
from ..plan.pixel_lines import PHOTO_LINES


__all__ = ["check_content_options", "content_objects", "content_item",
           "has_content", "fields", "part_serials"]


#: The options of each kind of content, past the one that asks for it.
_OPTIONS = {"text": ("font", "height"),
            "code": ("data", "size", "code_ec", "code_quiet", "code_height"),
            "image": ("width", "dither", "line_spacing", "image_at", "image_lines")}


def has_content(args):
    return any(getattr(args, kind, None) is not None for kind in _OPTIONS)


def check_content_options(args):
    """Refuse an option of one kind of content given without it (``--font`` without
    ``--text``); one line (:class:`~galvoscan.geometry.field.PlanError`)."""
    for kind, options in _OPTIONS.items():
        given = [name for name in options if getattr(args, name, None) is not None]
        if getattr(args, kind, None) is None and given:
            raise PlanError(f"--{given[0].replace('_', '-')} is for --{kind}")
    if getattr(args, "one_way", False) and args.image is None:
        raise PlanError("--one-way is for --image")


def content_item(kind, one):
    """An entry's options (``one``: the command line's, a job file's table over them) as the
    API's :class:`~galvoscan.api.Text`, :class:`~galvoscan.api.Photo` or
    :class:`~galvoscan.api.Code`; one line for what the command line gives incompletely."""
    layer = one.get("layer") or None
    if kind == "text":
        return Text(one["text"], **({} if one.get("height") is None else
                                    {"height_mm": one["height"]}),
                    at_mm=tuple(one["text_at"]), font=one["font"], align=one["align"],
                    letter_spacing_mm=one["letter_spacing"], line_height=one["line_height"],
                    layer=layer)
    if kind == "image":
        if one.get("width") is None:
            raise PlanError("--image needs --width MM")
        return Photo(one["image"], one["width"], at_mm=tuple(one.get("image_at") or (0, 0)),
                     dither=one.get("dither") or Dither.FLOYD.value,
                     line_spacing_mm=one.get("line_spacing"), one_way=bool(one.get("one_way")),
                     lines=one.get("image_lines") or PHOTO_LINES[0], layer=layer)
    if one.get("data") is None or one.get("size") is None:
        raise PlanError("--code needs --data TEXT and --size MM")
    if one.get("code_height") is not None and CodeKind(one["code"]) is not CodeKind.CODE128:
        raise PlanError(f"--code-height is Code 128's bar height: a {one['code']} code is "
                        f"--size wide and as high")
    return Code(one["code"], one["data"], one["size"], at_mm=tuple(one["code_at"]),
                ec=one.get("code_ec"), fill=one["code_fill"], quiet_modules=one.get("code_quiet"),
                height_mm=one.get("code_height"), layer=layer)


def content_objects(args, settings, profile, *, serial=None):
    """The :class:`~galvoscan.plan.objects.MarkObject` s of ``args.entries``' text, codes
    and photos (each entry the options of one object, over ``args``' own), ``serial`` the
    part's number (raises :class:`~galvoscan.geometry.field.PlanError`, one line): each made by
    the API (:func:`galvoscan.api.mark_object`)."""
    objects = []
    for kind in ("text", "image", "code"):
        for entry in args.entries.get(kind, ()):
            one = {**vars(args), **entry}
            try:
                objects.append(mark_object(content_item(kind, one), settings, profile,
                                           serial=serial,
                                           tolerance_mm=getattr(args, "tolerance", 0.01)))
            except (PlanError, DrawingError) as error:
                if not entry.get("_where"):
                    raise
                raise PlanError(f"{entry['_where']}: {error}") from None
    return objects


def part_serials(args, profile):
    """``(counter, serials)``: the serial counter and each part's number, when ``--text`` or
    ``--data`` holds ``{serial}`` (else ``(None, [None] × parts)``); one line for a damaged
    counter."""
    parts = getattr(args, "repeat", 1) or 1
    entries = getattr(args, "entries", None)
    texts = [getattr(args, "text", None), getattr(args, "data", None)] if entries is None else \
        [e.get("text") for e in entries["text"]] + [e.get("data") for e in entries["code"]]
    if not uses_serial(*texts):
        if getattr(args, "serial_start", None) is not None or \
                getattr(args, "serial_step", None) is not None:
            raise PlanError("--serial-start and --serial-step are for a {serial} field in "
                            "--text or --data")
        return None, [None] * parts
    counter = load_counter(profile.source, start=args.serial_start, step=args.serial_step)
    return counter, counter.numbers(parts)

