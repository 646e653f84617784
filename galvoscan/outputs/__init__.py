"""What leaves the host: a planned job run on a board over the link (:mod:`.stream`; what the
link can carry of it, :mod:`.link_budget`), or written as a flash image the board's job player
runs alone (:mod:`.image`).
"""
