"""``mark``'s and ``store``'s job options, declared once as a table (:data:`OPTIONS`): each
option's flag, its ``--help`` group, its argparse keywords (type, range, words, default,
help), and the job file's table and key it is saved under (:data:`SECTIONS`, derived).

``mark`` adds its arguments from this table (:func:`add_job_file_options`) and job files
(:mod:`.jobfile`) read each key with its option's own type, so a key's range, its words and
its one-line refusal are the option's. The job's shared settings (speed, power, PRR, passes,
wobble, tolerance) are :mod:`galvoscan.settings.laser`'s, its fill (hatch, hatch lines,
contour, outline) :mod:`galvoscan.plan.layer_keys`', which a layer's keys are read by too.
"""

from dataclasses import dataclass, field

from ..inputs.codes import QR_LEVELS, CodeFill, CodeKind
from ..inputs.drawings import SCALES, UNITS
from ..inputs.gcode import S_MAX, S_MAX_RANGE
from ..inputs.photo import Dither
from ..inputs.text import ALIGNMENTS
from ..plan.layer_keys import CONTOUR, HATCH, HATCH_LINES, LAYER_KEYS, OUTLINE
from ..plan.pixel_lines import PHOTO_LINES
from ..settings.fly import BELT_SPEED, ENCODER, FLY, FLY_DIRECTION, FLY_SPEED
from ..settings.io import IO_SETTINGS
from ..settings.sky import SKY_SETTINGS
from ..settings.laser import (PASSES, POWER, PRR, SPEED, TOLERANCE, WOBBLE, WOBBLE_ALONG,
                              WOBBLE_HZ, Z)
from .args import int_in, number_in, setting_keywords
from .jobargs import pair_mm
from .layers import LayerAction


__all__ = ["Option", "OPTIONS", "SECTIONS", "GROUPS", "add_job_file_options", "defaults",
           "job_file_table"]


#: The ``--help`` groups, in the order they are listed: id → (title; None: the parser's
#: own options).
GROUPS = {
    "file": None,
    "text": "text (TrueType/OpenType outlines, filled; or Hershey single-line fonts)",
    "serial": "serial numbers ({serial} in --text and --data, e.g. {serial:04d}; kept beside "
              "the machine profile, advanced only when a part has been marked to its end)",
    "code": "codes (QR, DataMatrix, Code 128, made by zxing-cpp; with FILE or alone)",
    "image": "images (PNG, JPEG: engraved as dithered scan lines, each run of dark pixels a "
             "mark)",
    "laser": "laser and speed (defaults: the machine profile's)",
    "passes": None,
    "drawing": "drawing",
    "wobble": "wobble (an ellipse laid over marked lines; needs a bitstream with the wobble "
              "stage; defaults: the profile's [wobble])",
    "placement": "placement",
    "fly": "marking on the fly (a belt carries the part through the field as it is marked; "
           "needs a bitstream with the fly: the ULX3S's; defaults: the profile's [fly])",
    "io": "I/O on a production line (each part waits in the board's queue for a part sensor, "
          "and an output tells a PLC it is done; needs a bitstream with I/O in the queue: the "
          "ULX3S's)",
    "sky": "SkyWriting (SCANLAB RTC's: each mark run in and out at its speed, laser off, the "
           "laser switched as the lagging mirrors cross its ends; needs a bitstream with "
           "pixel lines: the ULX3S's, build --preset engraver; defaults: the profile's [sky])",
}


@dataclass(frozen=True)
class Option:
    """One option: ``flag`` (None: the positional FILE), the ``group`` it is listed in, its
    ``argparse`` keywords, and, when a job file holds it, its ``section`` (``job``,
    ``drawing``, ``text``, ``code``, ``image``) and ``key`` there (default: its dest);
    ``inverted``: the key is the option's opposite (``outline = false`` is
    ``--no-outline``)."""
    flag: str
    group: str
    argparse: dict = field(default_factory=dict)
    section: str = None
    key: str = None

    inverted: bool = False

    @property
    def dest(self):
        return self.argparse.get("dest") or (self.flag or "file").lstrip("-").replace("-", "_")

    @property
    def default(self):
        """The value argparse gives it when the command line does not."""
        if self.argparse.get("action") == "store_true":
            return self.argparse.get("default", False)
        return self.argparse.get("default")

    @property
    def is_flag(self):
        """An option without a value (true or false in a job file)."""
        return self.argparse.get("action") == "store_true"


def _setting(setting, group, section):
    """The option of a :mod:`galvoscan.settings` setting: its flag, type, placeholder and
    help (unit, range, default)."""
    return Option(setting.flag, group, setting_keywords(setting), section=section,
                  key=setting.key)

#: Every job option, in ``--help``'s order.
OPTIONS = (
    Option(None, "file", dict(
        metavar="FILE", nargs="?",
        help="the drawing (.svg, .dxf, G-code: .gcode, .nc, …; or a .job in galvo units) or "
             "a job file (.toml, as --save writes); none, with --text, --code or --image"),
        section="drawing", key="file"),
    # text
    Option("--text", "text", dict(
        metavar="TEXT", help="mark this text (\\n starts a new line; {date:%%Y-%%m-%%d} and "
                             "{time:%%H:%%M} are the time of marking)"), section="text"),
    Option("--font", "text", dict(
        metavar="NAME|FILE", help="a font family (default: DejaVu Sans), a .ttf/.otf file, or "
                                  "hershey[:NAME] for a single-line font (futural, scripts, "
                                  "timesr, …)"), section="text"),
    Option("--height", "text", dict(
        type=number_in("height", 0.1, 500), default=None, metavar="MM",
        help="capital height, mm (default: 5)"), section="text"),
    Option("--text-at", "text", dict(
        type=pair_mm("--text-at"), default=(0.0, 0.0), metavar="X,Y",
        help="where the first line's baseline starts (left), is centred (centre) or ends "
             "(right), field mm (default: 0,0; a negative X as --text-at=-5,2)"),
        section="text", key="at"),
    Option("--align", "text", dict(
        choices=[*ALIGNMENTS, "center"], default="left",
        help="each line's left end, centre or right end at --text-at"), section="text"),
    Option("--letter-spacing", "text", dict(
        type=number_in("letter spacing", -100, 1000), default=0.0, metavar="MM",
        help="added between letters, mm (default 0: the font's own, kerning kept)"),
        section="text"),
    Option("--line-height", "text", dict(
        type=number_in("line height", 0.5, 10), default=1.4, metavar="K",
        help="baseline to baseline, times the height (default 1.4)"), section="text"),
    # serial numbers: a run's, not the job's
    Option("--serial-start", "serial", dict(
        type=int_in(0, 10 ** 12 - 1, "serial start"), default=None, metavar="N",
        help="the next part's number (replaces the kept one)")),
    Option("--serial-step", "serial", dict(
        type=int_in(1, 10 ** 6, "serial step"), default=None, metavar="K",
        help="added for each part (default: the kept one, 1)")),
    Option("--repeat", "serial", dict(
        type=int_in(1, 100_000, "repeat"), default=1, metavar="N",
        help="mark N parts one after the other, the serial advancing each time (default 1)")),
    # codes
    Option("--code", "code", dict(
        choices=[kind.value for kind in CodeKind], help="mark a code of --data, --size mm "
                                                        "wide"), section="code", key="kind"),
    Option("--data", "code", dict(metavar="TEXT", help="what the code holds"), section="code"),
    Option("--size", "code", dict(
        type=number_in("size", 0.5, 500), metavar="MM",
        help="the code's width, mm, its quiet zone outside it"), section="code"),
    Option("--code-at", "code", dict(
        type=pair_mm("--code-at"), default=(0.0, 0.0), metavar="X,Y",
        help="the code's centre, field mm (default: 0,0; a negative X as --code-at=-5,2)"),
        section="code", key="at"),
    Option("--code-ec", "code", dict(
        choices=QR_LEVELS, default=None,
        help="QR error correction: L, M (default), Q or H (7 to 30 %% of the symbol may be "
             "lost)"), section="code", key="ec"),
    Option("--code-fill", "code", dict(
        choices=[fill.value for fill in CodeFill], default=CodeFill.HATCH.value,
        help="dark modules filled (outline and lines along the rows at most half the spot "
             "apart; default) or marked as dots, one at each module's centre"),
        section="code", key="fill"),
    Option("--code-quiet", "code", dict(
        type=int_in(0, 100, "quiet zone"), default=None, metavar="MODULES",
        help="modules kept clear around the code (default: the symbology's: QR 4, "
             "DataMatrix 1, Code 128 10)"), section="code", key="quiet"),
    Option("--code-height", "code", dict(
        type=number_in("bar height", 0.5, 500), metavar="MM",
        help="Code 128's bar height, mm (default: a quarter of its width)"),
        section="code", key="height"),
    # photos
    Option("--image", "image", dict(metavar="FILE", help="engrave this picture, --width mm "
                                                         "wide"), section="image", key="file"),
    Option("--width", "image", dict(
        type=number_in("width", 0.1, 1000), metavar="MM",
        help="the picture's width, mm (its height by its aspect)"), section="image"),
    Option("--image-at", "image", dict(
        type=pair_mm("--image-at"), default=None, metavar="X,Y",
        help="the picture's centre, field mm (default: 0,0; a negative X as "
             "--image-at=-5,2)"), section="image", key="at"),
    Option("--dither", "image", dict(
        choices=[d.value for d in Dither], default=None,
        help="grey as dark and light cells: floyd (Floyd-Steinberg, the default), ordered (a "
             "Bayer screen) or threshold (none: line art)"), section="image"),
    Option("--line-spacing", "image", dict(
        type=number_in("line spacing", 0.001, 10), default=None, metavar="MM",
        help="scan line spacing and cell width, mm (default: the spot's diameter)"),
        section="image"),
    Option("--one-way", "image", dict(
        action="store_true", help="every scan line left to right (default: each the other "
                                  "way from the last)"), section="image"),
    Option("--image-lines", "image", dict(
        choices=list(PHOTO_LINES), default=None,
        help="how the picture is marked: pixels (the default: each row one sweep at one "
             "speed, each pixel lit by its own bit, the same pulses for every dark pixel; "
             "needs a bitstream with pixel lines: build --preset engraver, or the ULX3S's) or "
             "runs (a mark for each run of dark cells and a jump for each gap: any "
             "bitstream)"), section="image", key="lines"),
    # the job's laser and speed
    *(_setting(setting, "laser", "job") for setting in (SPEED, POWER, PRR)),
    _setting(PASSES, "passes", "job"),
    # the drawing's fill
    Option("--layer", "drawing", dict(
        nargs="+", action=LayerAction, default=[], dest="layers", metavar=("MATCH", "KEY=VALUE"),
        help="settings of their own for the paths of one colour (an SVG stroke, else fill: "
             "\"#ff0000\"; quote it) or one layer (an Inkscape layer's label, a DXF layer's "
             "name, a G-code file's S and F: \"S500 F6000\"); repeat it for more layers, run in that order, what none matches last; "
             "keys: " + ", ".join(f"{key} ({one.said})" for key, one in
                                  LAYER_KEYS.items()).replace("%", "%%"))),
    *(_setting(setting, "drawing", "job") for setting in (HATCH, HATCH_LINES, CONTOUR)),
    Option("--no-outline", "drawing", dict(
        action="store_true", help="mark the hatch only, not the outlines"),
        section="job", key=OUTLINE.key, inverted=True),
    _setting(TOLERANCE, "drawing", "job"),
    # wobble
    *(_setting(setting, "wobble", "job") for setting in (WOBBLE, WOBBLE_ALONG, WOBBLE_HZ)),
    # the focus shifter
    _setting(Z, "laser", "job"),
    # placement
    Option("--origin", "placement", dict(
        choices=["centre", "center", "lower-left", "page"], default="centre",
        help="what of the drawing goes to --offset: its bounding box's centre (default) or "
             "lower-left corner, or (page) its own origin, the drawing keeping its own "
             "coordinates (a DXF's 0,0; an SVG's top-left corner)"), section="drawing"),
    Option("--offset", "placement", dict(
        type=pair_mm("--offset"), default=(0.0, 0.0), metavar="X,Y",
        help="where in the field, mm from its centre (default: 0,0; a negative X as "
             "--offset=-5,2)"), section="drawing"),
    Option("--units", "placement", dict(
        choices=list(UNITS), default=None,
        help="the unit the drawing's numbers are in, in place of the units it declares (an "
             "SVG's width, height and viewBox; a DXF's $INSUNITS; G-code's G20, G21): " +
             ", ".join(f"{unit} ({name})" for unit, (_, name) in UNITS.items()) +
             "; pt and px are 1/72 and 1/96 in"), section="drawing"),
    Option("--s-max", "drawing", dict(
        type=number_in("S maximum", *S_MAX_RANGE), default=None, metavar="S",
        help=f"G-code: the S value of full power, each S marked at that share of the "
             f"laser's power (default: {S_MAX:g}, GRBL's $30; Inkscape's J Tech extension "
             f"and Marlin: 255)"), section="drawing"),
    Option("--scale", "placement", dict(
        type=number_in("scale", *SCALES), default=1.0, metavar="K",
        help="size factor, about the drawing's centre (default: 1)"), section="drawing"),
    Option("--rotate", "placement", dict(
        type=number_in("rotate", -360, 360), default=0.0, metavar="DEG",
        help="counter-clockwise, degrees"), section="drawing"),
    # marking on the fly
    *(_setting(setting, "fly", "job") for setting in (FLY, ENCODER, FLY_SPEED, FLY_DIRECTION,
                                                      BELT_SPEED)),
    # SkyWriting
    *(_setting(setting, "sky", "job") for setting in SKY_SETTINGS),
    # I/O in the queue
    *(_setting(setting, "io", "job") for setting in IO_SETTINGS),
)

_BY_DEST = {option.dest: option for option in OPTIONS}

#: The sections of a job file and their keys → the options they stand for, in the order a
#: saved file writes them; ``layer`` in a text, code or photo names the layer it takes its
#: settings from (:mod:`.layers` reads ``[[layer]]`` tables).
SECTIONS = {
    "job": {o.key or o.dest: o for o in OPTIONS if o.section == "job"},
    **{section: {**{o.key or o.dest: o for o in OPTIONS if o.section == section},
                 **({"layer": None} if section != "drawing" else {})}
       for section in ("drawing", "text", "code", "image")},
}


def option(dest):
    """The option whose value is ``dest``."""
    return _BY_DEST[dest]


def option_of_flag(flag):
    """The option whose flag is ``flag`` (``--sky``)."""
    return next(o for o in OPTIONS if o.flag == flag)


def defaults():
    """``{dest: value}``: what each option is when the command line does not give it."""
    return {o.dest: o.default for o in OPTIONS}


def add_job_file_options(parser):
    """Every option of :data:`OPTIONS` into ``parser``, each in its ``--help`` group."""
    groups = {}
    for one in OPTIONS:
        title = GROUPS[one.group]
        if title is None:
            target = parser
        else:
            if one.group not in groups:
                groups[one.group] = parser.add_argument_group(title)
            target = groups[one.group]
        keywords = dict(one.argparse)
        if isinstance(keywords.get("default"), list):
            keywords["default"] = []    # --layer appends to it: a list of each parser's own
        target.add_argument(one.flag or one.dest, **keywords)


def _key_said(key, one):
    """A key as the README's table lists it: the option it stands for when named otherwise,
    the form of its value when it is not one word or number."""
    said = f"`{key}`"
    if one is None:
        return said
    if one.inverted:
        return f"{said} (true/false: `{one.flag}`)"
    if one.argparse.get("action") == "append":
        return f"{said} (a list)"
    if one.flag is not None and one.flag != f"--{key.replace('_', '-')}":
        return f"{said} (`{one.flag}`)"
    if one.argparse.get("metavar") == "X,Y":
        return f"{said} ([x, y])"
    return said


def job_file_table():
    """The README's table of a job file's tables and their keys, from :data:`SECTIONS`."""
    rows = ["| table | keys (the option each stands for) |", "|---|---|"]
    for section, keys in SECTIONS.items():
        name = f"[{section}]" if section == "job" else f"[[{section}]]"
        rows.append(f"| `{name}` | " + ", ".join(_key_said(k, o) for k, o in keys.items()) +
                    " |")
    rows.append("| `[[layer]]` | `match` and the `--layer` keys |")
    return "\n".join(rows)
