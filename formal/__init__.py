"""SymbiYosys proofs: spec harnesses around the gateware and the runner that checks them."""
