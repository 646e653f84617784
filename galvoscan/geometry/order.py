"""Path order: the jumps between paths (:func:`jump_length`) and an order that cuts them
(:func:`order_paths`, greedy nearest neighbour over an R-tree); mm in, mm out."""

import math

import numpy as np
import shapely


__all__ = ["order_paths", "jump_length"]


def _rotated(path, k):
    """A closed path started at its vertex ``k``."""
    return np.concatenate([path[k:-1], path[:k], path[k:k + 1]])


def jump_length(paths, start=(0.0, 0.0)):
    """mm jumped from ``start`` through ``paths`` in their order."""
    return _jumps([np.asarray(p, dtype=float) for p in paths], start)


def _jumps(paths, start):
    here, total = np.asarray(start, dtype=float), 0.0
    for path in paths:
        total += math.hypot(*(path[0] - here))
        here = path[-1]
    return total


def order_paths(paths, closed, start=(0.0, 0.0)):
    """Paths in an order that cuts the jumps between them: greedy nearest neighbour.

    Each step goes to the nearest way into a path not yet taken: either end of an open path
    (reversed when entered at its end), any vertex of a closed one (started there). If that
    order jumps further than the input order, the input order is kept.

    Returns
    -------
    ordered : list of numpy.ndarray
    jump_before_mm, jump_after_mm : float
        Sum of the jumps from ``start`` through the paths, in input order and in the order
        returned.
    """
    paths = [np.asarray(p, dtype=float) for p in paths]
    before = _jumps(paths, start)
    if not paths:
        return [], 0.0, 0.0
    # Every way in: its point, path, vertex, and whether the path is taken reversed.
    entries, owners, vertices, flips = [], [], [], []
    for index, (path, is_closed) in enumerate(zip(paths, closed)):
        ks = np.arange(len(path) - 1) if is_closed and len(path) > 2 else [0, len(path) - 1]
        entries.append(path[ks])
        owners.append(np.full(len(ks), index))
        vertices.append(ks)
        flips.append(np.array([False] * len(ks) if len(ks) != 2 or is_closed else [False, True]))
    entries, owners = np.concatenate(entries), np.concatenate(owners)
    vertices, flips = np.concatenate(vertices), np.concatenate(flips)
    # Nearest alive entry: an R-tree asked for everything within a radius that doubles until
    # something alive is found; rebuilt without the dead once they are half of it.
    alive, ways_in = np.ones(len(paths), dtype=bool), np.bincount(owners)
    extent = np.ptp(entries, axis=0).max() + 1e-9
    radius = smallest = extent / math.sqrt(len(entries))
    ordered, here, tree, members, live = [], np.asarray(start, dtype=float), None, None, 0
    for _ in paths:
        if tree is None or 2 * live < len(members):
            members = np.flatnonzero(alive[owners])
            tree, live = shapely.STRtree(shapely.points(entries[members])), len(members)
        radius = max(smallest, radius)
        while True:
            near = members[tree.query(shapely.Point(here), "dwithin", radius)]
            near = near[alive[owners[near]]]
            if len(near):
                break
            radius *= 2
        distance = np.hypot(*(entries[near] - here).T)
        best = near[np.argmin(distance)]
        radius = 2 * distance.min()
        index, k = owners[best], vertices[best]
        path = paths[index]
        if flips[best]:
            path = path[::-1]
        elif k:
            path = _rotated(path, k)
        alive[index], live = False, live - ways_in[index]
        ordered.append(path)
        here = path[-1]
    after = _jumps(ordered, start)
    if after > before:
        return paths, before, before
    return ordered, before, after
