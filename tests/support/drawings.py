"""What the drawing tests share: SVG and DXF files made in a test, and geometry checks written
out here, independently of the loader."""

import ezdxf
import numpy as np

from galvoscan.inputs.drawings import load_drawing


# svgelements converts mm with 96 px/in × 0.0393701 in/mm (not 1/25.4): 0.54 ppm off, so SVG
# positions are compared to 0.1 µm (54 nm at 100 mm) and lengths to 0.6 ppm.
SVG_MM = 0.6e-6
SVG_ATOL = 1e-4


def svg(body, *, size='width="100mm" height="100mm" viewBox="0 0 100 100"'):
    return (f'<svg xmlns="http://www.w3.org/2000/svg" '
            f'xmlns:xlink="http://www.w3.org/1999/xlink" {size}>{body}</svg>')


def load_svg(tmp_path, body, name="t.svg", **kwargs):
    size = kwargs.pop("size", None)
    path = tmp_path / name
    path.write_text(svg(body) if size is None else svg(body, size=size))
    return load_drawing(path, **kwargs)


def new_dxf(units=4):
    doc = ezdxf.new("R2010", units=units)
    return doc, doc.modelspace()


def load_dxf(tmp_path, doc, name="t.dxf", **kwargs):
    path = tmp_path / name
    doc.saveas(path)
    return load_drawing(path, **kwargs)


def chord_midpoints(points):
    return (points[1:] + points[:-1]) / 2


def distance_to_curve(points, curve):
    """Distance from each point to a curve given as a dense polyline (an (m, 2) array)."""
    a, ab = curve[:-1], np.diff(curve, axis=0)
    a, ab = a[np.any(ab != 0, axis=1)], ab[np.any(ab != 0, axis=1)]
    out = []
    for p in np.asarray(points, dtype=float):
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
        out.append(np.min(np.hypot(*(a + t[:, None] * ab - p).T)))
    return np.array(out)


def bezier(controls, t):
    """De Casteljau, written out here so the check does not use the loader's evaluation."""
    p = [np.asarray(c, dtype=float) for c in controls]
    t = np.asarray(t)[:, None]
    while len(p) > 1:
        p = [(1 - t) * a + t * b for a, b in zip(p[:-1], p[1:])]
    return p[0]
