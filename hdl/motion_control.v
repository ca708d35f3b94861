`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/motion_control.md
// Motion control: decides when the period timer may take records from the position
// FIFO. A gate opens once START_LEVEL records are queued (PMAC's rotary-buffer
// threshold) and closes when the FIFO is empty at a period boundary. Empty after a
// record that ended a block is a normal stop; empty in the middle of a block is an
// underrun: every axis holds, the sticky flag is set and the gate stays shut until the
// host clears the flag.
//
// An inhibit (the interlock, logic_outputs) keeps a shut gate shut: start_blocked pulses
// in each cycle where the gate would have opened but for it. An open gate is not closed.
//
// Latency: the gate opens the cycle after the level reaches the threshold; the core
// takes the head record at the next boundary.
module motion_control #(
    parameter LEVEL_W = 9
) (
    // clock, reset
    input  wire               clk,
    input  wire               rst,
    // control
    input  wire               core_run,
    input  wire [15:0]        start_level,
    input  wire               clear_errors,
    input  wire               inhibit,
    // position FIFO
    input  wire [LEVEL_W-1:0] fifo_level,
    input  wire               fifo_valid,
    input  wire               head_block_end,
    output wire               fifo_pop,
    // period timer
    input  wire               rec_ready,
    output wire               rec_valid,
    // status
    output wire               gate,
    output wire               underrun,
    output wire               underrun_event,
    output wire               start_blocked
);

    reg gate_reg;
    reg at_rest_reg;      // the last record consumed ended a block (or none yet)
    reg underrun_reg;

    wire boundary  = core_run && rec_ready;
    wire ran_dry   = boundary && gate_reg && !fifo_valid;
    wire consume   = boundary && gate_reg && fifo_valid;
    wire [15:0] threshold = (start_level == 16'd0) ? 16'd1 : start_level;
    wire reached   = ({{(16-LEVEL_W){1'b0}}, fifo_level} >= threshold);   // LEVEL_W <= 16
    wire underrun_now = core_run && ran_dry && !at_rest_reg;
    wire would_open   = core_run && !gate_reg && !underrun_reg && reached;   // the gate opens unless inhibited

    always @(posedge clk) begin
        if (!core_run) begin
            gate_reg    <= 1'b0;
            at_rest_reg <= 1'b1;
        end else if (ran_dry) begin
            gate_reg <= 1'b0;
        end else if (consume) begin
            at_rest_reg <= head_block_end;
        end else if (!gate_reg && !underrun_reg && reached && !inhibit) begin
            gate_reg <= 1'b1;
        end

        if (underrun_now) underrun_reg <= 1'b1;
        else if (clear_errors) underrun_reg <= 1'b0;

        if (rst) begin
            gate_reg     <= 1'b0;
            at_rest_reg  <= 1'b1;
            underrun_reg <= 1'b0;
        end
    end

    assign rec_valid      = gate_reg && fifo_valid;
    assign fifo_pop       = rec_ready && gate_reg && fifo_valid;
    assign gate           = gate_reg;
    assign underrun       = underrun_reg;
    assign underrun_event = underrun_now;
    assign start_blocked  = would_open && inhibit;

`ifdef FORMAL
    // The core is offered a record only through the open gate, the gate opens only at
    // the threshold, and an underrun is flagged exactly when the FIFO runs dry after a
    // record that did not end its block.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    // The FIFO shows a record only when it holds one (a committed record may not be readable yet).
    always @(*) if (fifo_valid) assume (fifo_level != {LEVEL_W{1'b0}});
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($rose(gate_reg)) assert ($past(reached) && !$past(underrun_reg) && $past(core_run) && !$past(inhibit));
        if ($past(!core_run)) assert (!gate_reg && at_rest_reg);
        if ($past(underrun_now)) assert (underrun_reg && !gate_reg);
        if ($past(consume)) assert (at_rest_reg == $past(head_block_end));
        if (!$past(underrun_now) && $past(clear_errors)) assert (!underrun_reg);
        if ($past(underrun_reg) && !$past(clear_errors)) assert (underrun_reg);
        cover (underrun_reg);
        cover ($past(consume) && !at_rest_reg && $past(consume, 2));
    end
    always @(*) if (rec_valid) assert (gate_reg && fifo_valid);
    // The threshold once more on the ports, not through `reached` (a wrong comparator
    // there passes the checks above): the gate opens only with at least
    // max(START_LEVEL, 1) records, and opens as soon as a closed gate without an
    // underrun sees that many.
    wire [16:0] f_level = {{(17-LEVEL_W){1'b0}}, fifo_level};
    wire [16:0] f_start = (start_level == 16'd0) ? 17'd1 : {1'b0, start_level};
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($rose(gate_reg)) assert ($past(f_level) >= $past(f_start));
        if ($past(core_run && !gate_reg && !underrun_reg && f_level >= f_start && !inhibit)) assert (gate_reg);
        // The inhibit: a gate it holds shut is reported, and a gate that opens was not held.
        if ($past(core_run && !gate_reg && !underrun_reg && f_level >= f_start && inhibit)) assert (!gate_reg && $past(start_blocked));
        if ($past(start_blocked)) assert ($past(inhibit) && $past(!gate_reg));
        cover ($past(start_blocked, 2) && gate_reg);
    end
`endif

endmodule

`default_nettype wire
