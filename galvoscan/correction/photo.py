"""Calibration from a photo of a marked plate (Zhu & Zhang's vision-assisted pipeline).

1. :func:`calibration_job` marks an ``n × n`` grid of spiral-filled circles (the spiral's pitch is
   the line width, so each circle is solid) as a vector job.
2. The plate is photographed. It carries four reference marks (drilled holes, a printed frame:
   anything the camera sees) at known positions, :data:`FIDUCIALS` by default, which tie the
   photo to the plate.
3. :func:`find_marks` thresholds the photo (Otsu), labels its blobs and takes each one's
   centroid as its centre and its equivalent-area radius as its size (on the synthetic photos
   the centroid's worst error is a quarter of Zhu & Zhang's minimum enclosing circle's, which
   rests on a few rim pixels).
4. :func:`measure_photo` takes the four largest circles as the references, maps every circle
   centre through the homography they give into plate coordinates (galvo units of an ideal
   head), and pairs each with the grid point it was marked for.
5. :func:`table_from_photo` makes the table from those pairs (:mod:`.measure`).

:func:`render_photo` makes synthetic photos for testing: the job's path pushed through a scan
head model, seen through a tilted camera, blurred, with noise.
"""

import math

import numpy as np
from skimage.filters import gaussian, threshold_otsu  # ink and lens blur; the threshold
from skimage.measure import label, regionprops  # the blobs, their centroids and areas
from skimage.transform import ProjectiveTransform, estimate_transform  # photo → plate mapping

from .measure import DEFAULT_SPAN, MeasurementError, calibration_grid, table_from_measurement
from .model import FIELD_CENTRE


__all__ = ["FIDUCIAL_OFFSET", "FIDUCIAL_RADII", "fiducials", "calibration_job", "job_text",
           "mark_radius", "render_photo", "find_marks", "homography", "apply_homography",
           "measure_photo", "table_from_photo", "PhotoError"]


#: Reference marks sit this far (galvo units) beyond the calibrated square's corners, on its
#: diagonals. Their radii tell them apart, so a photo may be turned or mirrored: lower left
#: (the largest), lower right, upper right, upper left; all larger than any calibration circle.
FIDUCIAL_OFFSET = 3500
FIDUCIAL_RADII = (4000, 3000, 2200, 2200)


class PhotoError(MeasurementError):
    """A photo the pipeline cannot use; the message says what it found."""


def fiducials(span=DEFAULT_SPAN, centre=FIELD_CENTRE):
    """Plate positions (galvo units) of the four reference marks, as an array (4, 2)."""
    reach = span / 2 + FIDUCIAL_OFFSET
    return np.array([(centre + sx * reach, centre + sy * reach)
                     for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


def mark_radius(grid, span=DEFAULT_SPAN):
    """Radius (galvo units) of the calibration circles: a fifth of their spacing, ≤ 1500."""
    return min((span / (grid - 1)) / 5, 1500.0)


def calibration_job(grid=9, *, span=DEFAULT_SPAN, centre=FIELD_CENTRE, line_width=60,
                    radius=None):
    """The calibration pattern as vector segments ``(op, x, y)``.

    Each circle is an Archimedean spiral from its centre out to ``radius`` with one
    ``line_width`` between turns, then its rim; chords are at most four line widths (the DDA
    puts points on them at the ``pitch`` register's spacing). Circles go row by row,
    alternating direction, so jumps are short.
    """
    cx, cy = calibration_grid(grid, span, centre)
    radius = mark_radius(grid, span) if radius is None else radius
    if not 0 < line_width <= radius:
        raise MeasurementError(f"line width must be from 1 to the radius ({radius:.0f} units), "
                               f"not {line_width!r}")
    segments = []
    for row in range(grid):
        columns = range(grid) if row % 2 == 0 else range(grid - 1, -1, -1)
        for column in columns:
            x0, y0 = float(cx[row, column]), float(cy[row, column])
            segments.append(("jump", round(x0), round(y0)))
            turns = radius / line_width
            theta, end = 0.0, 2 * math.pi * turns
            while theta < end:
                r = line_width * theta / (2 * math.pi)
                # Step so that the chord is about 4 line widths (and no more than a quarter turn).
                theta = min(end, theta + min(math.pi / 2, 4 * line_width / max(r, line_width)))
                r = line_width * theta / (2 * math.pi)
                segments.append(("mark", round(x0 + r * math.cos(theta)),
                                 round(y0 + r * math.sin(theta))))
            rim = max(8, int(2 * math.pi * radius / (4 * line_width)))
            for k in range(1, rim + 1):
                angle = end + 2 * math.pi * k / rim
                segments.append(("mark", round(x0 + radius * math.cos(angle)),
                                 round(y0 + radius * math.sin(angle))))
    return segments


def job_text(segments, *, title="galvoscan calibration job"):
    """A job file (``galvoscan sim --job``) for ``segments``."""
    lines = [f"# {title}: {len(segments)} segments"]
    lines += [f"{op} {x} {y}" for op, x, y in segments]
    return "\n".join(lines) + "\n"


def _default_camera(pixels, span):
    """Plate units → pixels: the calibrated square and its references fill ~90 % of the frame,
    turned by 1.5°, with a slight tilt (perspective)."""
    view = span + 2 * (FIDUCIAL_OFFSET + max(FIDUCIAL_RADII)) + 2000
    scale = 0.9 * pixels / view
    turn = math.radians(1.5)
    c, s = scale * math.cos(turn), scale * math.sin(turn)
    # Centre the plate's field centre in the frame, then tilt.
    centred = np.array([[c, -s, pixels / 2 - (c - s) * FIELD_CENTRE],
                        [s, c, pixels / 2 - (s + c) * FIELD_CENTRE],
                        [0.0, 0.0, 1.0]])
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2e-5, -1.5e-5, 1.0]])
    shift = np.array([[1.0, 0.0, -pixels / 2], [0.0, 1.0, -pixels / 2], [0.0, 0.0, 1.0]])
    back = np.array([[1.0, 0.0, pixels / 2], [0.0, 1.0, pixels / 2], [0.0, 0.0, 1.0]])
    return back @ tilt @ shift @ centred


def apply_homography(matrix, points):
    """``points`` (N, 2) through the 3 × 3 homography ``matrix``."""
    return ProjectiveTransform(np.asarray(matrix, dtype=float))(np.asarray(points, dtype=float))


def homography(source, target):
    """The 3 × 3 homography taking ``source`` (N ≥ 4, 2) onto ``target`` (least squares:
    scikit-image's DLT with Hartley normalisation)."""
    source = np.asarray(source, dtype=float)
    target = np.asarray(target, dtype=float)
    if source.shape != target.shape or source.ndim != 2 or source.shape[1] != 2 or \
            len(source) < 4:
        raise PhotoError("a homography needs at least four point pairs")
    found = estimate_transform("projective", source, target)
    # A failed fit is falsy (scikit-image ≥ 0.26) or has non-finite parameters (before).
    if not found or not np.isfinite(found.params).all():
        raise PhotoError("the points give no homography (three or more of them in a line?)")
    return found.params / found.params[2, 2]


def render_photo(segments, land, *, grid, span=DEFAULT_SPAN, pixels=2048, line_width=60,
                 blur_px=1.0, noise=0.04, seed=0, camera=None):
    """A synthetic grey-scale photo (float array, 0 = black) of the marked plate.

    The job's path, sampled every third of a line width, goes through ``land`` (the scan head:
    commanded → plate galvo units) and ``camera`` (plate units → pixels, default: tilted and
    turned); marks are dark on a light plate, the references dark discs. Returns
    ``(image, camera)``.
    """
    camera = _default_camera(pixels, span) if camera is None else camera
    # Trace the path as the head draws it (marks only), densely.
    points = []
    last = None
    for op, x, y in segments:
        if op == "mark" and last is not None:
            length = math.hypot(x - last[0], y - last[1])
            count = max(1, int(length / (line_width / 3)))
            t = np.arange(1, count + 1) / count
            points.append(np.c_[last[0] + t * (x - last[0]), last[1] + t * (y - last[1])])
        last = (x, y)
    path = np.vstack(points)
    lx, ly = land(path[:, 0], path[:, 1])
    px = apply_homography(camera, np.c_[lx, ly])

    # Ink: splat each path sample over its four nearest pixels, then widen to the line width.
    ink = np.zeros((pixels, pixels))
    x0 = np.floor(px[:, 0]).astype(int)
    y0 = np.floor(px[:, 1]).astype(int)
    fx, fy = px[:, 0] - x0, px[:, 1] - y0
    for dx, dy, weight in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)),
                           (0, 1, (1 - fx) * fy), (1, 1, fx * fy)):
        xs, ys = x0 + dx, y0 + dy
        inside = (xs >= 0) & (xs < pixels) & (ys >= 0) & (ys < pixels)
        np.add.at(ink, (ys[inside], xs[inside]), weight[inside])
    units_per_px = 1 / np.linalg.norm(camera[:2, :2] @ np.array([1.0, 0.0]))
    width_px = max(line_width / units_per_px, 1.0)
    ink = gaussian(ink, width_px / 2)
    ink = np.clip(ink / (ink.max() * 0.25), 0, 1)

    # The reference marks: discs on the plate, drawn through the camera exactly.
    inverse = np.linalg.inv(camera)
    rows, cols = np.mgrid[0:pixels, 0:pixels]
    plate = apply_homography(inverse, np.c_[cols.ravel() + 0.0, rows.ravel() + 0.0])
    for (fx_, fy_), radius in zip(fiducials(span), FIDUCIAL_RADII):
        near = np.hypot(plate[:, 0] - fx_, plate[:, 1] - fy_) <= radius
        ink.ravel()[near] = 1.0

    image = 0.85 - 0.7 * ink
    image = gaussian(image, blur_px)
    rng = np.random.default_rng(seed)
    image = image + rng.normal(0.0, noise, image.shape)
    return np.clip(image, 0.0, 1.0), camera


def find_marks(image, *, dark_marks=True, min_area=20):
    """The marks in a grey-scale photo: a list of ``(x, y, radius, area)`` in pixels, each a
    4-connected blob's centroid, equivalent-area radius and area (blobs under ``min_area``
    pixels are specks and left out)."""
    image = np.asarray(image, dtype=float)
    if image.ndim == 3:                               # colour: use the mean of the channels
        image = image[..., :3].mean(axis=2)
    if image.ndim != 2 or min(image.shape) < 16:
        raise PhotoError(f"a photo must be a grey-scale or colour image, not shape {image.shape}")
    if image.max() > 1.0:
        image = image / 255.0
    threshold = threshold_otsu(image)
    foreground = image < threshold if dark_marks else image > threshold
    marks = []
    for blob in regionprops(label(foreground, connectivity=1)):
        if blob.area >= min_area:
            y, x = blob.centroid
            marks.append((x, y, blob.equivalent_diameter_area / 2, int(blob.area)))
    return marks


def measure_photo(image, grid, *, span=DEFAULT_SPAN, centre=FIELD_CENTRE, references=None,
                  dark_marks=True):
    """Commanded grid and measured circle centres from a photo of the calibration plate.

    Returns ``(cx, cy, mx, my)`` in galvo units, indexed ``[row][column]``. ``references``: the
    four reference marks' plate positions (default :func:`fiducials`), in the order lower left,
    lower right, upper right, upper left.
    """
    references = fiducials(span, centre) if references is None else np.asarray(references,
                                                                                 dtype=float)
    marks = find_marks(image, dark_marks=dark_marks)
    wanted = grid * grid + 4
    if len(marks) != wanted:
        raise PhotoError(f"found {len(marks)} marks; a {grid} × {grid} calibration plate has "
                         f"{grid * grid} circles and 4 reference marks")
    marks.sort(key=lambda mark: mark[2], reverse=True)
    found = np.array([(x, y) for x, y, _, _ in marks[:4]])
    circles = np.array([(x, y) for x, y, _, _ in marks[4:]])
    if marks[3][2] < 1.15 * marks[4][2] or marks[1][2] < 1.15 * marks[2][2] or \
            marks[0][2] < 1.15 * marks[1][2]:
        raise PhotoError("the reference marks do not have the sizes of FIDUCIAL_RADII: the "
                         "largest four marks must be three sizes, all above the circles'")

    # The references by size: lower left is the largest, lower right the next; of the other
    # two, upper right is the one nearer lower right.
    lower_left, lower_right, third, fourth = found
    if np.hypot(*(third - lower_right)) > np.hypot(*(fourth - lower_right)):
        third, fourth = fourth, third
    matrix = homography(np.array([lower_left, lower_right, third, fourth]), references)
    plate = apply_homography(matrix, circles)

    cx, cy = calibration_grid(grid, span, centre)
    nodes = np.c_[cx.ravel(), cy.ravel()].astype(float)
    distance = np.hypot(plate[:, None, 0] - nodes[None, :, 0],
                        plate[:, None, 1] - nodes[None, :, 1])
    nearest = distance.argmin(axis=1)
    spacing = span / (grid - 1)
    if len(set(nearest.tolist())) != len(nodes) or \
            distance[np.arange(len(plate)), nearest].max() > spacing / 3:
        raise PhotoError("the circles do not pair one to one with the grid points: wrong grid "
                         "size or span, or reference marks not where they were said to be")
    mx = np.empty(len(nodes))
    my = np.empty(len(nodes))
    mx[nearest], my[nearest] = plate[:, 0], plate[:, 1]
    return cx, cy, mx.reshape(cx.shape), my.reshape(cy.shape)


def table_from_photo(image, grid, *, nodes=17, method="bilinear", span=DEFAULT_SPAN,
                     centre=FIELD_CENTRE, references=None, dark_marks=True):
    """The correction table from a photo of the calibration plate (see the module)."""
    cx, cy, mx, my = measure_photo(image, grid, span=span, centre=centre,
                                   references=references, dark_marks=dark_marks)
    return table_from_measurement(cx, cy, mx, my, nodes=nodes, method=method)
