"""meerk40t's GRBL server (``grblcontrol``) for the galvoscan device, with G-code's Y up.

meerk40t's own server hands a sender's coordinates to the device's view as the scene's, whose
Y runs down from the field's top edge: a sender's drawing (Y up, as GRBL's and every sender's
view are) would come out mirrored top to bottom. :class:`GcodeUpControl` is meerk40t's server
with the G-code's coordinates taken as meerk40t places a G-code file on its GRBL device (and as
the galvoscan device marks one opened in meerk40t): the file's 0,0 at the lens field's lower
left corner, its Y up. The device's ``grblcontrol`` command starts it in place of meerk40t's
(:mod:`.device`); ``?`` reports the head's position in the same coordinates.
"""

from meerk40t.core.units import Length
from meerk40t.grbl.control import GRBLControl
from meerk40t.svgelements import Matrix


__all__ = ["GcodeUpControl", "gcode_to_device"]


def gcode_to_device(view):
    """The matrix from G-code's coordinates (in meerk40t's scene units, as its G-code job
    scales them) to the device's native units: Y turned up about the field's lower left corner
    (scene ``(x, height - y)``), then the device's view."""
    height = float(Length(view.height))
    matrix = Matrix()
    matrix.post_scale(1, -1)
    matrix.post_translate(0, height)
    matrix.post_cat(view.matrix)
    return matrix


class GcodeUpControl(GRBLControl):
    """meerk40t's :class:`~meerk40t.grbl.control.GRBLControl`, its emulator's G-code job given
    :func:`gcode_to_device` once it is made."""

    def start(self, port=23, verbose=False):
        super().start(port, verbose)
        emulator = self.emulator
        if emulator is not None:                # (None: the port could not be opened)
            matrix = gcode_to_device(self.root.device.view)
            emulator.units_to_device_matrix = matrix
            emulator.job.units_to_device_matrix = matrix
