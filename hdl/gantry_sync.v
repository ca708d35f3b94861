`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/gantry_sync.md
// Gantry synchronisation (seed 001): two motors move one gantry axis. The slave axis's
// step shaper takes the master axis's step requests instead of its own DDA's; in
// synchronised mode a correction, decided once per tick from the difference of two
// encoder (or grating) channels, inserts a slave step (a request where the master has
// none) or deletes one (a master request not passed on). Done on the requests before
// the slave's shaper, so every slave pulse keeps the slave axis's drive timing. The
// difference is measured in both modes; an alarm (sticky) flags it past a limit.
//
// A correction against the master's motion deletes a master step rather than reversing
// the slave (seed 001's deletion); one with the motion, or at rest, inserts a step.
// Engagement waits until both axes are at rest (no increment, and no ext_busy: a record
// of the core's pbp block runs on the axis's pair), so the offset is taken square and no
// speed changes under way. The master's motion is its increment's sign, or ext_up /
// ext_down (the direction of the pbp block's next step on it). The alarm stops the
// corrections (and the top halts on it): a dead or mirrored channel cannot run the
// slave away.
//
// The core selects: the shaper of axis slave_axis takes slave_req_* while engaged.
// Latency: a count change in cycle n is in diff at n+1, error at n+2, alarm at n+3; a
// correction decided at a tick in cycle t can reach the slave's shaper in t+1.
// Invariants (formal): the slave request is the master's plus the correction applied
// in the cycle, at most one correction is applied per tick, and corrections counts them.
module gantry_sync #(
    parameter N_AXES = 4,
    parameter TICK_W = 24
) (
    // clock, reset
    input  wire              clk,
    input  wire              rst,
    // configuration
    input  wire              enable,
    input  wire              sync,            // 0 forward (plain copy), 1 synchronised
    input  wire [2:0]        master,
    input  wire [2:0]        slave,
    input  wire [TICK_W-1:0] tick_clocks,     // the compensation tick; 0 acts as 1
    input  wire [15:0]       deadband,        // counts
    input  wire [15:0]       limit,           // counts
    // feedback: the two channels' counts
    input  wire [31:0]       enc_master,
    input  wire [31:0]       enc_slave,
    // every axis's increment in this period and DDA step request
    input  wire [32*N_AXES-1:0] inc,
    input  wire [N_AXES-1:0] req_valid,
    input  wire [N_AXES-1:0] req_negative,
    // every axis's motion besides its increment (the core's pbp block): busy (not at
    // rest: a record runs on its pair) and the direction its next step would take
    input  wire [N_AXES-1:0] ext_busy,
    input  wire [N_AXES-1:0] ext_up,
    input  wire [N_AXES-1:0] ext_down,
    // commands
    input  wire              halt,
    input  wire              clear_errors,
    input  wire              clear_counters,
    // the slave shaper's request
    output wire              slave_req_valid,
    output wire              slave_req_negative,
    // status
    output wire              engaged,
    output wire [2:0]        master_axis,     // m (for the core's formal properties)
    output wire [2:0]        slave_axis,
    output wire              alarm,
    output wire              refused,
    output wire [31:0]       error,
    output wire [15:0]       corrections
);

    localparam [TICK_W-1:0] TICK_ONE = {{(TICK_W-1){1'b0}}, 1'b1};

    // Axis numbers are 3 bits: more than 8 axes cannot be told apart (elaboration fails).
    generate
        if (N_AXES > 8 || N_AXES < 1) begin : n_axes_must_be_1_to_8
            gantry_sync_n_axes_must_be_1_to_8 unsupported ();
        end
    endgenerate

    reg              engaged_reg;
    reg [2:0]        master_reg;
    reg [2:0]        slave_reg;
    reg [31:0]       diff_reg;
    reg [31:0]       offset_reg;
    reg [31:0]       error_reg;
    reg [TICK_W-1:0] tick_cnt_reg;
    reg              corr_valid_reg;      // a correction waits to be applied
    reg              corr_negative_reg;   // ... and it is -1
    reg [15:0]       corrections_reg;
    reg              alarm_reg;
    reg              refused_reg;

    wire [3:0] n_axes = N_AXES[3:0];    // N_AXES <= 8
    wire config_valid = (master != slave) && ({1'b0, master} < n_axes) && ({1'b0, slave} < n_axes);
    // Increments of all eight possible axes (0 above N_AXES).
    wire [255:0] inc_all     = {{(256-32*N_AXES){1'b0}}, inc};
    wire [31:0]  master_inc  = inc_all[32*master_reg +: 32];
    wire [7:0]   busy_all    = {{(8-N_AXES){1'b0}}, ext_busy};
    wire [7:0]   up_all      = {{(8-N_AXES){1'b0}}, ext_up};
    wire [7:0]   down_all    = {{(8-N_AXES){1'b0}}, ext_down};
    wire at_rest = (inc_all[32*master +: 32] == 32'd0) && (inc_all[32*slave +: 32] == 32'd0)
                   && !busy_all[master] && !busy_all[slave];
    wire engage       = !engaged_reg && enable && config_valid && at_rest;
    wire disengage    = engaged_reg && !enable;

    wire [TICK_W-1:0] tick_last = (tick_clocks == {TICK_W{1'b0}}) ? {TICK_W{1'b0}} : tick_clocks - TICK_ONE;
    // >=: a tick lowered while engaged comes at once instead of after the counter wraps.
    wire tick = engaged_reg && (tick_cnt_reg >= tick_last);

    // |error| as an unsigned 32-bit value (|-2^31| = 2^31); the deadband test in 33 bits.
    wire [31:0]        error_mag = error_reg[31] ? (~error_reg + 32'd1) : error_reg;
    wire signed [32:0] error_wide = {error_reg[31], error_reg};
    wire signed [32:0] band_wide  = {17'd0, deadband};
    wire ahead  = error_wide > band_wide;       // the slave is behind: +1
    wire behind = error_wide < -band_wide;      // the slave is ahead: -1

    // The master's request this cycle, and what the correction does with it.
    wire [7:0] valid_all    = {{(8-N_AXES){1'b0}}, req_valid};
    wire [7:0] negative_all = {{(8-N_AXES){1'b0}}, req_negative};
    wire master_valid    = valid_all[master_reg];
    wire master_negative = negative_all[master_reg];
    // The correction goes into the request (synchronised, enabled, no alarm) as a
    // deletion of a master request against it, or as an insertion in a cycle without a
    // master request unless the master moves against it (then it waits to delete); it
    // counts as applied unless halted (the halted shaper drops every request).
    wire moving_up   = ((master_inc != 32'd0) && !master_inc[31]) || up_all[master_reg];
    wire moving_down = master_inc[31] || down_all[master_reg];
    wire against     = corr_negative_reg ? moving_up : moving_down;
    wire takes   = corr_valid_reg && sync && enable && !alarm_reg &&
                   (master_valid ? (master_negative != corr_negative_reg) : !against);
    wire applied = takes && !halt;
    assign slave_req_valid    = takes ? !master_valid : master_valid;
    assign slave_req_negative = (takes && !master_valid) ? corr_negative_reg : master_negative;

    always @(posedge clk) begin
        diff_reg  <= enc_master - enc_slave;
        error_reg <= engaged_reg ? diff_reg - offset_reg : 32'd0;

        if (engage) begin
            engaged_reg <= 1'b1;
            master_reg  <= master;
            slave_reg   <= slave;
            offset_reg  <= enc_master - enc_slave;   // this cycle's difference
        end else if (disengage) begin
            engaged_reg <= 1'b0;
        end

        if (!engaged_reg || disengage || tick) tick_cnt_reg <= {TICK_W{1'b0}};
        else tick_cnt_reg <= tick_cnt_reg + TICK_ONE;

        if (halt || alarm_reg || !engaged_reg || disengage || !sync) begin
            corr_valid_reg <= 1'b0;
        end else if (tick) begin
            corr_valid_reg    <= ahead || behind;
            corr_negative_reg <= behind;
        end else if (applied) begin
            corr_valid_reg <= 1'b0;
        end

        if (clear_counters) corrections_reg <= 16'd0;
        else if (applied) corrections_reg <= corr_negative_reg ? corrections_reg - 16'd1 : corrections_reg + 16'd1;

        if (engaged_reg && (error_mag > {16'd0, limit})) alarm_reg <= 1'b1;
        else if (clear_errors) alarm_reg <= 1'b0;
        if (enable && !config_valid && !engaged_reg) refused_reg <= 1'b1;
        else if (clear_errors) refused_reg <= 1'b0;

        if (rst) begin
            engaged_reg       <= 1'b0;
            master_reg        <= 3'd0;
            slave_reg         <= 3'd0;
            diff_reg          <= 32'd0;
            offset_reg        <= 32'd0;
            error_reg         <= 32'd0;
            tick_cnt_reg      <= {TICK_W{1'b0}};
            corr_valid_reg    <= 1'b0;
            corr_negative_reg <= 1'b0;
            corrections_reg   <= 16'd0;
            alarm_reg         <= 1'b0;
            refused_reg       <= 1'b0;
        end
    end

    assign engaged     = engaged_reg;
    assign master_axis = master_reg;
    assign slave_axis  = slave_reg;
    assign alarm       = alarm_reg;
    assign refused     = refused_reg;
    assign error       = error_reg;
    assign corrections = corrections_reg;

`ifdef FORMAL
    // The slave moves by the master's request plus the correction applied; a correction
    // exists only while engaged and synchronised; at most one is applied between two
    // ticks (counted exactly); the error and the alarm follow the counts with the
    // latencies of the header; the pair taken at engagement is a valid one.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire [7:0] f_valid_all = {{(8-N_AXES){1'b0}}, req_valid};
    wire [7:0] f_neg_all   = {{(8-N_AXES){1'b0}}, req_negative};
    wire signed [2:0] f_master_step = f_valid_all[master_reg] ? (f_neg_all[master_reg] ? -3'sd1 : 3'sd1) : 3'sd0;
    wire signed [2:0] f_corr        = corr_valid_reg ? (corr_negative_reg ? -3'sd1 : 3'sd1) : 3'sd0;
    wire signed [2:0] f_slave_step  = slave_req_valid ? (slave_req_negative ? -3'sd1 : 3'sd1) : 3'sd0;
    reg  [1:0]  f_applied_since_tick;
    reg  [15:0] f_net;                 // corrections applied since the last clear
    always @(posedge clk) begin
        if (rst || tick) f_applied_since_tick <= 2'd0;
        else if (applied && f_applied_since_tick != 2'd3) f_applied_since_tick <= f_applied_since_tick + 2'd1;
        if (rst || clear_counters) f_net <= 16'd0;
        else if (applied) f_net <= f_net + {{14{f_corr[2]}}, f_corr[1:0]};
    end

    always @(*) if (f_past_valid && !rst) begin
        assert (f_slave_step == f_master_step + (takes ? f_corr : 3'sd0));
        if (corr_valid_reg) assert (engaged_reg);
        if (engaged_reg) assert (master_reg != slave_reg && {1'b0, master_reg} < n_axes && {1'b0, slave_reg} < n_axes);
        if (!engaged_reg) assert (tick_cnt_reg == {TICK_W{1'b0}} && !corr_valid_reg);
        assert (f_applied_since_tick <= 2'd1);
        if (f_applied_since_tick != 2'd0) assert (!corr_valid_reg);   // until the next tick
        // An inserted step never goes against the master's motion: that is a deletion.
        // (The motion: the master's increment's sign, or its ext_up/ext_down.)
        if (takes && !master_valid) begin
            assert (!(f_corr < 0 && ((inc_all[32*master_reg +: 32] != 32'd0 && !inc_all[32*master_reg + 31])
                                     || up_all[master_reg])));
            assert (!(f_corr > 0 && (inc_all[32*master_reg + 31] || down_all[master_reg])));
        end
        if (takes) assert (sync && enable && !alarm_reg);
        assert (corrections_reg == f_net);
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (diff_reg == $past(enc_master) - $past(enc_slave));
        assert (error_reg == ($past(engaged_reg) ? $past(diff_reg) - $past(offset_reg) : 32'd0));
        if ($past(engaged_reg) && $past(error_mag) > {16'd0, $past(limit)}) assert (alarm_reg);
        if (!$past(engaged_reg) && !$past(clear_errors)) assert (alarm_reg == $past(alarm_reg));
        // ... and only then: the alarm rises exactly when the error passed the limit.
        if (alarm_reg && !$past(alarm_reg)) assert ($past(engaged_reg) && $past(error_mag) > {16'd0, $past(limit)});
        if ($past(engage)) assert (engaged_reg && offset_reg == $past(enc_master) - $past(enc_slave));
        // Engaged only from rest: no increment, no ext_busy.
        if (engaged_reg && !$past(engaged_reg))
            assert ($past(inc_all[32*master +: 32]) == 32'd0 && $past(inc_all[32*slave +: 32]) == 32'd0
                    && !$past(busy_all[master]) && !$past(busy_all[slave]));
        // No correction survives a halt, an alarm, forward mode or disengagement.
        if ($past(halt || alarm_reg || !sync || !engaged_reg || !enable)) assert (!corr_valid_reg);
        // At a tick the decision is the error's sign outside the deadband (computed apart).
        if ($past(tick && sync && enable && !halt && !alarm_reg))
            assert (corr_valid_reg == ($signed($past(error_reg)) > $signed({1'b0, $past(deadband)})
                                       || $signed($past(error_reg)) < -$signed({1'b0, $past(deadband)}))
                    && (!corr_valid_reg || corr_negative_reg == $past(error_reg[31])));
        // A correction is only decided at a tick, towards the error's sign.
        if (corr_valid_reg && !$past(corr_valid_reg)) begin
            assert ($past(tick) && $past(sync) && !$past(halt));
            assert (corr_negative_reg == $past(behind));
        end
        cover ($past(applied && !master_valid) && corr_valid_reg == 1'b0);         // inserted
        cover ($past(applied && master_valid) && !$past(slave_req_valid));         // deleted
        cover ($past(corr_valid_reg && !takes) && corr_valid_reg && engaged_reg);   // waited
        cover ($past(corr_valid_reg && !takes && !master_valid && master_inc == 32'd0) && engaged_reg); // waited on ext motion
        cover ($past(enable && config_valid && !engaged_reg && busy_all[master]) && !engaged_reg);     // ext_busy: no engagement
        cover (alarm_reg && !$past(alarm_reg));
        cover ($past(tick) && $past(tick, 3) && tick_clocks == 24'd2 && !$past(tick, 2));
    end
`endif

endmodule

`default_nettype wire
