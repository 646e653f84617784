"""Deliberately broken stages of marking on the fly, to show that the fly proofs catch each
fault: the real fly offset stage and clipped-point gate with one rule changed."""

from galvoscan.gateware.fly.offset import ClippedOnWires, FlyOffset


#: Each fault of the offset stage: what it does, and the property it breaks.
OFFSET_FAULTS = {
    "wraps": ("a sum past the field wraps round (its low 16 bits)",
              "a moved point is held within the field, never wrapped"),
    "unflagged": ("a point held at the edge is not flagged",
                  "a point is flagged clipped exactly when it was held at the edge"),
    "x_only": ("only the X axis's hold flags the point",
               "a point is flagged clipped exactly when it was held at the edge"),
}

#: Each fault of the gate: what it does, and whether the correction stage is between.
GATE_FAULTS = {
    "flag_at_entry": ("the flag moves to the wires as the point enters the stage between, a "
                      "frame early", True),
    "never_gates": ("marking passes whatever the point on the wires", True),
    "gates_the_held_point": ("the gate looks at the point held between, not the one on the "
                             "wires", True),
    "direct_late": ("without a stage between, the flag of the point before", False),
}


class BrokenOffset(FlyOffset):
    def __init__(self, fault):
        if fault not in OFFSET_FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault
        super().__init__()

    def _held(self, moved, low, high):
        if self.fault == "wraps":
            return moved[:16]
        return super()._held(moved, low, high)

    def _flag(self, clipped_x, clipped_y):
        if self.fault == "unflagged":
            return 0
        if self.fault == "x_only":
            return clipped_x
        return super()._flag(clipped_x, clipped_y)


class BrokenGate(ClippedOnWires):
    def __init__(self, fault):
        if fault not in GATE_FAULTS:
            raise ValueError(f"unknown fault {fault!r}")
        self.fault = fault
        super().__init__(held=GATE_FAULTS[fault][1])

    def _moves_on(self):
        if self.fault == "flag_at_entry":
            return self.entering
        return super()._moves_on()

    def _gate(self):
        if self.fault == "never_gates":
            return 0
        if self.fault == "gates_the_held_point":
            return self.held_clipped
        if self.fault == "direct_late":
            # (The flag a clock late: the point before's while the PHY takes this one.)
            return self.on_wires & ~self.taken
        return super()._gate()
