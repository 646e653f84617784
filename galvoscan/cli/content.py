"""The content ``mark`` and ``store`` make themselves, beside or instead of a drawing: text
(``--text``), codes (``--code``) and photos (``--image``), each a :class:`~galvoscan.plan.objects.MarkObject` of
the job."""

from dataclasses import replace
from datetime import datetime
import argparse

from ..geometry.drawing import DrawingError
from ..geometry.field import Placement, PlanError
from ..geometry.fill import HatchSet
from ..inputs.codes import CodeFill, CodeKind, CodeSpec, QR_LEVELS
from ..inputs.photo import Dither, PhotoSpec
from ..inputs.serial import load_counter, uses_serial
from ..inputs.text import ALIGNMENTS, text_drawing, TextSpec
from ..plan.objects import code_object, MarkObject, photo_object
from .args import int_in, number_in
from .jobargs import pair_mm


__all__ = ["add_content_options", "check_content_options", "content_objects", "has_content",
           "fields", "part_serials"]


def add_content_options(parser):
    text = parser.add_argument_group(
        "text (TrueType/OpenType outlines, filled; or Hershey single-line fonts)")
    text.add_argument("--text", metavar="TEXT",
                      help="mark this text (\\n starts a new line; {date:%%Y-%%m-%%d} and "
                           "{time:%%H:%%M} are the time of marking)")
    text.add_argument("--font", metavar="NAME|FILE",
                      help="a font family (default: DejaVu Sans), a .ttf/.otf file, or "
                           "hershey[:NAME] for a single-line font (futural, scripts, "
                           "timesr, …)")
    text.add_argument("--height", type=number_in("height", 0.1, 500), default=None,
                      metavar="MM", help="capital height, mm (default: 5)")
    text.add_argument("--text-at", type=pair_mm("--text-at"), default=(0.0, 0.0),
                      metavar="X,Y", help="where the first line's baseline starts (left), is "
                                          "centred (centre) or ends (right), field mm "
                                          "(default: 0,0; a negative X as --text-at=-5,2)")
    text.add_argument("--align", choices=[*ALIGNMENTS, "center"], default="left",
                      help="each line's left end, centre or right end at --text-at")
    text.add_argument("--letter-spacing", type=number_in("letter spacing", -100, 1000),
                      default=0.0, metavar="MM", help="added between letters, mm (default 0: "
                                                      "the font's own, kerning kept)")
    text.add_argument("--line-height", type=number_in("line height", 0.5, 10), default=1.4,
                      metavar="K", help="baseline to baseline, times the height (default 1.4)")
    serial = parser.add_argument_group(
        "serial numbers ({serial} in --text and --data, e.g. {serial:04d}; kept beside the "
        "machine profile, advanced only when a part has been marked to its end)")
    serial.add_argument("--serial-start", type=int_in(0, 10 ** 12 - 1, "serial start"),
                        default=None, metavar="N", help="the next part's number (replaces the "
                                                        "kept one)")
    serial.add_argument("--serial-step", type=int_in(1, 10 ** 6, "serial step"), default=None,
                        metavar="K", help="added for each part (default: the kept one, 1)")
    serial.add_argument("--repeat", type=int_in(1, 100_000, "repeat"), default=1, metavar="N",
                        help="mark N parts one after the other, the serial advancing each "
                             "time (default 1)")
    code = parser.add_argument_group(
        "codes (QR, DataMatrix, Code 128, made by zxing-cpp; with FILE or alone)")
    code.add_argument("--code", choices=[kind.value for kind in CodeKind],
                      help="mark a code of --data, --size mm wide")
    code.add_argument("--data", metavar="TEXT", help="what the code holds")
    code.add_argument("--size", type=number_in("size", 0.5, 500), metavar="MM",
                      help="the code's width, mm, its quiet zone outside it")
    code.add_argument("--code-at", type=pair_mm("--code-at"), default=(0.0, 0.0),
                      metavar="X,Y", help="the code's centre, field mm (default: 0,0; a "
                                          "negative X as --code-at=-5,2)")
    code.add_argument("--code-ec", choices=QR_LEVELS, default=None,
                      help="QR error correction: L, M (default), Q or H (7 to 30 %% of the "
                           "symbol may be lost)")
    code.add_argument("--code-fill", choices=[fill.value for fill in CodeFill],
                      default=CodeFill.HATCH.value,
                      help="dark modules filled (outline and lines along the rows at most half "
                           "the spot apart; default) or marked as dots, one at each module's "
                           "centre")
    code.add_argument("--code-quiet", type=int_in(0, 100, "quiet zone"), default=None,
                      metavar="MODULES", help="modules kept clear around the code (default: "
                                              "the symbology's: QR 4, DataMatrix 1, Code 128 "
                                              "10)")
    code.add_argument("--code-height", type=number_in("bar height", 0.5, 500), metavar="MM",
                      help="Code 128's bar height, mm (default: a quarter of its width)")


    image = parser.add_argument_group(
        "images (PNG, JPEG: engraved as dithered scan lines, each run of dark pixels a mark)")
    image.add_argument("--image", metavar="FILE", help="engrave this picture, --width mm wide")
    image.add_argument("--width", type=number_in("width", 0.1, 1000), metavar="MM",
                       help="the picture's width, mm (its height by its aspect)")
    image.add_argument("--dither", choices=[d.value for d in Dither], default=None,
                       help="grey as dark and light cells: floyd (Floyd-Steinberg, the "
                            "default), ordered (a Bayer screen) or threshold (none: line art)")
    image.add_argument("--line-spacing", type=number_in("line spacing", 0.001, 10),
                       default=None, metavar="MM", help="scan line spacing and cell width, mm "
                                                        "(default: the spot's diameter)")
    image.add_argument("--image-at", type=pair_mm("--image-at"), default=None, metavar="X,Y",
                       help="the picture's centre, field mm (default: 0,0; a negative X as "
                            "--image-at=-5,2)")
    image.add_argument("--one-way", action="store_true",
                       help="every scan line left to right (default: each the other way from "
                            "the last)")


#: The options of each kind of content, past the one that asks for it.
_OPTIONS = {"text": ("font", "height"),
            "code": ("data", "size", "code_ec", "code_quiet", "code_height"),
            "image": ("width", "dither", "line_spacing", "image_at")}


def has_content(args):
    return any(getattr(args, kind, None) is not None for kind in _OPTIONS)


class _Moment:
    """The time of marking as a field: ``{date:%d.%m.%Y}`` its strftime; bare ``{date}`` the
    ISO date, ``{time}`` hours and minutes (not Python's microseconds)."""

    def __init__(self, now, plain):
        self.now, self.plain = now, plain

    def __format__(self, spec):
        return self.now.strftime(spec or self.plain)


def fields(text, *, serial=None, what="--text"):
    """``text`` with its fields filled: ``{serial}`` (``serial``), ``{date:…}``, ``{time:…}``
    (now); one line (:class:`~galvoscan.geometry.field.PlanError`) for a field it does not know
    or one written wrong."""
    now = datetime.now()
    values = {"serial": serial if serial is not None else 0,
              "date": _Moment(now, "%Y-%m-%d"), "time": _Moment(now, "%H:%M")}
    known = "{serial}, {serial:05d}, {date}, {date:%d.%m.%Y}, {time}, {time:%H:%M:%S}"
    try:
        return text.replace("\\n", "\n").format(**values)
    except (KeyError, IndexError, AttributeError) as error:
        raise PlanError(f"{what} {text!r}: {{{' '.join(str(error).split()).strip(chr(39))}}} "
                        f"is not a field galvoscan knows ({known}; a brace itself as {{{{ "
                        f"or }}}})") from None
    except ValueError as error:
        raise PlanError(f"{what} {text!r}: a field written wrong ({' '.join(str(error).split())}"
                        f"); fields are {known}, a brace itself {{{{ or }}}}") from None


def check_content_options(args):
    """Refuse an option of one kind of content given without it (``--font`` without
    ``--text``); one line (:class:`~galvoscan.geometry.field.PlanError`)."""
    for kind, options in _OPTIONS.items():
        given = [name for name in options if getattr(args, name, None) is not None]
        if getattr(args, kind, None) is None and given:
            raise PlanError(f"--{given[0].replace('_', '-')} is for --{kind}")
    if getattr(args, "one_way", False) and args.image is None:
        raise PlanError("--one-way is for --image")


def content_objects(args, settings, profile, *, serial=None):
    """The :class:`~galvoscan.plan.objects.MarkObject` s of ``args.entries``' text, codes
    and photos (each entry the options of one object, over ``args``' own), ``serial`` the
    part's number (raises :class:`~galvoscan.geometry.field.PlanError`, one line)."""
    objects = []
    for kind, make in (("text", _text_object), ("image", _image_object),
                       ("code", _code_object)):
        for entry in args.entries.get(kind, ()):
            one = argparse.Namespace(**{**vars(args), **entry})
            try:
                made = make(one, settings, profile, serial)
            except (PlanError, DrawingError) as error:
                if not entry.get("_where"):
                    raise
                raise PlanError(f"{entry['_where']}: {error}") from None
            objects.append(replace(made, layer=entry["layer"]) if entry.get("layer") else made)
    return objects


def _code_object(args, settings, profile, serial):
    """``--code`` as a :class:`~galvoscan.plan.objects.MarkObject`."""
    if args.data is None or args.size is None:
        raise PlanError("--code needs --data TEXT and --size MM")
    if args.code_height is not None and CodeKind(args.code) is not CodeKind.CODE128:
        raise PlanError(f"--code-height is Code 128's bar height: a {args.code} code is "
                        f"--size wide and as high")
    spec = CodeSpec(CodeKind(args.code), fields(args.data, serial=serial, what="--data"),
                    args.size, ec_level=args.code_ec,
                    fill=CodeFill(args.code_fill), quiet_modules=args.code_quiet,
                    height_mm=args.code_height)
    return code_object(spec, settings, centre_mm=args.code_at, spot_mm=profile.laser.spot_mm)


def _image_object(args, settings, profile, serial=None):
    """``--image`` as a :class:`~galvoscan.plan.objects.MarkObject`."""
    if args.width is None:
        raise PlanError("--image needs --width MM")
    spec = PhotoSpec(args.image, args.width, args.line_spacing or profile.laser.spot_mm,
                     dither=Dither(args.dither or Dither.FLOYD.value),
                     bidirectional=not args.one_way)
    return photo_object(spec, settings, centre_mm=tuple(args.image_at or (0.0, 0.0)))


def _text_object(args, settings, profile, serial):
    """``--text`` as a :class:`~galvoscan.plan.objects.MarkObject`: an outline font's
    glyphs filled by the job's hatch sets (or, none given, lines at most half the spot apart)
    and outlined; a Hershey font's strokes marked once."""
    text = fields(args.text, serial=serial)
    spec = TextSpec(text, args.height or 5.0, font=args.font, align=args.align,
                    letter_spacing_mm=args.letter_spacing, line_spacing=args.line_height)
    drawing = text_drawing(spec, tolerance_mm=getattr(args, "tolerance", 0.01))
    if spec.hershey:
        fill = replace(settings, hatch=(), contour=None, outline=True)
    else:
        fill = settings if settings.hatch or settings.contour else replace(
            settings, hatch=(HatchSet(profile.laser.spot_mm / 2),), outline=True)
    return MarkObject(drawing, Placement(origin="page", offset_mm=tuple(args.text_at)), fill,
                      own_fill=bool(spec.hershey))   # single strokes: the lines themselves


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

