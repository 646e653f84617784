"""Board glue: pin-outs and clocking for the boards galvoscan runs on."""
