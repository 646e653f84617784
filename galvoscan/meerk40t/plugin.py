"""The galvoscan plugin for meerk40t, found through the ``meerk40t.extension`` entry point
(``pip install 'galvoscan[meerk40t]'``): at ``register`` it registers the galvoscan device
(``provider/device/galvoscan``) and its entry in meerk40t's list of devices."""

from .device import GalvoscanDevice


__all__ = ["plugin"]


def plugin(kernel, lifecycle=None):
    if lifecycle == "register":
        _ = kernel.translation
        kernel.register("provider/device/galvoscan", GalvoscanDevice)
        kernel.register("provider/friendly/galvoscan", ("Fibre-Laser", 4))
        kernel.register("dev_info/galvoscan", {
            "provider": "provider/device/galvoscan",
            "friendly_name": _("galvoscan (open FPGA scan-head controller)"),
            "extended_info": _("A galvoscan board over XY2-100 and a fiber laser's DB25, or "
                               "its simulated board; the field and the laser come from "
                               "galvoscan's machine profile."),
            "priority": 5,
            "family": _("Generic Fibre-Laser"),
            "choices": [{"attr": "label", "default": "galvoscan"}],
        })
