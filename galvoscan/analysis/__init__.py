"""Scan analysis: how a scan pattern moves the mirrors and doses the work piece (issue 5).

The data flow follows the hardware: commanded XY2-100 frames (from the gateware, or the Python
model of its sequencer that the full-pattern replay test proves equal) → mirror model
(:mod:`.galvo`) → laser pulses along the real path → dose map and metrics (:mod:`.dose`).
"""
