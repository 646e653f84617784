"""Correction table files: galvoscan's own, SCANLAB ``.ctb`` and JCZ ``.cor``.

**galvoscan (.json)**: ``{"format": "galvoscan-correction-table", "version": 1, "nodes": n,
"units": "galvo", "dx": [[...]], "dy": [[...]], "source": "..."}``; ``dx[iy][ix]`` is the offset
in galvo units added at node (ix, iy), which sits at ``(ix, iy) × 65536 / (n - 1)``. Any of the
gateware's sizes (5, 9, 17, 33, 65).

**SCANLAB .ctb** (as the issue that asked for it states it, and as a public tool reads RTC3/4
files): no header, two 65 × 65 tables of little-endian 16-bit words, X then Y, each row by row
(X index fastest). Each word is the *absolute* output for its node; the identity table holds
``i × 1024`` at node ``i`` (65535 for the last, which 16 bits cannot hold). Words are read as
unsigned unless ``signed=True`` (centre 0, identity ``(i − 32) × 1024``).

**JCZ .cor** (EzCad2/LMC boards; layout as documented by the MeerK40t project's Balor driver):
version 2 starts with the label "JCZ_COR_2_1" in UTF-16LE padded to 22 bytes, 6 reserved bytes
and a float64 scale (galvo units per mm), then 65 × 65 pairs of little-endian int32 (dx, dy),
row by row (Y outer). Version 1 ("LMC1COR_1.0") has a 2-byte gap, 63 float64 header values (the
scale is the 44th) and float64 pairs. Both read; version 2 written.

Neither vendor publishes its format; no vendor file was available to check the axis order or
the sign against, so a table brought over should be checked with a test mark first (the
``galvoscan correct show`` plot tells a mirrored table at a glance).
"""

import json
import struct
from pathlib import Path

import numpy as np

from ..gateware.field.correction_table import OFFSET_MAX, OFFSET_MIN, TABLE_SIZES, \
    CorrectionTable


__all__ = ["TableFileError", "FORMATS", "load_table", "save_table", "read_ctb", "write_ctb",
           "ctb_clipped_nodes", "read_cor", "write_cor", "read_json", "write_json"]


#: File formats by suffix.
FORMATS = {".json": "galvoscan", ".ctb": "SCANLAB", ".cor": "JCZ"}

_LENS_NODES = 65
_CTB_BYTES = 2 * _LENS_NODES * _LENS_NODES * 2
_COR_V2_LABEL = "JCZ_COR_2_1"
_COR_V1_LABEL = "LMC1COR_1.0"
_COR_LABEL_BYTES = 0x16
_COR_V2_HEADER = _COR_LABEL_BYTES + 6 + 8
_COR_V1_HEADER = _COR_LABEL_BYTES + 2 + 63 * 8
_FORMAT_NAME = "galvoscan-correction-table"


class TableFileError(ValueError):
    """A correction table file that cannot be read or written; the message says why."""


def _table(dx, dy, what):
    dx = np.asarray(dx)
    dy = np.asarray(dy)
    if min(dx.min(), dy.min()) < OFFSET_MIN or max(dx.max(), dy.max()) > OFFSET_MAX:
        raise TableFileError(f"{what}: offsets beyond ±32767 galvo units "
                             f"(dx {dx.min()}…{dx.max()}, dy {dy.min()}…{dy.max()})")
    try:
        return CorrectionTable(dx.astype(np.int64), dy.astype(np.int64))
    except ValueError as error:
        raise TableFileError(f"{what}: {error}") from None


def _lens_table(table):
    """The table on 65 nodes, as lens files hold it."""
    return table if table.n == _LENS_NODES else table.resampled(_LENS_NODES)


# --- SCANLAB .ctb ---------------------------------------------------------------------------

def _ctb_identity(signed):
    nodes = np.arange(_LENS_NODES, dtype=np.int64) * 1024
    return np.minimum(nodes - 32768, 32767) if signed else np.minimum(nodes, 65535)


def read_ctb(data, *, signed=False, what="ctb file"):
    """A :class:`CorrectionTable` (65 nodes) from the bytes of a ``.ctb`` file."""
    if len(data) != _CTB_BYTES:
        raise TableFileError(f"{what}: a .ctb file is {_CTB_BYTES} bytes (two 65 × 65 tables "
                             f"of 16-bit words), not {len(data)}")
    words = np.frombuffer(data, dtype="<i2" if signed else "<u2").astype(np.int64)
    absolute_x, absolute_y = words.reshape(2, _LENS_NODES, _LENS_NODES)
    identity = _ctb_identity(signed)
    return _table(absolute_x - identity[None, :], absolute_y - identity[:, None], what)


def _ctb_absolute(table, signed):
    table = _lens_table(table)
    identity = _ctb_identity(signed)
    return table.dx + identity[None, :], table.dy + identity[:, None]


def ctb_clipped_nodes(table, *, signed=False):
    """Nodes whose output lies outside what a ``.ctb`` word can hold (beyond the field)."""
    low, high = (-32768, 32767) if signed else (0, 65535)
    absolute_x, absolute_y = _ctb_absolute(table, signed)
    return int(np.count_nonzero((absolute_x < low) | (absolute_x > high) |
                                (absolute_y < low) | (absolute_y > high)))


def write_ctb(table, *, signed=False):
    """The bytes of a ``.ctb`` file for ``table`` (resampled to 65 nodes if needed).

    A ``.ctb`` holds absolute outputs, so a node that aims beyond the field edge is clipped to
    it (:func:`ctb_clipped_nodes` counts them; the spot cannot go there anyway).
    """
    low, high = (-32768, 32767) if signed else (0, 65535)
    absolute_x, absolute_y = _ctb_absolute(table, signed)
    return np.stack([np.clip(absolute_x, low, high), np.clip(absolute_y, low, high)]) \
        .astype("<i2" if signed else "<u2").tobytes()


# --- JCZ .cor -------------------------------------------------------------------------------

def _cor_label(data):
    return data[:_COR_LABEL_BYTES].decode("utf-16-le", errors="replace").rstrip("\x00")


def read_cor(data, *, what="cor file"):
    """``(table, units_per_mm)`` from the bytes of a JCZ ``.cor`` file (version 1 or 2)."""
    label = _cor_label(data)
    count = _LENS_NODES * _LENS_NODES
    if label.startswith(_COR_V2_LABEL):
        header, pair, kind = _COR_V2_HEADER, "<ii", "int32"
        scale_at = _COR_LABEL_BYTES + 6
    elif label.startswith(_COR_V1_LABEL):
        header, pair, kind = _COR_V1_HEADER, "<dd", "float64"
        scale_at = _COR_LABEL_BYTES + 2 + 43 * 8
    else:
        raise TableFileError(f"{what}: not a JCZ correction file (label {label[:16]!r}, "
                             f"expected {_COR_V2_LABEL!r} or {_COR_V1_LABEL!r})")
    size = header + count * struct.calcsize(pair)
    if len(data) < size:
        raise TableFileError(f"{what}: cut short: {len(data)} bytes, a {label} file has {size}")
    scale, = struct.unpack_from("<d", data, scale_at)
    values = np.frombuffer(data, dtype="<i4" if kind == "int32" else "<f8", count=2 * count,
                           offset=header).astype(float)
    if not np.all(np.isfinite(values)):
        raise TableFileError(f"{what}: offsets that are not numbers")
    values = np.round(values).reshape(_LENS_NODES, _LENS_NODES, 2)
    return _table(values[..., 0], values[..., 1], what), scale


def write_cor(table, *, units_per_mm):
    """The bytes of a version 2 JCZ ``.cor`` file (resampled to 65 nodes if needed)."""
    if not isinstance(units_per_mm, (int, float)) or not np.isfinite(units_per_mm) or \
            units_per_mm <= 0:
        raise TableFileError(f"units_per_mm must be a positive number, not {units_per_mm!r}")
    table = _lens_table(table)
    label = _COR_V2_LABEL.encode("utf-16-le").ljust(_COR_LABEL_BYTES, b"\x00")
    pairs = np.stack([table.dx, table.dy], axis=-1).astype("<i4")
    return label + bytes(6) + struct.pack("<d", float(units_per_mm)) + pairs.tobytes()


# --- galvoscan .json ------------------------------------------------------------------------

def read_json(text, *, what="table file"):
    """A :class:`CorrectionTable` from galvoscan's own JSON format."""
    try:
        document = json.loads(text)
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise TableFileError(f"{what}: not JSON ({error})") from None
    if not isinstance(document, dict) or document.get("format") != _FORMAT_NAME:
        raise TableFileError(f"{what}: not a galvoscan correction table (no \"format\": "
                             f"\"{_FORMAT_NAME}\")")
    if document.get("version") != 1:
        raise TableFileError(f"{what}: version {document.get('version')!r}; this galvoscan "
                             f"reads version 1")
    nodes = document.get("nodes")
    if nodes not in TABLE_SIZES:
        raise TableFileError(f"{what}: nodes must be one of {TABLE_SIZES}, not {nodes!r}")
    grids = []
    for name in ("dx", "dy"):
        grid = document.get(name)
        if not (isinstance(grid, list) and len(grid) == nodes and
                all(isinstance(row, list) and len(row) == nodes and
                    all(isinstance(v, int) and not isinstance(v, bool) for v in row)
                    for row in grid)):
            raise TableFileError(f"{what}: {name} must be {nodes} rows of {nodes} integers")
        grids.append(np.array(grid, dtype=np.int64))
    return _table(*grids, what)


def write_json(table, *, source=""):
    """galvoscan's own JSON text for ``table``; ``source`` says where it came from."""
    document = {"format": _FORMAT_NAME, "version": 1, "nodes": table.n, "units": "galvo",
                "layout": "dx[iy][ix] is added at galvo position (ix, iy) * 65536 / (nodes - 1)",
                "source": source, "dx": table.dx.tolist(), "dy": table.dy.tolist()}
    return json.dumps(document, indent=None, separators=(",", ":")) + "\n"


# --- by file name ---------------------------------------------------------------------------

def load_table(path, *, nodes=None, signed_ctb=False):
    """The table in ``path`` (format from its suffix), resampled to ``nodes`` if given."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise TableFileError(f"{path}: unknown table format {suffix or '(no suffix)'}; "
                             f"known: {', '.join(FORMATS)}")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise TableFileError(f"{path}: {error.strerror}") from None
    if suffix == ".json":
        table = read_json(data, what=str(path))
    elif suffix == ".ctb":
        table = read_ctb(data, signed=signed_ctb, what=str(path))
    else:
        table, _ = read_cor(data, what=str(path))
    if nodes is not None and nodes != table.n:
        try:
            table = table.resampled(nodes)
        except ValueError as error:
            raise TableFileError(f"{path}: {error}") from None
    return table


def save_table(path, table, *, source="", units_per_mm=None, signed_ctb=False):
    """Write ``table`` to ``path`` in the format its suffix names; returns warnings (text)."""
    path = Path(path)
    suffix = path.suffix.lower()
    warnings = []
    if suffix == ".json":
        path.write_text(write_json(table, source=source))
    elif suffix == ".ctb":
        clipped = ctb_clipped_nodes(table, signed=signed_ctb)
        if clipped:
            warnings.append(f"{path}: {clipped} of 4225 nodes aim beyond the field edge and "
                            f"were clipped to it (a .ctb holds absolute positions)")
        path.write_bytes(write_ctb(table, signed=signed_ctb))
    elif suffix == ".cor":
        if units_per_mm is None:
            raise TableFileError(f"{path}: a .cor file records the lens scale: give "
                                 f"units_per_mm (galvo units per mm)")
        path.write_bytes(write_cor(table, units_per_mm=units_per_mm))
    else:
        raise TableFileError(f"{path}: unknown table format {suffix or '(no suffix)'}; "
                             f"known: {', '.join(FORMATS)}")
    return warnings
