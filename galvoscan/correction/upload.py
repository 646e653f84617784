"""A correction table written into a running board, node by node, through the host client."""


__all__ = ["upload_table"]


def upload_table(board, table, *, verify=False):
    """Write every node of ``table`` through a :class:`~galvoscan.link.client.HostClient`.

    Four frames a node: ``cor_node``, ``cor_dx``, ``cor_dy`` (two's complement), then the
    ``cor_write`` strobe, which stores both offsets at once between two points. ``verify``
    reads ``errors`` afterwards and raises :class:`ValueError` if the board refused any frame.
    """
    for iy in range(table.n):
        for ix in range(table.n):
            board.write("cor_node", iy * table.n + ix)
            board.write("cor_dx", int(table.dx[iy, ix]) & 0xFFFF)
            board.write("cor_dy", int(table.dy[iy, ix]) & 0xFFFF)
            board.write("cor_write", 1)
    if verify and board.read("errors"):
        raise ValueError(f"the board counts {board.read('errors')} rejected frames")
