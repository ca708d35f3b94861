`timescale 1ns / 1ps
`default_nettype none
// The run-time mutant selector of the RTL mutation build (scripts/mutants_rtl.py,
// rust/finestep-rtl-sys feature netlist-mutants): every mutated module of the netlist
// has one; `sel` is FINESTEP_MUTSEL from the environment, read once through DPI
// (sim/mutants_rtl/finestep_mutsel.cpp); 0 (unset) is the unmutated design. Not
// Verilog-2005 (DPI): it is never part of hdl/ or a synthesis.
module finestep_mutsel (
    output reg [15:0] sel
);
    import "DPI-C" function int finestep_mutsel_env();
    initial sel = finestep_mutsel_env();
endmodule
`default_nettype wire
