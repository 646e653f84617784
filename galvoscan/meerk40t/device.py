"""The galvoscan device: a meerk40t :class:`~meerk40t.kernel.Service` with a view of the lens
field, a spooler and :class:`~.driver.GalvoscanDriver`.

Its settings are few and its own: the machine profile it reads (a TOML file; empty: galvoscan's
default profile), the link (``sim``: a simulated board in meerk40t's process; else a serial
port: a board's, or the pseudo-terminal ``galvoscan board --sim`` serves), the chord
tolerance curves are flattened to and how often the board's state is read for meerk40t's status
bar (:mod:`.status`) while no job runs. The field, the laser's PRR range and the operations'
defaults come from the profile; nothing is written back to it.

The view makes the device's native units galvoscan's galvo units: 65536 across the lens field
(``[field] size_mm``), Y up (meerk40t's scene has Y down: the view flips it), so that a cut's
coordinates are the board's.
"""

from meerk40t.core.spoolers import Spooler
from meerk40t.core.units import Length
from meerk40t.core.view import View
from meerk40t.device.mixins import Status
from meerk40t.kernel import Service, signal_listener

from .. import api
from ..geometry.field import UNITS
from ..link.client import ClientError
from ..settings.laser import TOLERANCE
from .driver import SIM, GalvoscanDriver


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
            self.profile = self._load_profile()
        except ValueError as error:             # (a profile file gone or broken since)
            self.channel("console")(f"galvoscan: error: {error}: galvoscan's default profile "
                                    f"is used")
            self.profile = api.default_profile()
        prr_low, prr_high = self.profile.laser.prr_khz
        self.register("frequency", (prr_low, prr_high))
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
        return api.load_profile(self.profile_path) if self.profile_path else \
            api.default_profile()

    @signal_listener("profile_path")
    def realize(self, origin=None, *args):
        """The view of the profile's lens field, read again when the profile changes."""
        if origin is not None and origin != self.path:
            return
        if origin is not None:
            try:
                self.profile = self._load_profile()
            except ValueError as error:
                self.channel("console")(f"galvoscan: error: {error}: the profile in use is "
                                        f"kept")
                return
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

        @self.console_command("board_status", help=_("The galvoscan board's state"))
        def board_status(command, channel, _, **kwargs):
            try:
                channel(f"galvoscan: board: {self.driver.board_status()}")
            except (ClientError, OSError, ValueError) as error:
                channel(f"galvoscan: error: the board's state cannot be read: {error}")

        @self.console_command("pause", help=_("Hold the spooler's next job"))
        def pause(command, channel, _, **kwargs):
            self.driver.pause()
            channel("galvoscan: the next job is held (a job on the board runs to its end)")

        @self.console_command("resume", help=_("Release held jobs"))
        def resume(command, channel, _, **kwargs):
            self.driver.resume()
            channel("galvoscan: jobs released")
