"""The field-distortion correction table and its exact integer arithmetic (Zhu & Zhang's
bilinear grid; README "Distortion correction").

The table is an ``n × n`` grid of nodes spread evenly over the whole 16-bit field, ``n = 2^k + 1``,
so that node ``i`` sits at galvo position ``i × 2^(16-k)`` (the last node at 65536, just past the
field edge) and a position splits into a cell index (its top ``k`` bits) and a fraction within
the cell (the other ``s = 16 - k`` bits), with no division. Each node holds a signed offset
``(dx, dy)`` in galvo units that is *added* to a position there: the table says where to command
the mirrors so that the spot lands where it was asked to.

Between nodes the offset is interpolated bilinearly, exactly as the gateware does it (so this is
the reference the gateware is tested against, bit for bit): with ``W = 2^s``, cell fractions
``fx``, ``fy`` and the cell's corner offsets ``d00`` (lower left), ``d10`` (+x), ``d01`` (+y),
``d11``::

    rnd(v)  = (v + W/2) >> s                     (round half up, arithmetic shift)
    top     = rnd(d00 × (W - fx) + d10 × fx)
    bottom  = rnd(d01 × (W - fx) + d11 × fx)
    offset  = rnd(top × (W - fy) + bottom × fy)
    output  = clamp(position + offset, 0, 65535)

All products are 16 × 16-bit signed, the size of one iCE40 DSP. The table is a plain object of
integers: the gateware's RAM, the host tools and the analysis all use the same one.
"""

import numpy as np


__all__ = ["CorrectionTable", "TABLE_SIZES", "OFFSET_MIN", "OFFSET_MAX"]


#: Node counts per axis the gateware accepts: 2^k + 1 with k from 2 to 6.
TABLE_SIZES = (5, 9, 17, 33, 65)

#: Range of a node offset in galvo units (signed 16-bit).
OFFSET_MIN, OFFSET_MAX = -32768, 32767

_FIELD_MAX = 0xFFFF


class CorrectionTable:
    """An ``n × n`` table of (dx, dy) node offsets in galvo units.

    Parameters
    ----------
    dx, dy : array-like of int, shape (n, n)
        Offsets indexed ``[iy][ix]``: row ``iy`` is the Y node, column ``ix`` the X node. Node
        ``(ix, iy)`` sits at galvo position ``(ix, iy) × 65536 / (n - 1)``. Integers from
        −32768 to 32767.

    Attributes
    ----------
    n : int
        Nodes per axis, one of :data:`TABLE_SIZES`.
    shift : int
        Bits of a position below the cell index: cells are ``2^shift`` units wide.
    """

    def __init__(self, dx, dy):
        dx = np.asarray(dx)
        dy = np.asarray(dy)
        if dx.ndim != 2 or dx.shape != dy.shape or dx.shape[0] != dx.shape[1]:
            raise ValueError(f"dx and dy must be square tables of the same size, not "
                             f"{dx.shape} and {dy.shape}")
        n = dx.shape[0]
        if n not in TABLE_SIZES:
            raise ValueError(f"a correction table has {', '.join(map(str, TABLE_SIZES))} nodes "
                             f"per axis (2^k + 1), not {n}")
        for name, values in (("dx", dx), ("dy", dy)):
            if not np.issubdtype(values.dtype, np.integer):
                if not np.all(np.isfinite(values)) or np.any(values != np.round(values)):
                    raise ValueError(f"{name} must hold whole galvo units")
            if values.min() < OFFSET_MIN or values.max() > OFFSET_MAX:
                raise ValueError(f"{name} offsets must lie in {OFFSET_MIN} … {OFFSET_MAX} galvo "
                                 f"units, not {values.min()} … {values.max()}")
        self.n = n
        self.shift = 16 - (n - 1).bit_length() + 1
        self.dx = dx.astype(np.int64)
        self.dy = dy.astype(np.int64)

    @classmethod
    def identity(cls, n=17):
        """A table of zero offsets: positions pass unchanged."""
        if n not in TABLE_SIZES:
            raise ValueError(f"n must be one of {', '.join(map(str, TABLE_SIZES))}, not {n!r}")
        zeros = np.zeros((n, n), dtype=np.int64)
        return cls(zeros, zeros)

    @property
    def node_spacing(self):
        """Galvo units between neighbouring nodes."""
        return 1 << self.shift

    def node_positions(self):
        """Galvo positions of the nodes along one axis (the last is 65536)."""
        return np.arange(self.n, dtype=np.int64) << self.shift

    def words(self):
        """The RAM image: node ``iy × n + ix`` holds ``dy << 16 | dx`` (two's complement)."""
        dx = (self.dx & 0xFFFF).ravel()
        dy = (self.dy & 0xFFFF).ravel()
        return [int(w) for w in (dy << 16) | dx]

    def with_node(self, ix, iy, dx, dy):
        """A copy with one node changed."""
        new_dx, new_dy = self.dx.copy(), self.dy.copy()
        new_dx[iy, ix], new_dy[iy, ix] = dx, dy
        return CorrectionTable(new_dx, new_dy)

    def resampled(self, n):
        """The same correction on ``n`` nodes per axis.

        To fewer nodes, every ``m``-th node is kept (exact on those nodes); to more, the new
        nodes take this table's own interpolated offsets.
        """
        if n not in TABLE_SIZES:
            raise ValueError(f"n must be one of {', '.join(map(str, TABLE_SIZES))}, not {n!r}")
        if n <= self.n:
            step = (self.n - 1) // (n - 1)
            return CorrectionTable(self.dx[::step, ::step], self.dy[::step, ::step])
        nodes = np.minimum(np.arange(n, dtype=np.int64) << (16 - (n - 1).bit_length() + 1),
                           _FIELD_MAX)
        gx, gy = np.meshgrid(nodes, nodes)
        ox, oy = self.offsets(gx, gy)
        return CorrectionTable(ox, oy)

    def offsets(self, x, y):
        """Interpolated ``(dx, dy)`` at galvo positions ``x``, ``y`` (arrays of 0 … 65535)."""
        x = np.asarray(x, dtype=np.int64)
        y = np.asarray(y, dtype=np.int64)
        if np.any((x < 0) | (x > _FIELD_MAX) | (y < 0) | (y > _FIELD_MAX)):
            raise ValueError("positions must lie in 0 … 65535 galvo units")
        s = self.shift
        whole, half = 1 << s, 1 << (s - 1)
        ix, fx = x >> s, x & (whole - 1)
        iy, fy = y >> s, y & (whole - 1)

        def axis(table):
            d00, d10 = table[iy, ix], table[iy, ix + 1]
            d01, d11 = table[iy + 1, ix], table[iy + 1, ix + 1]
            top = (d00 * (whole - fx) + d10 * fx + half) >> s
            bottom = (d01 * (whole - fx) + d11 * fx + half) >> s
            return (top * (whole - fy) + bottom * fy + half) >> s

        return axis(self.dx), axis(self.dy)

    def apply(self, x, y):
        """Corrected positions and a clipped flag: ``(x', y', clipped)``, as the gateware."""
        x = np.asarray(x, dtype=np.int64)
        y = np.asarray(y, dtype=np.int64)
        ox, oy = self.offsets(x, y)
        wide_x, wide_y = x + ox, y + oy
        clipped = (wide_x < 0) | (wide_x > _FIELD_MAX) | (wide_y < 0) | (wide_y > _FIELD_MAX)
        return np.clip(wide_x, 0, _FIELD_MAX), np.clip(wide_y, 0, _FIELD_MAX), clipped

    def __eq__(self, other):
        return isinstance(other, CorrectionTable) and self.n == other.n and \
            np.array_equal(self.dx, other.dx) and np.array_equal(self.dy, other.dy)

    def __repr__(self):
        return (f"CorrectionTable(n={self.n}, dx {self.dx.min()}…{self.dx.max()}, "
                f"dy {self.dy.min()}…{self.dy.max()})")
