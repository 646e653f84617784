"""The content ``mark`` and ``store`` make themselves, beside or instead of a drawing: codes
(``--code``), each a :class:`~galvoscan.jobs.vector_job.MarkObject` of the job."""

from ..jobs.codes import QR_LEVELS, CodeFill, CodeKind
from .args import int_in, number_in
from .jobargs import pair_mm


__all__ = ["add_content_options", "content_objects", "has_content"]


def add_content_options(parser):
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


def has_content(args):
    return getattr(args, "code", None) is not None


def content_objects(args, settings, profile):
    """The :class:`~galvoscan.jobs.vector_job.MarkObject` s the options ask for (raises
    :class:`~galvoscan.jobs.plan.PlanError`, one line)."""
    from ..jobs.codes import CodeSpec, code_object
    from ..jobs.plan import PlanError
    objects = []
    given = [name for name in ("data", "size", "code_ec", "code_quiet", "code_height")
             if getattr(args, name) is not None]
    if args.code is None:
        if given:
            raise PlanError(f"--{given[0].replace('_', '-')} is for --code")
        return objects
    if args.data is None or args.size is None:
        raise PlanError("--code needs --data TEXT and --size MM")
    spec = CodeSpec(CodeKind(args.code), args.data, args.size, ec_level=args.code_ec,
                    fill=CodeFill(args.code_fill), quiet_modules=args.code_quiet,
                    height_mm=args.code_height)
    objects.append(code_object(spec, settings, centre_mm=args.code_at,
                               spot_mm=profile.laser.spot_mm))
    return objects
