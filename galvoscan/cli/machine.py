"""``galvoscan machine init`` and ``machine show``: the machine profile (``galvoscan.toml``), and
the ``--machine FILE`` option every job command shares (:func:`add_machine_option`,
:func:`profile_from`)."""

import json
from pathlib import Path
import sys

from .args import fail, output_file


__all__ = ["add_parsers", "add_machine_option", "profile_from"]


def add_machine_option(parser):
    """``--machine FILE``: the machine profile (default: ./galvoscan.toml if it exists, else the
    built-in defaults)."""
    # Here: profile.machine takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..profile.machine import DEFAULT_PROFILE_NAME
    parser.add_argument("--machine", metavar="FILE", default=None,
                        help=f"machine profile (default: ./{DEFAULT_PROFILE_NAME} if there is "
                             f"one, else the built-in defaults; `galvoscan machine init` "
                             f"writes one)")


def profile_from(args):
    """The :class:`~galvoscan.profile.machine.MachineProfile` that ``--machine`` names, or a
    one-line error. Without ``--machine`` and without ./galvoscan.toml: the default profile,
    with a note on stderr."""
    # Here: profile.machine takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..profile.machine import DEFAULT_PROFILE_NAME, ProfileError, default_profile, load_profile
    path = getattr(args, "machine", None)
    if path is None:
        if not Path(DEFAULT_PROFILE_NAME).exists():
            profile = default_profile()
            print(f"galvoscan: note: no ./{DEFAULT_PROFILE_NAME}: using the default profile "
                  f"({_n(profile.field.size_mm)} mm field); `galvoscan machine init` writes one",
                  file=sys.stderr)
            return profile
        path = DEFAULT_PROFILE_NAME
    try:
        return load_profile(path)
    except ProfileError as error:
        fail(error)


def _n(value, digits=6):
    """A number without trailing zeros: 110, 0.05, 595.782."""
    text = f"{value:.{digits}g}"
    if "e" in text:                      # 1e+06: print it whole
        text = f"{value:.{digits}f}".rstrip("0").rstrip(".")
    return text


def _describe(profile):
    """The resolved profile, in user units, as lines of text."""
    # Here: profile.machine takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..profile.machine import FRAME_US, POWER_REGISTER_MAX
    f, link, laser, galvo, d = (profile.field, profile.link, profile.laser, profile.galvo,
                                profile.defaults)
    table = profile.correction_table()
    source = "built-in defaults (no file)" if profile.source is None else str(profile.source)
    correction = "none (the board's identity table)" if f.correction is None else \
        f"{f.correction} ({table.n} × {table.n} nodes, dx {table.dx.min()} … " \
        f"{table.dx.max()}, dy {table.dy.min()} … {table.dy.max()} galvo units)"
    if link.port:
        where = f"serial {link.port} at {link.baud} baud"
    elif link.spi:
        where = f"SPI {link.spi}"
    else:
        where = f"not set (give --port or --spi; serial at {link.baud} baud)"
    if profile.variable_jump_delay:
        jumps = (f"{_n(galvo.min_jump_delay_us)} µs (a jump of 0) … "
                 f"{_n(galvo.jump_delay_us)} µs (one of {_n(galvo.jump_length_limit_mm)} mm "
                 f"or longer), in proportion to its length")
    else:
        jumps = f"{_n(galvo.jump_delay_us)} µs after every jump"
    power_reg = profile.power_register(d.power_percent)
    fly = profile.fly
    rows = [
        ("profile", source),
        ("[field]", None),
        ("size", f"{_n(f.size_mm)} × {_n(f.size_mm)} mm "
                 f"({_n(profile.units_per_mm)} galvo units per mm, "
                 f"{_n(profile.mm_per_unit * 1000, 4)} µm per unit)"),
        ("correction", correction),
        ("[link]", None),
        ("board", where),
        ("timeout", f"{_n(link.timeout_s)} s"),
        ("[laser]", None),
        ("power at 100 %", f"{_n(laser.max_power_w)} W (laser_power {POWER_REGISTER_MAX})"),
        ("pulse rate", f"{_n(laser.prr_khz[0])} … {_n(laser.prr_khz[1])} kHz"),
        ("spot", f"{_n(laser.spot_mm)} mm"),
        ("guide laser", "yes" if laser.guide else "no"),
        ("[galvo]", None),
        ("jump delay", f"{jumps} (the board counts {FRAME_US} µs frames)"),
        ("  for a 0.1 / 1 / 10 mm jump", " / ".join(str(profile.jump_delay_register(mm))
                                                    for mm in (0.1, 1, 10)) + " µs"),
        ("max speed", f"{_n(galvo.max_speed_mm_s)} mm/s"),
        ("laser on / off delay", f"{_n(galvo.laser_on_delay_us)} / "
                                 f"{_n(galvo.laser_off_delay_us)} µs"),
        ("mark / polygon delay", f"{_n(galvo.mark_delay_us)} / {_n(galvo.polygon_delay_us)} µs"
                                 f"{' × (1 - cos φ)' if galvo.polygon_scaled else ''}"),
        ("[defaults]", None),
        ("speed", f"{_n(d.speed_mm_s)} mm/s"),
        ("power", f"{_n(d.power_percent)} % = {_n(profile.power_w(d.power_percent), 3)} W "
                  f"(laser_power {power_reg})"),
        ("pulse rate", f"{_n(d.prr_khz)} kHz (laser_prr {profile.prr_register(d.prr_khz)})"),
        ("passes", str(d.passes)),
        ("[fly]", None),
        ("encoder", "none (mark --fly then needs --encoder, or --fly-speed for the board's "
                    "simulated encoder)" if fly.counts_per_mm is None else
                    f"{_n(fly.counts_per_mm)} counts/mm"),
        ("belt", f"towards {fly.direction}, " + (
            "its top speed not set (mark --belt-speed)" if fly.belt_speed_mm_s is None
            else f"at most {_n(fly.belt_speed_mm_s)} mm/s")),
        ("board clock", f"{_n(fly.board_clock_mhz)} MHz (the simulated encoder counts in "
                        f"it)"),
    ]
    width = max(len(name) for name, value in rows if value is not None)
    return [name if value is None else f"  {name:<{width}}  {value}" if name != "profile"
            else f"{name}: {value}" for name, value in rows]


def _cmd_show(args):
    profile = profile_from(args)
    if args.json:
        print(json.dumps(profile.as_dict(), indent=2, ensure_ascii=False))
    else:
        print("\n".join(_describe(profile)))
    return 0


def _cmd_init(args):
    # Here: profile.template takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..profile.machine import DEFAULT_PROFILE_NAME, default_profile
    from ..profile.template import profile_text
    path = Path(args.file)
    if path.exists() and not args.force:
        fail(f"{path} exists: not overwritten (--force replaces it)")
    path.write_text(profile_text(), encoding="utf-8")
    profile = default_profile()
    print(f"wrote {path}: the default profile ({_n(profile.field.size_mm)} mm field, "
          f"{_n(profile.laser.max_power_w)} W laser, {_n(profile.defaults.power_percent)} % "
          f"default power), every key commented")
    option = "" if path == Path(DEFAULT_PROFILE_NAME) else f" --machine {path}"
    print("edit next: [link] port (the board's serial port), [field] size_mm (the lens's "
          "field) and [laser] max_power_w (the laser's rated power); then check it with "
          f"`galvoscan machine show{option}`")
    return 0


def add_parsers(commands):
    # Here: profile.machine takes 0.1 s to import; `galvoscan --help` need not wait.
    from ..profile.machine import DEFAULT_PROFILE_NAME
    machine = commands.add_parser(
        "machine", help="write or show the machine profile (galvoscan.toml)",
        description="The machine profile: a TOML file with what a marking or cleaning job "
                    "needs to know about the machine that the board's registers do not hold "
                    "(the lens's field and correction table, the laser's power and pulse rates, "
                    "the jump delay, the link, the job defaults).")
    sub = machine.add_subparsers(dest="machine_command", required=True, metavar="COMMAND")

    init = sub.add_parser(
        "init", help="write a commented profile to edit",
        description="Write the default profile, every key commented with its unit, range and "
                    "purpose. An existing file is not overwritten unless --force.")
    init.add_argument("file", nargs="?", type=output_file, default=DEFAULT_PROFILE_NAME,
                      metavar="FILE", help="where to write it (default: %(default)s)")
    init.add_argument("--force", action="store_true", help="overwrite FILE if it exists")
    init.set_defaults(run=_cmd_init)

    show = sub.add_parser(
        "show", help="print the profile as jobs will use it",
        description="Load the profile, check every key, and print it resolved, in mm, W, kHz "
                    "and µs, with the numbers derived from it (galvo units per mm, jump delay "
                    "in frames, register values of the defaults).")
    add_machine_option(show)
    show.add_argument("--json", action="store_true",
                      help="print it as JSON: the file's keys by section, and \"derived\"")
    show.set_defaults(run=_cmd_show)
