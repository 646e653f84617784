"""The DXF reader of :func:`.drawings.load_drawing`: a DXF file (ezdxf) as polylines in the
drawing's units, then mm, with what is not marked counted.

:func:`_read_dxf` is called only by :func:`.drawings.load_drawing`, which turns what it raises
into a :class:`~galvoscan.geometry.drawing.DrawingError` naming the file and checks the
polylines it returns; the chord limits and wording it shares with the SVG reader are in
:mod:`.reading`.
"""

from collections import Counter
import io
import logging
from logging.handlers import BufferingHandler
import math

import numpy as np
from ezdxf import bbox, colors, recover, units
from ezdxf.addons import MTextExplode, text2path
from ezdxf.document import Drawing
from ezdxf.entities.boundary_paths import EdgePath, PolylinePath
from ezdxf.fonts import fonts
from ezdxf.lldxf.tagger import binary_tags_loader
from ezdxf.math import bulge_to_arc, ConstructionArc

from ..geometry.drawing import DrawingError, PathStyle
from .reading import UNITS, TooManyChords, _chords, _counted, _one_line, _round_chords


__all__ = []                                # nothing public: load_drawing reads DXF files


#: Text marked as its glyphs' outlines (ezdxf's text2path, in the text style's font).
_TEXT_TYPES = {"TEXT", "MTEXT", "ATTRIB"}
#: How a binary DXF file starts (AutoCAD's DXF reference, "Binary DXF Files").
_BINARY_SENTINEL = b"AutoCAD Binary DXF\r\n\x1a\x00"
#: The $INSUNITS codes of :data:`~.reading.UNITS`' units (AutoCAD's DXF reference, $INSUNITS).
_INSUNITS = {1: "in", 4: "mm", 5: "cm", 6: "m"}
#: mm per $INSUNITS unit where the definition is exact (ezdxf's table has 1 in = 25.4000000001).
_EXACT_MM = {**{code: UNITS[unit][0] for code, unit in _INSUNITS.items()}, 2: 304.8,
             8: 25.4e-6, 9: 0.0254, 10: 914.4, 13: 1e-3, 14: 100.0}


def _xy(vertices):
    return np.array([(v.x, v.y) for v in vertices], dtype=float).reshape(-1, 2)


def _spline_points(spline, tolerance):
    """A B-spline evaluated by ezdxf and flattened here.

    ezdxf's ``BSpline.flattening`` (and ``path.make_path``) run from the first knot to the last,
    right only for clamped knots: a closed (periodic) spline comes out with loops far outside
    it. The curve lives between knots ``order - 1`` and ``count``. Each knot span starts as 8
    chords; a chord is halved until the curve at 1/4, 1/2 and 3/4 of it is within tolerance.
    """
    knots = np.asarray(spline.knots(), dtype=float)
    low, high = knots[spline.order - 1], knots[spline.count]
    breaks = np.unique(np.concatenate([[low, high], knots[(knots > low) & (knots < high)]]))
    ts = np.unique(np.concatenate([np.linspace(a, b, 9) for a, b in zip(breaks, breaks[1:])]))
    points = _xy(spline.points(ts))
    t0, t1, p0, p1 = ts[:-1], ts[1:], points[:-1], points[1:]
    done_t, done_p = [ts[:1]], [points[:1]]
    for depth in range(40):
        chord, worst = p1 - p0, np.zeros(len(t0))
        for share in (0.25, 0.5, 0.75):
            curve = _xy(spline.points(t0 + share * (t1 - t0)))
            along = np.clip(np.sum((curve - p0) * chord, axis=1) /
                            np.maximum(np.sum(chord * chord, axis=1), 1e-300), 0, 1)
            worst = np.maximum(worst, np.hypot(*(p0 + along[:, None] * chord - curve).T))
        good = (worst <= tolerance) | (depth == 39)
        done_t.append(t1[good]), done_p.append(p1[good])
        if good.all():
            break
        bad = ~good
        _chords(sum(map(len, done_t)) + 2 * np.count_nonzero(bad))
        tm = (t0[bad] + t1[bad]) / 2
        pm = _xy(spline.points(tm))
        t0, t1 = np.concatenate([t0[bad], tm]), np.concatenate([tm, t1[bad]])
        p0, p1 = np.concatenate([p0[bad], pm]), np.concatenate([pm, p1[bad]])
    return np.concatenate(done_p)[np.argsort(np.concatenate(done_t), kind="stable")]


def _polyline_points(entity, tolerance):
    """A 2D/3D polyline's LINE and ARC pieces, joined from its first vertex. ARC entities
    always run counter-clockwise, so each piece is turned to start where the last ended."""
    first = next(iter(entity.vertices_in_wcs() if entity.dxftype() == "LWPOLYLINE"
                      else entity.points_in_wcs()))
    chained = [_xy([first])]
    for piece in entity.virtual_entities():
        if piece.dxftype() == "LINE":
            points = _xy([piece.dxf.start, piece.dxf.end])
        else:
            _round_chords(piece.dxf.radius, math.radians(_span_degrees(piece)), tolerance)
            points = _xy(piece.flattening(tolerance))
        end = chained[-1][-1]
        chained.append(points[::-1] if np.hypot(*(points[-1] - end)) <
                       np.hypot(*(points[0] - end)) else points)
    return np.concatenate(chained)


def _hatch_boundaries(hatch, tolerance):
    """A HATCH as its boundaries, each a closed shape (the fill is CAD's; ``--hatch`` makes the
    marking's): ``[(points, True), …]``. Arcs and ellipses are flattened on the curve itself,
    as the entities are (ezdxf's paths would make them Bézier curves, some 0.03 % of the
    radius off); a boundary's pieces are joined end to end."""
    ocs, elevation = hatch.ocs(), hatch.dxf.elevation.z
    found = []
    for boundary in hatch.paths:
        if isinstance(boundary, PolylinePath):
            pieces = _bulge_pieces(boundary.vertices, tolerance)
        elif isinstance(boundary, EdgePath):
            pieces = [_edge_points(edge, tolerance) for edge in boundary.edges]
        else:
            continue
        pieces = [piece for piece in pieces if len(piece)]
        if not pieces:
            continue
        points = _joined(pieces)
        if ocs.transform:
            points = _xy(ocs.points_to_wcs([(x, y, elevation) for x, y in points]))
        if len(points) >= 3:
            found.append((points, True))
    return found


def _bulge_pieces(vertices, tolerance):
    """A polyline boundary's ``(x, y, bulge)`` vertices as lines and arcs, closed."""
    pieces = []
    for (x0, y0, bulge), (x1, y1, _) in zip(vertices, vertices[1:] + vertices[:1]):
        if bulge:
            centre, start, end, radius = bulge_to_arc((x0, y0), (x1, y1), bulge)
            arc = ConstructionArc(centre, radius, math.degrees(start), math.degrees(end))
            _round_chords(radius, 4 * math.atan(abs(bulge)), tolerance)
            pieces.append(_xy(arc.flattening(tolerance)))
        else:
            pieces.append(np.array([(x0, y0), (x1, y1)], dtype=float))
    return pieces


def _edge_points(edge, tolerance):
    """One edge of an edge boundary, flattened."""
    kind = edge.type.name
    if kind == "LINE":
        return _xy([edge.start, edge.end])
    if kind == "ARC":
        arc = edge.construction_tool()
        _round_chords(arc.radius, math.radians(arc.angle_span or 360), tolerance)
        return _xy(arc.flattening(tolerance))
    if kind == "ELLIPSE":
        ellipse = edge.construction_tool()
        span = (ellipse.end_param - ellipse.start_param) % math.tau or math.tau
        _round_chords(math.hypot(*ellipse.major_axis), span, tolerance)
        return _xy(ellipse.flattening(tolerance))
    return _spline_points(edge.construction_tool(), tolerance)      # SPLINE


def _joined(pieces):
    """Pieces of one boundary end to end, each turned to start where the last ended (edges
    may run either way)."""
    def gap(a, b):
        return np.hypot(*(a - b))
    first = pieces[0]
    if len(pieces) > 1:
        after = pieces[1]
        if min(gap(first[0], after[0]), gap(first[0], after[-1])) < \
                min(gap(first[-1], after[0]), gap(first[-1], after[-1])):
            first = first[::-1]
    joined = [first]
    for piece in pieces[1:]:
        end = joined[-1][-1]
        joined.append(piece[::-1] if gap(piece[-1], end) < gap(piece[0], end) else piece)
    return np.concatenate(joined)


def _span_degrees(arc):
    """The degrees an ARC entity turns through (0: a whole circle)."""
    return (arc.dxf.end_angle - arc.dxf.start_angle) % 360


def _entity_points(entity, tolerance, skipped):
    """``(points, closed)`` of one entity that is not a block reference, a list of them (a
    HATCH's boundaries), or None."""
    kind = entity.dxftype()
    if kind == "LINE":
        return _xy([entity.dxf.start, entity.dxf.end]), False
    # (Each curve's chords counted before ezdxf makes them: see MAX_CHORDS.)
    if kind == "CIRCLE":
        _round_chords(entity.dxf.radius, math.tau, tolerance)
        return _xy(entity.flattening(tolerance)), True
    if kind == "ARC":
        span = _span_degrees(entity)
        _round_chords(entity.dxf.radius, math.radians(span or 360), tolerance)
        return _xy(entity.flattening(tolerance)), span == 0
    if kind == "ELLIPSE":
        span = (entity.dxf.end_param - entity.dxf.start_param) % math.tau
        _round_chords(math.hypot(*entity.dxf.major_axis), span or math.tau, tolerance)
        return _xy(entity.flattening(tolerance)), min(span, math.tau - span) < 1e-9
    if kind == "SPLINE":
        return _spline_points(entity.construction_tool(), tolerance), bool(entity.closed)
    if kind == "HATCH":
        return _hatch_boundaries(entity, tolerance)
    if kind == "LWPOLYLINE" or (kind == "POLYLINE" and
                                (entity.is_2d_polyline or entity.is_3d_polyline)):
        return _polyline_points(entity, tolerance), bool(entity.is_closed)
    if kind in _TEXT_TYPES:
        return _text_outlines(entity, tolerance, skipped)
    skipped["attribute definition" if kind == "ATTDEF" else f"{kind} entity"] += 1
    return None


def _entity_colour(entity, document, block_colour=None):
    """An entity's colour as ``#rrggbb``: its true colour, else its ACI colour (ezdxf's table:
    1 red, 5 blue, 7 white …); BYLAYER its layer's (inside a block, on layer 0, the
    reference's, as CAD draws it); BYBLOCK the reference's; None where there is none."""

    def hex_of(rgb):
        return "#{:02x}{:02x}{:02x}".format(*rgb)
    try:
        if entity.dxf.hasattr("true_color"):
            return hex_of(colors.int2rgb(entity.dxf.true_color))
        aci = entity.dxf.get("color", colors.BYLAYER)
        if aci == colors.BYBLOCK:
            return block_colour
        if aci == colors.BYLAYER:
            layer_name = str(entity.dxf.get("layer", "0"))
            if layer_name == "0" and block_colour is not None:
                return block_colour
            table = document.layers.get(layer_name) if document is not None else None
            if table is None:
                return None
            if table.dxf.hasattr("true_color"):
                return hex_of(colors.int2rgb(table.dxf.true_color))
            aci = abs(table.dxf.get("color", 7))
        return hex_of(colors.aci2rgb(aci)) if 1 <= aci <= 255 else None
    except Exception:                       # a damaged table: no colour, the rest is read
        return None


def _text_outlines(entity, tolerance, skipped):
    """A TEXT's, ATTRIB's or MTEXT's glyphs as closed outlines, in the text style's font (as
    ezdxf's text2path finds it; an MTEXT first exploded into TEXT entities by ezdxf's
    MTextExplode, in a scratch block of the document's own). A font that is not installed is
    said (ezdxf marks it in another); a text with characters its font lacks is left out,
    naming them (it would be marked as boxes)."""
    if entity.dxftype() == "MTEXT":
        scratch = entity.doc.blocks.new_anonymous_block()
        with MTextExplode(scratch) as explode:
            explode.explode(entity, destroy=False)
        texts = [e for e in scratch if e.dxftype() == "TEXT"]
    else:
        texts = [entity]
    out = []
    for text in texts:
        if not str(text.dxf.get("text", "")).strip():
            continue
        height = float(text.dxf.get("height", 1.0))
        # (The chords counted before they are made, as every curve's: see MAX_CHORDS.)
        _chords(len(text.dxf.text) * 40 * math.ceil(math.sqrt(max(height, 0) / tolerance)))
        missing = _font_misses(text, skipped)
        if missing:
            skipped[f"text entity left out: {missing}"] += 1
            continue
        for path in text2path.make_paths_from_entity(text):
            points = _xy(path.flattening(tolerance))
            if len(points) >= 2:
                out.append((points, bool(np.allclose(points[0], points[-1]))))
    return out


def _font_misses(text, skipped):
    """Why ``text`` cannot be marked in the font ezdxf takes for it (characters it lacks), or
    None; a style's font that is not installed counted in ``skipped`` as a note."""
    style = text.doc.styles.get(text.dxf.get("style", "Standard")) if text.doc else None
    asked = style.dxf.get("font", "") if style is not None else ""
    face = fonts.get_entity_font_face(text)
    if asked and not fonts.is_shx_font_name(asked) and not fonts.font_manager.has_font(asked):
        skipped[f"text entity in font {asked}, not installed: marked in {face.filename}"] += 1
    if not face.filename.lower().endswith((".ttf", ".otf", ".ttc")):
        return None
    try:
        cmap = fonts.font_manager.get_ttf_font(face.filename).getBestCmap()
    except Exception:                       # (a font ezdxf lists but cannot open)
        return None
    plain = text.plain_text() if hasattr(text, "plain_text") else str(text.dxf.text)
    lacking = "".join(dict.fromkeys(ch for ch in plain if not ch.isspace() and
                                    ord(ch) not in cmap))
    return f"{lacking!r} not in font {face.filename}" if lacking else None


def _dxf_entity(entity, tolerance, out, skipped, matrix=None, depth=0, block_colour=None):
    """Append the polylines of one entity to ``out``, in the drawing's units, each with its
    colour (:func:`_entity_colour`; ``block_colour``: the reference's, inside a block).

    Block references are not exploded by ezdxf (which makes a non-uniformly scaled polyline
    loose lines and ellipses, no longer closed): the block's entities are flattened in its own
    coordinates, finer by the reference's largest stretch, and their points mapped by the
    reference's matrix (row vectors, as ezdxf's ``Matrix44``).
    """
    kind = entity.dxftype()
    colour = _entity_colour(entity, entity.doc, block_colour)
    try:
        if kind == "INSERT":
            if depth > 50:
                raise DrawingError("block references nested more than 50 deep")
            for attrib in entity.attribs:     # placed already: the outer matrix only
                _dxf_entity(attrib, tolerance, out, skipped, matrix, depth + 1, colour)
            block = entity.block()
            if block is None:
                skipped["reference to a missing block"] += 1
                return
            for insert in (entity.multi_insert() if entity.mcount > 1 else [entity]):
                m = np.array([insert.matrix44().get_row(i) for i in range(4)])
                m = m if matrix is None else m @ matrix
                stretch = max(np.linalg.norm(m[:2, :2], 2), 1e-12)
                for child in block:
                    _dxf_entity(child, tolerance / stretch, out, skipped, m, depth + 1, colour)
            return
        found = _entity_points(entity, tolerance, skipped)
    except DrawingError:
        raise
    except Exception as error:              # one broken entity: skip it, say so
        skipped[f"{kind} entity ezdxf cannot evaluate ({_one_line(error)})"] += 1
        return
    for points, closed in ([found] if isinstance(found, tuple) else found or ()):
        out.append((points if matrix is None else points @ matrix[:2, :2] + matrix[3, :2],
                    closed, colour))


def _units(code, asked, notes):
    """``(mm per unit, what the units were taken from)``: ``asked`` (a :data:`~.reading.UNITS`
    key, None: the file's), else the file's $INSUNITS ``code``; how, said in ``notes``."""
    try:
        name = UNITS[_INSUNITS[code]][1] if code in _INSUNITS else units.decode(code)
    except (IndexError, TypeError, ValueError):     # a code AutoCAD does not define
        name = "a unit unknown to ezdxf"
    declared = f"its $INSUNITS {code}, {name}" if code else "no $INSUNITS: taken as mm"
    if asked is not None:
        notes.append(f"DXF numbers taken as {UNITS[asked][1]} (--units {asked}; "
                     f"{declared})")
        return UNITS[asked][0], f"--units {asked}"
    if code == units.InsertUnits.Unitless:
        notes.append("DXF has no units ($INSUNITS 0): taken as mm")
        return 1.0, declared
    if code in _EXACT_MM:
        factor = _EXACT_MM[code]
        if factor != 1.0:
            notes.append(f"DXF units {units.decode(code)} ($INSUNITS {code}): "
                         f"{factor:g} mm each")
        return factor, declared
    try:
        return units.conversion_factor(code, units.InsertUnits.Millimeters), declared
    except (TypeError, ValueError):
        raise DrawingError(f"DXF units $INSUNITS {code} cannot be converted to mm "
                           f"(--units says what they are)") from None


def _read_dxf(data, tolerance_mm, units_asked=None):
    """``(polylines in mm, closed flags, skipped, notes, styles, (what the units were taken
    from, mm a unit))``; ``units_asked``: the unit the numbers are in (a
    :data:`~.reading.UNITS` key), in place of the file's $INSUNITS."""

    # recover reads damaged text files in any encoding; binary DXF it does not (it takes the
    # sentinel for a group code), so that is loaded as ezdxf.readfile loads it, then audited.
    # What ezdxf logs about a damaged file becomes a note, rather than lines on the user's
    # terminal.
    logger, said = logging.getLogger("ezdxf"), BufferingHandler(1 << 30)
    said.setLevel(logging.WARNING)
    logger.addHandler(said)
    propagate, logger.propagate = logger.propagate, False
    try:
        if data.startswith(_BINARY_SENTINEL):
            try:
                document = Drawing.load(binary_tags_loader(data))
            except Exception as error:      # struct's and ezdxf's words for a cut-off file
                raise DrawingError(f"damaged binary DXF: it ends early or a group is corrupt "
                                   f"({_one_line(error)})") from None
            auditor = document.audit()
        else:
            document, auditor = recover.read(io.BytesIO(data))
    finally:
        logger.removeHandler(said)
        logger.propagate = propagate
    if auditor.has_errors:
        raise DrawingError(f"damaged DXF ({_one_line(auditor.errors[0].message)})")
    notes = [f"ezdxf: {_one_line(record.getMessage())}" for record in said.buffer[:3]]
    if auditor.has_fixes:
        notes.append(f"ezdxf repaired {len(auditor.fixes)} problem(s) in the DXF")
    factor, units_said = _units(document.units, units_asked, notes)
    out, styles, skipped = [], [], Counter()
    hidden = {layer.dxf.name.lower() for layer in document.layers
              if layer.is_off() or layer.is_frozen()}
    for entity in document.modelspace():
        # What CAD does not show is not marked (construction layers, switched-off details).
        if str(entity.dxf.get("layer", "0")).lower() in hidden or entity.dxf.get("invisible", 0):
            skipped["entity on a hidden layer"] += 1
        else:                               # flattened in the drawing's own units
            before = len(out)
            try:
                _dxf_entity(entity, tolerance_mm / factor, out, skipped)
            except TooManyChords:
                raise TooManyChords(_entity_said(entity), _size_mm(entity, factor),
                                    (units_said, factor)) from None
            # A block's entities go with the reference's layer.
            layer = str(entity.dxf.get("layer", "0"))
            styles += [PathStyle(colour=colour, layer=layer) for _, _, colour in out[before:]]
    skipped = _counted(skipped)
    return ([p * factor for p, _, _ in out], [c for _, c, _ in out], skipped, notes, styles,
            (units_said, factor))


def _entity_said(entity):
    """An entity as CAD names it: its type and handle (``CIRCLE entity #2F``)."""
    handle = entity.dxf.get("handle", None)
    return f"{entity.dxftype()} entity{f' #{handle}' if handle else ''}"


def _size_mm(entity, factor):
    """The entity's width and height in mm (ezdxf's bounding box of its control points), or
    None where ezdxf cannot say."""
    try:
        box = bbox.extents([entity], fast=True)
        return (box.size.x * factor, box.size.y * factor) if box.has_data else None
    except Exception:                       # (a damaged entity: the refusal goes without it)
        return None
