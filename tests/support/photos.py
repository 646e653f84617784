"""Photographs' stand-ins for the tests, made with numpy and Pillow."""

import numpy as np
from PIL import Image


def grey_photo(path, size=(400, 300)):
    """Smooth grey shading (a ramp across, a lesser one down, a soft bright bump), 8-bit grey,
    written to ``path``: a photograph's mix of dark runs, lone dots and light gaps once
    dithered. Returns ``path``."""
    width, height = size
    y, x = np.mgrid[0:height, 0:width]
    shade = 0.5 * x / (width - 1) + 0.3 * y / (height - 1) + \
        0.35 * np.exp(-((x - 0.6 * width) ** 2 + (y - 0.4 * height) ** 2) / (2 * 70.0 ** 2))
    shade = (shade - shade.min()) / (shade.max() - shade.min())
    Image.fromarray((255 * shade).astype(np.uint8), "L").save(path)
    return path
