"""The galvoscan device: a meerk40t :class:`~meerk40t.kernel.Service` with a view of the lens
field, a spooler and :class:`~.driver.GalvoscanDriver`.

Its own settings are few: the machine profile it reads (a TOML file; empty: galvoscan's default
profile), the link (``sim``: a simulated board in meerk40t's process; else a serial port: a
board's, or the pseudo-terminal ``galvoscan board --sim`` serves), the chord tolerance curves
are flattened to, and how often the board's state is read for meerk40t's status bar
(:mod:`.status`) while no job runs. The rest are the profile's keys, every one a setting of the
device (:mod:`.settings`, from galvoscan's one declaration of them): the field, the link's baud,
the laser's power and PRR range, the delays, the operations' defaults. A key changed in
meerk40t (its settings, or ``galvoscan_profile set KEY VALUE``) is checked by galvoscan's
profile reader and used at once; it is written back to the file, comments kept, only by
``galvoscan_profile save [PATH]``.

The view makes the device's native units galvoscan's galvo units: 65536 across the lens field
(``[field] size_mm``), Y up (meerk40t's scene has Y down: the view flips it), so that a cut's
coordinates are the board's.
"""

from meerk40t.core.spoolers import Spooler
from meerk40t.core.units import Length
from meerk40t.core.view import View
from meerk40t.device.mixins import Status
from meerk40t.kernel import Service, signal_listener

from ..geometry.field import UNITS
from ..link.client import ClientError
from ..profile.writer import ProfileDocument
from ..settings.laser import TOLERANCE
from .driver import SIM, GalvoscanDriver
from .grbl import GcodeUpControl
from .settings import ATTRIBUTES, ProfileSettings, key_line, profile_choices


__all__ = ["GalvoscanDevice", "STATUS_POLL_S"]

#: How often the board's state is read for meerk40t's status bar while no job runs, s (the
#: ``status_poll_s`` setting's default).
STATUS_POLL_S = 2.0


class GalvoscanDevice(Service, Status):
    """meerk40t's device for a galvoscan board (``provider/device/galvoscan``)."""

    def __init__(self, kernel, path, *args, choices=None, **kwargs):
        Service.__init__(self, kernel, path)
        Status.__init__(self)
        self.name = "galvoscan"
        self.state = 0
        for choice in choices or ():
            if choice.get("attr") is not None and choice.get("default") is not None:
                setattr(self, choice["attr"], choice["default"])
        _ = kernel.translation
        self.register_choices("galvoscan", [
            {"attr": "label", "object": self, "default": "galvoscan", "type": str,
             "label": _("Label"), "tip": _("What this device is called."),
             "section": "_00_General"},
            {"attr": "profile_path", "object": self, "default": "", "type": str,
             "label": _("Machine profile"),
             "tip": _("galvoscan's machine profile (TOML): the field, the lens table, the "
                      "laser, the delays and the link's baud. Empty: galvoscan's default."),
             "section": "_00_General"},
            {"attr": "link", "object": self, "default": SIM, "type": str,
             "label": _("Link"),
             "tip": _("'sim': a simulated board in this process; else the board's serial port "
                      "(or the pseudo-terminal of `galvoscan board --sim`)."),
             "section": "_00_General"},
            {"attr": "tolerance_mm", "object": self, "default": TOLERANCE.default,
             "type": float, "label": _("Curve tolerance (mm)"),
             "tip": _("How far a flattened curve may stray from meerk40t's curve."),
             "section": "_00_General"},
            {"attr": "status_poll_s", "object": self, "default": STATUS_POLL_S, "type": float,
             "label": _("Status poll (s)"),
             "tip": _("How often the board's state (busy or ready, armed, the interlock, "
                      "faults) is read for the status bar while no job runs; 0: only after "
                      "jobs."),
             "section": "_00_General"},
        ])
        try:
            self.profile_document = self._load_profile()
        except ValueError as error:             # (a profile file gone or broken since)
            self.channel("console")(f"galvoscan: error: {error}: galvoscan's default profile "
                                    f"is used")
            self.profile_document = ProfileDocument.default()
        self.profile_settings = ProfileSettings(self)
        self.register_choices("galvoscan", profile_choices(self.profile_settings, _))
        for kind in ("cut", "engrave", "hatch", "raster", "image"):
            self.register(f"format/op {kind}",
                          "{danger}{defop}{enabled}{pass}{element_type} {speed}mm/s @{power} "
                          "{frequency}kHz {colcode} {opstop}")
        self.register("format/op dots",
                      "{danger}{defop}{enabled}{pass}{element_type} {dwell_time}ms dwell "
                      "{frequency}kHz {colcode} {opstop}")
        self.setting(bool, "use_percent_for_power_display", True)
        self.setting(bool, "use_mm_min_for_speed_display", False)
        self.view = View(1, 1)
        self.realize()
        self.spooler = Spooler(self)
        self.driver = GalvoscanDriver(self)
        self.spooler.driver = self.driver
        self.add_service_delegate(self.spooler)
        self.viewbuffer = ""
        self._commands()

    def _load_profile(self):
        """The profile file's document (the setting empty: galvoscan's default profile)."""
        return ProfileDocument.load(self.profile_path) if self.profile_path else \
            ProfileDocument.default()

    @property
    def profile(self):
        """The machine profile in use (:class:`~galvoscan.profile.machine.MachineProfile`)."""
        return self.profile_document.profile

    def set_profile_key(self, name, value, *, typed=False):
        """Set the profile's key ``name`` (``section.key``) to ``value`` (text as typed, or
        ``typed``: a value of the key's type, as meerk40t's settings give it), checked by
        galvoscan's profile reader; the profile in use changes, the file does not. Returns
        whether it was set (if not, one line says why)."""
        try:
            if typed:
                self.profile_document.set(name, value)
            else:
                self.profile_document.set_text(name, value)
        except ValueError as error:
            self.channel("console")(f"galvoscan: error: {error}: the profile in use is kept")
            return False
        self.realize()
        self.channel("console")(f"galvoscan: {key_line(self.profile_document, name)} "
                                f"(not saved: `galvoscan_profile save` writes it)")
        return True

    @signal_listener("profile_path")
    def realize(self, origin=None, *args):
        """The view of the profile's lens field and its PRR range, read again when the
        profile changes."""
        if origin is not None and origin != self.path:
            return
        if origin is not None:
            try:
                self.profile_document = self._load_profile()
            except ValueError as error:
                self.channel("console")(f"galvoscan: error: {error}: the profile in use is "
                                        f"kept")
                return
        self.register("frequency", tuple(self.profile.laser.prr_khz))
        size = f"{self.profile.field.size_mm:g}mm"
        scale = float(Length(size)) / UNITS
        self.view.set_dims(size, size)
        self.view.set_native_scale(scale, scale)
        self.view.transform(flip_y=True)
        self.signal("view;realized")

    def service_attach(self, *args, **kwargs):
        """The device made the active one: its board's state polled for the status bar."""
        self.driver.status_bar.start()

    def service_detach(self, *args, **kwargs):
        self.driver.status_bar.stop()

    def shutdown(self, *args, **kwargs):
        self.driver.status_bar.stop()

    @property
    def safe_label(self):
        return str(getattr(self, "label", self.name)).replace(" ", "-").replace("/", "-")

    @property
    def current(self):
        return self.view.iposition(self.driver.native_x, self.driver.native_y)

    @property
    def native(self):
        return self.driver.native_x, self.driver.native_y

    def location(self):
        return self.link

    def pre_outline(self):
        """What meerk40t's trace (its Outline button) runs before its moves round the
        outline: the driver gathers them."""
        yield ("outline_start",)

    def post_outline(self):
        """… and after them: the driver walks the outline with the guide laser."""
        yield ("outline_end",)

    def get_operation_defaults(self, op_type):
        """An operation's defaults: the profile's speed, power (per mille, meerk40t's) and
        PRR."""
        defaults = self.profile.defaults
        return {"speed": defaults.speed_mm_s, "power": defaults.power_percent * 10,
                "frequency": defaults.prr_khz}

    def _commands(self):
        _ = self.kernel.translation

        @self.console_command(("estop", "abort"), help=_("Stop the job: arm = 0 first"))
        def estop(command, channel, _, **kwargs):
            self.spooler.clear_queue()
            self.driver.reset()
            channel("galvoscan: stopped, arm = 0 sent")

        @self.console_argument("times", type=int, help=_("How many times (1 … 100)"))
        @self.console_command("guide_frame", help=_("Trace the last job's outline with the "
                                                     "guide laser, the laser off"))
        def guide_frame(command, channel, _, times=None, **kwargs):
            times = 1 if times is None else times
            if not 1 <= times <= 100:
                channel(f"galvoscan: error: guide_frame: times must be from 1 to 100, not "
                        f"{times}")
                return
            self.spooler.command("frame", times)

        @self.console_command("galvoscan_profile",
                              help=_("The machine profile's keys: list; set KEY VALUE (checked, "
                                     "used at once); save [PATH] (written, comments kept)"))
        def galvoscan_profile(command, channel, _, remainder=None, **kwargs):
            words = (remainder or "").split(maxsplit=2)
            action = words[0] if words else "list"
            document = self.profile_document
            if action == "list" and len(words) == 1 or not words:
                where = f"{document.path}" if self.profile_path else \
                    "galvoscan's default profile"
                channel(f"galvoscan: machine profile: {where}"
                        f"{' (changed, not saved)' if document.changed else ''}")
                for name in ATTRIBUTES.values():
                    channel(f"galvoscan: {key_line(document, name)}")
            elif action == "set" and len(words) == 3:
                self.set_profile_key(words[1], words[2])
            elif action == "save" and len(words) <= 2:
                self._save_profile(words[1] if len(words) == 2 else None, channel)
            else:
                channel("galvoscan: error: galvoscan_profile takes list, set KEY VALUE (KEY as "
                        "laser.prr_khz) or save [PATH]")

        @self.console_command("board_status", help=_("The galvoscan board's state"))
        def board_status(command, channel, _, **kwargs):
            try:
                channel(f"galvoscan: board: {self.driver.board_status()}")
            except (ClientError, OSError, ValueError) as error:
                channel(f"galvoscan: error: the board's state cannot be read: {error}")

        @self.console_command("pause", help=_("Hold the job on the board, the laser "
                                               "disarmed (again: let it go on)"))
        def pause(command, channel, _, **kwargs):
            if self.driver.paused:
                self.driver.resume()
                channel("galvoscan: resumed (a held job goes on, the laser armed again)")
                return
            self.driver.pause()
            channel("galvoscan: paused: the board marks what it holds queued, then holds the "
                    "job with the laser disarmed (`pause` or `resume` lets it go on)")

        @self.console_option("port", "p", type=int, default=23, help=_("port to listen on."))
        @self.console_option("verbose", "v", type=bool, action="store_true",
                             help=_("watch server channels"))
        @self.console_option("quit", "q", type=bool, action="store_true",
                             help=_("shutdown current grblserver"))
        @self.console_command("grblcontrol", help=_("meerk40t's GRBL server, G-code's Y up "
                                                     "(its 0,0 the field's lower left corner)"))
        def grblcontrol(command, channel, _, port=23, verbose=False, quit=False,
                        remainder=None, **kwargs):
            # meerk40t's own command, but for the server it starts (GcodeUpControl).
            if remainder and remainder.lower() in ("stop", "quit"):
                quit = True
            control = self.lookup("grblcontrol")
            if control is None:
                if quit:
                    channel(_("No control instance to stop."))
                    return
                control = GcodeUpControl(self.kernel.root)
                self.register("grblcontrol", control)
                control.start(port, verbose)
            if quit:
                control.quit()
                self.unregister("grblcontrol")

        @self.console_command("resume", help=_("Let a held job go on"))
        def resume(command, channel, _, **kwargs):
            self.driver.resume()
            channel("galvoscan: resumed (a held job goes on, the laser armed again)")

    def _save_profile(self, path, channel):
        """Write the profile in use to ``path`` (None: the file it was read from), its comments
        kept; a profile read from no file needs a path, and the device then reads that
        file."""
        if path is None and not self.profile_path:
            channel("galvoscan: error: galvoscan_profile save: the device uses galvoscan's "
                    "default profile, not a file: give a PATH to write it to; nothing written")
            return
        try:
            self.profile_document.save(path)
        except ValueError as error:
            channel(f"galvoscan: error: {error}: nothing written")
            return
        saved = str(self.profile_document.path)
        channel(f"galvoscan: machine profile written to {saved}")
        if saved != self.profile_path:
            self.profile_path = saved
            channel(f"galvoscan: the device reads its profile from {saved} now")
