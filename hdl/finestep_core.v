`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/finestep_core.md
// finestep core: the fine-interpolation half of a two-stage CNC controller. Period
// records (every axis's Q16.16 increment for one period + flags) enter through a
// valid/ready port; the period timer loads one per period on the same clock for all
// axes; a DDA per axis spreads each increment over the period; a step shaper per axis
// turns the step requests into drive-timed step/dir, up/down or quadrature pins. The
// gantry block may give one axis (the slave) the requests of another (the master),
// corrected from two encoder channels (see gantry_sync). With HAS_PBP a record with the
// flag PBP is a line or an arc for the point-by-point comparison interpolator, whose
// requests drive the pair it names while the period timer runs idle periods (see
// docs/spec/pbp_interp.md#in-the-core).
//
// Latency from an increment taking effect to the first pin edge: 3 clocks.
// Every output is a flip-flop or a function of flip-flops only.
module finestep_core #(
    parameter N_AXES   = 4,
    parameter P_WIDTH  = 20,
    parameter TIMING_W = 12,
    parameter HAS_GANTRY = 1,    // 0: no gantry block (its outputs read 0, every axis its own)
    parameter STEP_SHARED = 0,   // 1: one step engine visits the axes (no gantry block then)
    parameter RAM_BLOCK  = 0,    // 1: the step engine's stores in block RAM
    parameter STEP_DIGIT = 0,    // with STEP_SHARED: 0 step_engine; 1, 2, 4, 8 step_serial
    parameter HAS_ALT    = 1,    // 0: no alternate record (no jog): rec_alt is taken as 0
    parameter HAS_PBP    = 0     // 1: pbp_interp runs the records with the flag PBP
) (
    // clock, reset
    input  wire                       clk,
    input  wire                       rst,
    // control
    input  wire                       run,
    input  wire [P_WIDTH-1:0]         period_clocks,
    input  wire                       clear_errors,
    input  wire                       halt,          // safety fault: see step_shaper
    // per-axis configuration
    input  wire [N_AXES-1:0]          axis_enable,
    input  wire [TIMING_W*N_AXES-1:0] step_len,
    input  wire [TIMING_W*N_AXES-1:0] step_space,
    input  wire [TIMING_W*N_AXES-1:0] dir_setup,
    input  wire [TIMING_W*N_AXES-1:0] dir_hold,
    input  wire [2*N_AXES-1:0]        out_mode,
    input  wire [3*N_AXES-1:0]        invert,
    // gantry synchronisation (see gantry_sync)
    input  wire                       gantry_enable,
    input  wire                       gantry_sync_mode,
    input  wire [2:0]                 gantry_master,
    input  wire [2:0]                 gantry_slave,
    input  wire [23:0]                gantry_tick,
    input  wire [15:0]                gantry_deadband,
    input  wire [15:0]                gantry_limit,
    input  wire [31:0]                enc_master,
    input  wire [31:0]                enc_slave,
    input  wire                       clear_counters,
    // period record port
    input  wire                       rec_valid,
    output wire                       rec_ready,
    // the period timer's boundary (its own rec_ready): a period ends in this cycle, also
    // the idle periods it runs while a pbp record holds rec_ready low
    output wire                       period_boundary,
    input  wire [32*N_AXES-1:0]       rec_inc,
    input  wire [7:0]                 rec_flags,
    // the alternate record (period_timer): rec_alt_inc on the rec_alt_lane lanes, zero
    // on the others, offered instead of rec_inc while rec_alt
    input  wire                       rec_alt,
    input  wire [N_AXES-1:0]          rec_alt_lane,
    input  wire [31:0]                rec_alt_inc,
    // drive pins
    output wire [N_AXES-1:0]          pin_a,
    output wire [N_AXES-1:0]          pin_b,
    output wire [N_AXES-1:0]          pin_en,
    // status
    output wire [32*N_AXES-1:0]       position,
    output wire [N_AXES-1:0]          rate_error,
    output wire [N_AXES-1:0]          step_lost,
    output wire                       record_error,
    output wire                       block_end,
    output wire                       gantry_engaged,
    output wire                       gantry_alarm,
    output wire                       gantry_refused,
    output wire [31:0]                gantry_error,
    output wire [15:0]                gantry_corrections
);

`include "finestep_interface.vh"
`include "finestep_core_checks.vh"

    // log2 of the step engine's slots (0: a DDA and a shaper per axis); with the
    // digit-serial engine log2 of its round R = slots * 32 / STEP_DIGIT clocks, the
    // quantum of the periods (docs/spec/step_serial.md#environment).
    localparam SLOTS_L = (N_AXES <= 2) ? 1 : ((N_AXES <= 4) ? 2 : 3);
    localparam DIGIT_L = (STEP_DIGIT <= 1) ? 0 : ((STEP_DIGIT == 2) ? 1 : ((STEP_DIGIT == 4) ? 2 : 3));
    // (a STEP_DIGIT outside 1..8 builds no serial engine: its elaboration check names it
    // without the engine's widths going negative first)
    localparam SERIAL  = (STEP_SHARED != 0 && STEP_DIGIT >= 1 && STEP_DIGIT <= 8) ? 1 : 0;
    localparam SL = (STEP_SHARED == 0) ? 0 : ((SERIAL != 0) ? SLOTS_L + 5 - DIGIT_L : SLOTS_L);
    // The checks across parameters (P_WIDTH above log2 of the round; the digit-serial
    // engine's TIMING_W and P_WIDTH limits) are in finestep_core_checks.vh, generated
    // from hdl/interface.toml's constraints.

    wire                 timer_active;
    wire [P_WIDTH-1:0]   p_active;
    // The DDAs hold their phase at M/2 until the period timer runs.
    wire                 dda_run = run && timer_active;
    wire [32*N_AXES-1:0] inc;

    wire start_ok;

    // The point-by-point comparison interpolator's side of the record port
    // (docs/spec/pbp_interp.md#in-the-core): what the period timer is offered, and the
    // block's requests on each axis (none without HAS_PBP).
    wire                 timer_rec_valid;
    wire                 timer_rec_ready;
    wire [32*N_AXES-1:0] timer_rec_inc;
    wire [7:0]           timer_rec_flags;
    wire                 timer_record_error;
    wire                 timer_block_end;
    wire [N_AXES-1:0]    pbp_req_valid;
    wire [N_AXES-1:0]    pbp_req_negative;
    // For the gantry: the axes of the pair a record runs on (not at rest), and the
    // direction the block's next step would take each (see pbp_interp's move_up/down).
    wire [N_AXES-1:0]    pbp_busy;
    wire [N_AXES-1:0]    pbp_up;
    wire [N_AXES-1:0]    pbp_down;
    // With the step engine: a request of the block not yet taken by its axis's shaper
    // visit (the engine holds it up to S clocks); 0 with a DDA and a shaper per axis.
    wire                 pbp_ext_pending;

    assign period_boundary = timer_rec_ready;

    // The digit-serial engine is the CPLD's: its period timer is shaped for area (the
    // same behaviour, see period_timer).
    period_timer #(
        .N_AXES(N_AXES),
        .P_WIDTH(P_WIDTH),
        .SL(SL),
        .AREA(SERIAL),
        .HAS_ALT(HAS_ALT)
    ) timer (
        .clk(clk),
        .rst(rst),
        .run(run),
        .start_ok(start_ok),
        .period_clocks(period_clocks),
        .clear_errors(clear_errors),
        .rec_valid(timer_rec_valid),
        .rec_ready(timer_rec_ready),
        .rec_inc(timer_rec_inc),
        .rec_flags(timer_rec_flags),
        .rec_alt(rec_alt),
        .rec_alt_lane(rec_alt_lane),
        .rec_alt_inc(rec_alt_inc),
        .active(timer_active),
        .p_active(p_active),
        .inc(inc),
        .block_end(timer_block_end),
        .record_error(timer_record_error)
    );

    generate
        if (HAS_PBP != 0) begin : with_pbp
            // A pbp record's fields (hdl/interface.toml [pbp]): the PBP_RECORD bits
            // {ARC, CW, PAIR} at FS_PBP_BITS_LANE/LSB, X, Y, the arc's decision count and
            // TICK_DIV each FS_PBP_<FIELD>_LSB +: _WIDTH of lane FS_PBP_<FIELD>_LANE.
            localparam COORD_W = FS_PBP_X_WIDTH;
            localparam DIV_W   = FS_PBP_TICK_DIV_WIDTH;
            localparam COUNT_W = FS_PBP_COUNT_WIDTH;
            localparam BITS    = FS_REC_INC_WIDTH * FS_PBP_BITS_LANE + FS_PBP_BITS_LSB;
            localparam X_AT    = FS_REC_INC_WIDTH * FS_PBP_X_LANE + FS_PBP_X_LSB;
            localparam Y_AT    = FS_REC_INC_WIDTH * FS_PBP_Y_LANE + FS_PBP_Y_LSB;
            localparam COUNT_AT = FS_REC_INC_WIDTH * FS_PBP_COUNT_LANE + FS_PBP_COUNT_LSB;
            localparam DIV_AT  = FS_REC_INC_WIDTH * FS_PBP_TICK_DIV_LANE + FS_PBP_TICK_DIV_LSB;
            // The clocks between two visits of an axis: the block's decisions must be at
            // least that far apart (one request per axis per visit, as the DDA's).
            localparam [DIV_W:0] S_CLOCKS = 1 << SL;
            wire alt_offered = (HAS_ALT != 0) && rec_alt;
            wire offered_pbp = rec_flags[FS_REC_FLAG_PBP_BIT] && !alt_offered;
            wire busy;
            wire done;
            // The timer is offered nothing while a pbp record runs or a request of it has
            // not reached its axis's shaper (its boundaries run idle periods), and a pbp
            // record as an idle period without BLOCK_END (the block's done gives it), so
            // the FIFO advances at the boundary that starts it.
            wire wait_pbp = busy || pbp_ext_pending;
            assign timer_rec_valid = rec_valid && !wait_pbp;
            assign rec_ready       = timer_rec_ready && !wait_pbp;
            assign timer_rec_inc   = offered_pbp ? {32*N_AXES{1'b0}} : rec_inc;
            assign timer_rec_flags = offered_pbp ? (rec_flags & ~(8'd1 << FS_REC_FLAG_BLOCK_END_BIT)) : rec_flags;
            wire [1:0] pair = rec_inc[BITS + FS_PBP_RECORD_PAIR_0_BIT +: 2];
            wire [DIV_W-1:0] tick = rec_inc[DIV_AT +: DIV_W];
            wire pair_ok = ({1'b0, pair, 1'b1} < N_AXES) && ({1'b0, tick} + 1'b1 >= S_CLOCKS);
            // Taken with the timer's record (a boundary while running); one on a pair not
            // built, or with decisions closer than S clocks, is refused (record_error) and
            // runs as the idle period it is.
            wire take = run && timer_rec_ready && rec_valid && !wait_pbp && offered_pbp;
            reg [1:0]       pair_reg;
            reg [DIV_W-1:0] tick_reg;
            reg             end_reg;
            reg             refused_reg;
            always @(posedge clk) begin
                if (take) begin
                    pair_reg <= pair;
                    tick_reg <= tick;
                    end_reg  <= rec_flags[FS_REC_FLAG_BLOCK_END_BIT];
                end
                if (take && !pair_ok)
                    refused_reg <= 1'b1;
                else if (clear_errors)
                    refused_reg <= 1'b0;
                if (rst) begin
                    pair_reg    <= 2'd0;
                    end_reg     <= 1'b0;
                    refused_reg <= 1'b0;
                end
            end
            wire [1:0] req_valid2, req_negative2, move_up2, move_down2;
            wire       ready_unused;
            // A stop (run low) aborts the record as a halt does.
            pbp_interp #(
                .COORD_W(COORD_W),
                .DIV_W(DIV_W)
            ) interp (
                .clk(clk),
                .rst(rst),
                .halt(halt || !run),
                .tick_div(tick_reg),
                .rec_valid(take && pair_ok),
                .rec_ready(ready_unused),
                .rec_arc(rec_inc[BITS + FS_PBP_RECORD_ARC_BIT]),
                .rec_cw(rec_inc[BITS + FS_PBP_RECORD_CW_BIT]),
                .rec_x(rec_inc[X_AT +: COORD_W]),
                .rec_y(rec_inc[Y_AT +: COORD_W]),
                .rec_steps(rec_inc[COUNT_AT +: COUNT_W]),
                .req_valid(req_valid2),
                .req_negative(req_negative2),
                .busy(busy),
                .done(done),
                .move_up(move_up2),
                .move_down(move_down2)
            );
            genvar k;
            for (k = 0; k < N_AXES; k = k + 1) begin : lane
                wire on_pair = ({30'd0, pair_reg} == k / 2);
                assign pbp_req_valid[k]    = on_pair && req_valid2[k % 2];
                assign pbp_req_negative[k] = req_negative2[k % 2];
                assign pbp_busy[k]         = on_pair && busy;
                assign pbp_up[k]           = on_pair && move_up2[k % 2];
                assign pbp_down[k]         = on_pair && move_down2[k % 2];
            end
            assign block_end    = timer_block_end || (done && end_reg);
            assign record_error = timer_record_error || refused_reg;
            wire unused_pbp = &{1'b0, ready_unused};
        end else begin : without_pbp
            assign timer_rec_valid  = rec_valid;
            assign rec_ready        = timer_rec_ready;
            assign timer_rec_inc    = rec_inc;
            assign timer_rec_flags  = rec_flags;
            assign pbp_req_valid    = {N_AXES{1'b0}};
            assign pbp_req_negative = {N_AXES{1'b0}};
            assign pbp_busy         = {N_AXES{1'b0}};
            assign pbp_up           = {N_AXES{1'b0}};
            assign pbp_down         = {N_AXES{1'b0}};
            assign block_end        = timer_block_end;
            assign record_error     = timer_record_error;
            wire unused_pending = &{1'b0, pbp_ext_pending};
        end
    endgenerate

    wire [N_AXES-1:0] dda_req_valid;
    wire [N_AXES-1:0] dda_req_negative;
    // With a DDA and a shaper per axis, each axis's own request: the pbp block's while
    // its record runs (the DDAs are idle then), else its DDA's. The gantry block sees
    // these, so a pbp move of the master reaches the slave as a DDA step does.
    wire [N_AXES-1:0] own_req_valid    = pbp_req_valid | dda_req_valid;
    wire [N_AXES-1:0] own_req_negative = (pbp_req_valid & pbp_req_negative) | (~pbp_req_valid & dda_req_negative);
    wire              slave_req_valid, slave_req_negative;
    wire [2:0]        master_axis, slave_axis;
    // The request each axis's shaper takes (a DDA and a shaper per axis; 0 with an engine).
    wire [N_AXES-1:0] shaper_req_valid, shaper_req_negative;

    generate
        if (HAS_GANTRY != 0 && STEP_SHARED == 0) begin : with_gantry
            gantry_sync #(
                .N_AXES(N_AXES),
                .TICK_W(24)
            ) gantry (
                .clk(clk),
                .rst(rst),
                .enable(gantry_enable),
                .sync(gantry_sync_mode),
                .master(gantry_master),
                .slave(gantry_slave),
                .tick_clocks(gantry_tick),
                .deadband(gantry_deadband),
                .limit(gantry_limit),
                .enc_master(enc_master),
                .enc_slave(enc_slave),
                .inc(inc),
                .req_valid(own_req_valid),
                .req_negative(own_req_negative),
                .ext_busy(pbp_busy),
                .ext_up(pbp_up),
                .ext_down(pbp_down),
                .halt(halt),
                .clear_errors(clear_errors),
                .clear_counters(clear_counters),
                .slave_req_valid(slave_req_valid),
                .slave_req_negative(slave_req_negative),
                .engaged(gantry_engaged),
                .master_axis(master_axis),
                .slave_axis(slave_axis),
                .alarm(gantry_alarm),
                .refused(gantry_refused),
                .error(gantry_error),
                .corrections(gantry_corrections)
            );
        end else begin : without_gantry
            assign slave_req_valid    = 1'b0;
            assign slave_req_negative = 1'b0;
            assign master_axis        = 3'd0;
            assign slave_axis         = 3'd0;
            assign gantry_engaged     = 1'b0;
            assign gantry_alarm       = 1'b0;
            assign gantry_refused     = 1'b0;
            assign gantry_error       = 32'd0;
            assign gantry_corrections = 16'd0;
            wire unused_gantry = &{1'b0, gantry_enable, gantry_sync_mode, gantry_master, gantry_slave,
                                   gantry_tick, gantry_deadband, gantry_limit, enc_master, enc_slave,
                                   clear_counters, pbp_busy, pbp_up, pbp_down};
        end
    endgenerate
    // The master's axis is the formal properties' (the gantry's pbp rules below).
    wire unused_master_axis = &{1'b0, master_axis};

    genvar i;
    generate
        if (SERIAL != 0) begin : serial
            wire [STEP_DIGIT-1:0] pos_digit;
            wire [7:0]            pos_index;
            wire [2:0]            pos_axis;
            step_serial #(
                .N_AXES(N_AXES),
                .P_WIDTH(P_WIDTH),
                .TIMING_W(TIMING_W),
                .DIGIT(STEP_DIGIT)
            ) engine (
                .clk(clk), .rst(rst),
                .run(dda_run), .p_active(p_active), .inc(inc),
                .start_ok(start_ok),
                .axis_enable(axis_enable),
                .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
                .out_mode(out_mode), .invert(invert),
                .clear_errors(clear_errors), .halt(halt),
                .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
                .rate_error(rate_error), .step_lost(step_lost),
                .pos_digit(pos_digit), .pos_index(pos_index), .pos_axis(pos_axis)
            );
            // The position words, collected from the engine's digit stream: a visit's
            // digits shift into one word, written to its axis with the last digit, so a
            // word never shows a mix of two visits (docs/spec/step_serial.md#in-the-core).
            localparam QL = 5 - DIGIT_L;
            reg [31-STEP_DIGIT:0] collect_reg;      // the digits so far, the newest on top
            reg [32*N_AXES-1:0]   position_reg;
            wire [31:0]           collected = {pos_digit, collect_reg};
            integer a;
            always @(posedge clk) begin
                collect_reg <= collected[31:STEP_DIGIT];
                for (a = 0; a < N_AXES; a = a + 1) begin
                    if (pos_index == (1 << QL) - 1 && {29'd0, pos_axis} == a) position_reg[32*a +: 32] <= collected;
                end
                if (rst) position_reg <= {32*N_AXES{1'b0}};
            end
            assign position = position_reg;
            wire unused_slave = &{1'b0, slave_req_valid, slave_req_negative, slave_axis};
            assign dda_req_valid    = {N_AXES{1'b0}};
            assign dda_req_negative = {N_AXES{1'b0}};
            wire unused_dda_req = &{1'b0, dda_req_valid, dda_req_negative, RAM_BLOCK[0], pbp_req_valid,
                                    pbp_req_negative, own_req_valid, own_req_negative,
                                    shaper_req_valid, shaper_req_negative};
            assign pbp_ext_pending = 1'b0;
            assign shaper_req_valid    = {N_AXES{1'b0}};
            assign shaper_req_negative = {N_AXES{1'b0}};
        end else if (STEP_SHARED != 0) begin : shared
            step_engine #(
                .N_AXES(N_AXES),
                .P_WIDTH(P_WIDTH),
                .TIMING_W(TIMING_W),
                .RAM_BLOCK(RAM_BLOCK),
                .EXT_REQ(HAS_PBP)
            ) engine (
                .clk(clk), .rst(rst),
                .run(dda_run), .p_active(p_active), .inc(inc),
                .start_ok(start_ok),
                .axis_enable(axis_enable),
                .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
                .out_mode(out_mode), .invert(invert),
                .clear_errors(clear_errors), .halt(halt),
                .ext_req_valid(pbp_req_valid), .ext_req_negative(pbp_req_negative),
                .ext_pending(pbp_ext_pending),
                .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
                .position(position), .rate_error(rate_error), .step_lost(step_lost)
            );
            // No gantry block with the engine: no axis takes another's requests. The pbp
            // block's requests reach the engine's shaper visits (EXT_REQ).
            wire unused_slave = &{1'b0, slave_req_valid, slave_req_negative, slave_axis};
            assign dda_req_valid    = {N_AXES{1'b0}};
            assign dda_req_negative = {N_AXES{1'b0}};
            wire unused_dda_req = &{1'b0, dda_req_valid, dda_req_negative, own_req_valid, own_req_negative,
                                    shaper_req_valid, shaper_req_negative};
            assign shaper_req_valid    = {N_AXES{1'b0}};
            assign shaper_req_negative = {N_AXES{1'b0}};
        end else begin : per_axis
            assign start_ok = 1'b1;
            assign pbp_ext_pending = 1'b0;
            for (i = 0; i < N_AXES; i = i + 1) begin : axis
                // The gantry's engaged slave takes the gantry's request only (its own
                // axis's DDA or pbp request is ignored), every other axis its own request.
                wire is_slave = gantry_engaged && (slave_axis == i);
                assign shaper_req_valid[i]    = is_slave ? slave_req_valid : own_req_valid[i];
                assign shaper_req_negative[i] = is_slave ? slave_req_negative : own_req_negative[i];

                dda_axis #(
                    .P_WIDTH(P_WIDTH)
                ) dda (
                    .clk(clk),
                    .rst(rst),
                    .run(dda_run),
                    .period_clocks(period_clocks),
                    .p_active(p_active),
                    .inc(inc[32*i +: 32]),
                    .req_valid(dda_req_valid[i]),
                    .req_negative(dda_req_negative[i])
                );

                step_shaper #(
                    .TIMING_W(TIMING_W)
                ) shaper (
                    .clk(clk),
                    .rst(rst),
                    .step_len(step_len[TIMING_W*i +: TIMING_W]),
                    .step_space(step_space[TIMING_W*i +: TIMING_W]),
                    .dir_setup(dir_setup[TIMING_W*i +: TIMING_W]),
                    .dir_hold(dir_hold[TIMING_W*i +: TIMING_W]),
                    .out_mode(out_mode[FS_OUT_MODE_WIDTH*i +: FS_OUT_MODE_WIDTH]),
                    .invert(invert[FS_INVERT_WIDTH*i +: FS_INVERT_WIDTH]),
                    .axis_enable(axis_enable[i]),
                    .clear_errors(clear_errors),
                    .halt(halt),
                    .req_valid(shaper_req_valid[i]),
                    .req_negative(shaper_req_negative[i]),
                    .pin_a(pin_a[i]),
                    .pin_b(pin_b[i]),
                    .pin_en(pin_en[i]),
                    .position(position[32*i +: 32]),
                    .rate_error(rate_error[i]),
                    .step_lost(step_lost[i])
                );
            end
        end
    endgenerate

`ifdef FORMAL
    // The pbp block's hand-off (docs/spec/pbp_interp.md#in-the-core), stated on the ports
    // of the blocks: the period timer's record port and increments, the block's requests
    // on the axes and the DDAs' (sim/formal/pbp_handoff.sby: with the step engine and
    // with a DDA and a shaper per axis).
    generate
        if (HAS_PBP != 0) begin : f_pbp
            reg f_past_valid;
            initial f_past_valid = 1'b0;
            initial assume (rst);
            always @(posedge clk) f_past_valid <= 1'b1;
            wire f_busy = with_pbp.busy;
            always @(*) if (f_past_valid && !rst) begin
                // While a pbp record runs, or a request of it has not reached its axis's
                // shaper, the period timer is offered nothing and the port is not ready ...
                if (f_busy || pbp_ext_pending) assert (!timer_rec_valid && !rec_ready);
                // ... and while it runs every increment the timer hands the DDAs (or the
                // engine's DDA visits) is zero: they have nothing of their own to request.
                if (f_busy) assert (inc == {32*N_AXES{1'b0}});
                // The block requests on one axis at a time, and only on its pair's.
                assert (!(with_pbp.req_valid2[0] && with_pbp.req_valid2[1]));
            end
            always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
                // A halt (or a stop) ends the block's record and its requests from the
                // next clock.
                if ($past(halt || !run)) assert (pbp_req_valid == {N_AXES{1'b0}} && !f_busy);
`ifdef FORMAL_DDA_REQ
                // With a DDA per axis: from a record's second clock on, no DDA request
                // (the last of the period before may come in its first). Bounded (task
                // bmc_per_axis): the induction would need dda_axis's acc < M, which its
                // own proof shows; with zero increments (above) and acc < M no DDA wraps.
                if (STEP_SHARED == 0 && f_busy && $past(f_busy)) assert (dda_req_valid == {N_AXES{1'b0}});
`endif
                cover (f_busy && $past(f_busy) && |pbp_req_valid);
                cover ($past(f_busy) && !f_busy && !$past(halt) && run);
            end
            if (HAS_GANTRY != 0 && STEP_SHARED == 0) begin : f_gantry
                // With the gantry block: the gantry sees each axis's own request (the
                // pbp block's where it requests, else the DDA's), and while engaged the
                // slave axis's shaper takes exactly the gantry's request (a pbp or DDA
                // request on the slave's own axis is ignored).
                genvar k;
                for (k = 0; k < N_AXES; k = k + 1) begin : f_axis
                    always @(*) if (f_past_valid && !rst) begin
                        assert (own_req_valid[k] == (pbp_req_valid[k] || dda_req_valid[k]));
                        if (pbp_req_valid[k]) assert (own_req_negative[k] == pbp_req_negative[k]);
                        if (gantry_engaged && slave_axis == k) begin
                            assert (shaper_req_valid[k] == slave_req_valid);
                            if (slave_req_valid) assert (shaper_req_negative[k] == slave_req_negative);
                        end else begin
                            assert (shaper_req_valid[k] == own_req_valid[k]);
                        end
                    end
                end
                always @(posedge clk) if (f_past_valid && !rst)
                    cover (gantry_engaged && f_busy && |pbp_req_valid);
                // The gantry sees a pbp record's motion (docs/spec/gantry_sync.md): no
                // engagement while a record runs on the pair of the master or the slave
                // (their axes are not at rest), and no correction inserted (a slave step
                // without a master step) against the direction the block shows for the
                // master's next step (pbp_interp's move_up/move_down, whose every request
                // follows them: sim/formal/pbp_interp.sby).
                wire [7:0] f_master_valid = {{(8-N_AXES){1'b0}}, own_req_valid};
                wire [7:0] f_master_up    = {{(8-N_AXES){1'b0}}, pbp_up};
                wire [7:0] f_master_down  = {{(8-N_AXES){1'b0}}, pbp_down};
                wire f_inserted = gantry_engaged && slave_req_valid && !f_master_valid[master_axis];
                // An engagement was asked while a record ran on the master's pair.
                reg f_asked_in_record;
                always @(posedge clk)
                    if (rst || gantry_engaged) f_asked_in_record <= 1'b0;
                    else if (gantry_enable && f_busy && {1'b0, with_pbp.pair_reg} == gantry_master[2:1])
                        f_asked_in_record <= 1'b1;
                always @(*) if (f_past_valid && !rst) begin
                    if (f_inserted) assert (!(slave_req_negative && f_master_up[master_axis])
                                            && !(!slave_req_negative && f_master_down[master_axis]));
                end
                always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
                    if (gantry_engaged && !$past(gantry_engaged))
                        assert (!($past(f_busy) && ({1'b0, $past(with_pbp.pair_reg)} == $past(gantry_master[2:1])
                                                    || {1'b0, $past(with_pbp.pair_reg)} == $past(gantry_slave[2:1]))));
                    // Covered: an engagement that waited for a record on the pair to end;
                    // a correction inserted with the master's pbp motion.
                    cover (gantry_engaged && !$past(gantry_engaged) && $past(f_asked_in_record));
                    cover (f_inserted && f_busy && (f_master_up[master_axis] || f_master_down[master_axis]));
                end
            end
        end
    endgenerate
`endif

endmodule

`default_nettype wire
