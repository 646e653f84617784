"""The SVG elements that would sink a whole drawing in svgelements, found before it reads the
file and left out, each with a note that names it, as a browser draws the rest.

Two kinds, both errors by the SVG specification, which a browser renders around:

* a ``<path>`` whose data does not start with a moveto (SVG 1.1 §8.3.2: "must begin with a
  moveto"; a browser draws none of it). svgelements starts such a path from no point and, for
  some commands (``H``, ``V``, ``A``), fails on it with Python's words;
* a ``<use>`` that refers to itself, directly or through other ``<use>`` elements (SVG 2
  §5.6.1: a circular reference is an error; the element is not rendered). svgelements follows
  it until Python's recursion limit.

Everything else is left to svgelements: the file is rewritten only when something is left out,
or to name the Inkscape layers: each ``<g inkscape:groupmode="layer">`` is given
:data:`LAYER_ATTRIBUTE`, its label (else its id), which svgelements hands down to everything
inside it (an inner layer's own in place of its parent's), so each shape knows its layer.
"""

import xml.etree.ElementTree as ElementTree


__all__ = ["screen_svg", "LAYER_ATTRIBUTE"]

#: The attribute each Inkscape layer group is given, its label: what a shape's layer is read
#: from (as an attribute the SVG's own styling cannot have set).
LAYER_ATTRIBUTE = "data-galvoscan-layer"
_INKSCAPE = "{http://www.inkscape.org/namespaces/inkscape}"


_XLINK_HREF = "{http://www.w3.org/1999/xlink}href"
#: What may come before a path's first command (SVG's wsp).
_LEADING = " \t\r\n\f"


def _kind(element):
    tag = element.tag
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def _named(element, kind, number):
    """``<path> 'outline'``, or by its place among its kind when it has no id."""
    ident = element.get("id")
    return f"<{kind}> {ident!r}" if ident else f"<{kind}> number {number}"


def _circular_uses(root):
    """The ``<use>`` elements on a circle of references: each one that is reached again by
    expanding what it refers to."""
    by_id = {element.get("id"): element for element in root.iter() if element.get("id")}
    uses = [element for element in root.iter() if _kind(element) == "use"]

    def expands_to(use):
        """The ``<use>`` elements inside what ``use`` refers to (the target itself among
        them, and ``use`` itself when it lies inside its own target)."""
        ref = use.get(_XLINK_HREF) or use.get("href") or ""
        target = by_id.get(ref[1:]) if ref.startswith("#") else None
        return [] if target is None else [e for e in target.iter() if _kind(e) == "use"]

    reached = {id(use): expands_to(use) for use in uses}
    circular = []
    for use in uses:
        seen, todo = set(), list(reached[id(use)])
        while todo:
            other = todo.pop()
            if other is use:
                circular.append(use)
                break
            if id(other) not in seen:
                seen.add(id(other))
                todo.extend(reached.get(id(other), ()))
    return circular


def screen_svg(data):
    """``(data, notes)``: the SVG's bytes with the elements above left out (a note for
    each) and its layers named. A file that is not well-formed XML is handed on as it is, for svgelements to say
    what is wrong with it."""
    try:
        root = ElementTree.fromstring(data)
    except (ElementTree.ParseError, ValueError):
        return data, []
    parents = {child: parent for parent in root.iter() for child in parent}
    left_out, notes = [], []
    paths = [element for element in root.iter() if _kind(element) == "path"]
    for number, path in enumerate(paths, 1):
        commands = (path.get("d") or "").lstrip(_LEADING)
        if commands and commands[0] not in "Mm":
            left_out.append(path)
            notes.append(f"{_named(path, 'path', number)} starts without a moveto (M): left "
                         f"out, as a browser draws none of it")
    uses = [element for element in root.iter() if _kind(element) == "use"]
    for use in _circular_uses(root):
        left_out.append(use)
        notes.append(f"{_named(use, 'use', uses.index(use) + 1)} refers to itself (directly "
                     f"or through other <use> elements): left out, as a browser draws none "
                     f"of it")
    layers = [g for g in root.iter() if _kind(g) == "g" and
              g.get(_INKSCAPE + "groupmode") == "layer"]
    for number, group in enumerate(layers, 1):
        group.set(LAYER_ATTRIBUTE, group.get(_INKSCAPE + "label") or group.get("id") or
                  f"layer {number}")
    if not left_out and not layers:
        return data, []
    for element in left_out:
        if element in parents:
            parents[element].remove(element)
    return ElementTree.tostring(root), notes
