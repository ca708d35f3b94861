// The ECP5 cells of a synth_ecp5 netlist for Verilator: Yosys's own simulation models
// (ecp5/common_sim.vh, ecp5/ccu2c_sim.vh from the Yosys share directory, found by
// rust/finestep-rtl-sys/build.rs) and, for the block RAM Yosys ships only as a black box,
// sim/netlist/ecp5_dp16kd.v. NO_INCLUDES leaves out the FD1*/I-O wrappers (cells_ff.vh,
// cells_io.vh), which synth_ecp5's output does not use.
`define NO_INCLUDES
`include "common_sim.vh"
`include "ccu2c_sim.vh"
`include "ecp5_dp16kd.v"
