// Simulation models of the iCE40 I/O cells, for the compiled backend's netlist simulation
// (galvoscan/sim/compiled/netlist.py): Yosys' own cells_sim.v models SB_IO with a tristate
// PACKAGE_PIN, which CXXRTL cannot simulate; every pin of a galvoscan build goes one way, so
// here an output pin is driven (through the cell's output flip-flop where PIN_TYPE registers
// it) and an input pin is read (through its input flip-flop where PIN_TYPE registers it).
// Used with `techmap -map`, so only the cells' instances are replaced.

module SB_IO (
    inout PACKAGE_PIN,
    input LATCH_INPUT_VALUE, CLOCK_ENABLE, INPUT_CLK, OUTPUT_CLK, OUTPUT_ENABLE,
    input D_OUT_0, D_OUT_1,
    output D_IN_0, D_IN_1
);
    parameter [5:0] PIN_TYPE = 6'b000000;
    parameter [0:0] PULLUP = 1'b0;
    parameter [0:0] NEG_TRIGGER = 1'b0;
    parameter IO_STANDARD = "SB_LVCMOS";
    generate
        if (PIN_TYPE[5:2] == 4'b0000) begin : input_pin
            if (PIN_TYPE[1:0] == 2'b00) begin : registered
                reg q = 1'b0;
                always @(posedge INPUT_CLK) q <= PACKAGE_PIN;
                assign D_IN_0 = q;
            end else begin : plain
                assign D_IN_0 = PACKAGE_PIN;
            end
        end else begin : output_pin
            if (PIN_TYPE[5:2] == 4'b1101 || PIN_TYPE[5:2] == 4'b0101) begin : registered
                // (Out of configuration low, as the cells' flip-flops come.)
                reg q = 1'b0;
                always @(posedge OUTPUT_CLK) q <= D_OUT_0;
                assign PACKAGE_PIN = q;
            end else begin : plain
                assign PACKAGE_PIN = D_OUT_0;
            end
            assign D_IN_0 = 1'b0;
        end
    endgenerate
    assign D_IN_1 = 1'b0;
endmodule

module SB_GB_IO (
    inout PACKAGE_PIN,
    input LATCH_INPUT_VALUE, CLOCK_ENABLE, INPUT_CLK, OUTPUT_CLK, OUTPUT_ENABLE,
    input D_OUT_0, D_OUT_1,
    output D_IN_0, D_IN_1, GLOBAL_BUFFER_OUTPUT
);
    parameter [5:0] PIN_TYPE = 6'b000000;
    parameter [0:0] PULLUP = 1'b0;
    parameter [0:0] NEG_TRIGGER = 1'b0;
    parameter IO_STANDARD = "SB_LVCMOS";
    assign GLOBAL_BUFFER_OUTPUT = PACKAGE_PIN;
    assign D_IN_0 = PACKAGE_PIN;
    assign D_IN_1 = 1'b0;
endmodule
