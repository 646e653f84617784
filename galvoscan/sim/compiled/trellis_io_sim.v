// Simulation model of the ECP5 I/O cell, for the compiled backend's netlist simulation
// (galvoscan/sim/compiled/netlist.py): Yosys' own (share/ecp5/common_sim.vh) drives the pad B
// as an inout, which CXXRTL cannot simulate; every pin of a galvoscan build goes one way, so
// here an input pin's pad is read (O) and an output pin's pad is driven (I). netlist.py
// refuses a bidirectional one. Used with `techmap -map`, so only the cells' instances are
// replaced.

module TRELLIS_IO (inout B, input I, input T, output O);
    parameter DIR = "INPUT";
    generate
        if (DIR == "INPUT") begin : input_pin
            assign O = B;
        end else begin : output_pin
            // T, the output's tristate, never rises in a galvoscan build (Amaranth's output
            // buffers hold it low, from a flip-flop of a constant 0); were it to, the released
            // pin reads low, as the board's pull-downs hold the laser's lines.
            assign B = T ? 1'b0 : I;
            assign O = 1'b0;
        end
    endgenerate
endmodule
