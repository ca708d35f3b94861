`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/safety_monitor.md
// Safety monitor: the host watchdog and the external E-stop, either of which halts the
// machine (all pulse output stops, enables drop) through a sticky fault that only the
// host can clear, and only once its cause is gone.
//
// E-stop: the pin passes a two-flop synchroniser and a glitch filter (the filtered level
// changes after FILTER consecutive samples of the other level; 0 acts as 1); polarity
// is configurable. Watchdog: while enabled, a counter loaded with `timeout` on every
// kick counts down; reaching zero is a fault. `clear_faults` clears the E-stop fault if
// the filtered E-stop is released, and the watchdog fault if the watchdog is not
// expired (disabled, counting, or kicked in the same cycle).
//
// Out of reset the machine is halted (E-stop fault set, E-stop taken as active until
// the filter sees it released): the host must clear the fault to start.
//
// Latency: an E-stop held steady halts within 3 + max(FILTER, 1) clocks; a missing kick
// halts `timeout` + 2 clocks after the last one.
module safety_monitor #(
    parameter WD_W     = 24,
    parameter FILTER_W = 8
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // configuration
    input  wire                watchdog_enable,
    input  wire [WD_W-1:0]     watchdog_timeout,
    input  wire                estop_active_high,
    input  wire [FILTER_W-1:0] estop_filter,
    // host
    input  wire                kick,
    input  wire                clear_faults,
    // pin (asynchronous)
    input  wire                estop_pin,
    // status
    output wire                estop_active,    // filtered, polarity applied
    output wire                fault_estop,
    output wire                fault_watchdog,
    output wire                halt
);

    localparam [FILTER_W-1:0] FILTER_ONE = {{(FILTER_W-1){1'b0}}, 1'b1};

    reg [1:0]          estop_sync_reg;
    reg                estop_level_reg;     // filtered pin level
    reg [FILTER_W-1:0] estop_count_reg;     // consecutive samples differing from it
    reg [WD_W-1:0]     watchdog_count_reg;
    reg                fault_estop_reg;
    reg                fault_watchdog_reg;
    reg                halt_reg;          // fault_estop || fault_watchdog, from its own flip-flop

    wire [FILTER_W-1:0] filter_length = (estop_filter == {FILTER_W{1'b0}}) ? FILTER_ONE : estop_filter;
    wire sample_differs = (estop_sync_reg[1] != estop_level_reg);
    wire level_flips    = sample_differs && (estop_count_reg + FILTER_ONE >= filter_length);
    wire estop_now      = estop_level_reg == estop_active_high;
    wire expired        = watchdog_enable && (watchdog_count_reg == {WD_W{1'b0}}) && !kick;

    always @(posedge clk) begin
        estop_sync_reg <= {estop_sync_reg[0], estop_pin};

        if (!sample_differs || level_flips) estop_count_reg <= {FILTER_W{1'b0}};
        else estop_count_reg <= estop_count_reg + FILTER_ONE;
        if (level_flips) estop_level_reg <= !estop_level_reg;

        if (kick || !watchdog_enable) watchdog_count_reg <= watchdog_timeout;
        else if (watchdog_count_reg != {WD_W{1'b0}}) watchdog_count_reg <= watchdog_count_reg - {{(WD_W-1){1'b0}}, 1'b1};

        if (estop_now) fault_estop_reg <= 1'b1;
        else if (clear_faults) fault_estop_reg <= 1'b0;
        if (expired) fault_watchdog_reg <= 1'b1;
        else if (clear_faults) fault_watchdog_reg <= 1'b0;
        // The halt fans out to every axis: it leaves a flip-flop, not a gate behind two.
        halt_reg <= estop_now || expired || (!clear_faults && (fault_estop_reg || fault_watchdog_reg));

        if (rst) begin
            // The machine starts halted, E-stop taken as active: the host clears the
            // fault once the filter has seen the E-stop released.
            estop_sync_reg     <= {2{estop_active_high}};
            estop_level_reg    <= estop_active_high;
            estop_count_reg    <= {FILTER_W{1'b0}};
            watchdog_count_reg <= watchdog_timeout;
            fault_estop_reg    <= 1'b1;
            fault_watchdog_reg <= 1'b0;
            halt_reg           <= 1'b1;
        end
    end

    assign estop_active   = estop_now;
    assign fault_estop    = fault_estop_reg;
    assign fault_watchdog = fault_watchdog_reg;
    assign halt           = halt_reg;

`ifdef FORMAL
    // An E-stop held for 3 + FILTER clocks always halts; a pulse of fewer than FILTER
    // synchronised samples never does; no fault clears while its cause persists; a
    // watchdog kicked at least every `timeout` clocks never trips, and one not kicked for
    // `timeout` + 2 clocks always has.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(*) if (f_past_valid) assert (halt_reg == (fault_estop_reg || fault_watchdog_reg));
    always @(posedge clk) if (f_past_valid) begin
        assume ($stable(estop_active_high) && $stable(estop_filter) && $stable(watchdog_timeout) && $stable(watchdog_enable));
    end

    reg [FILTER_W+2:0] f_held;        // clocks the pin has been at the active level
    reg [WD_W+1:0]     f_unkicked;    // clocks since the last kick (while enabled)
    always @(posedge clk) begin
        if (rst) begin
            f_held <= 0;
            f_unkicked <= 0;
        end else begin
            f_held <= (estop_pin == estop_active_high) ? ((&f_held) ? f_held : f_held + 1'b1) : 0;
            f_unkicked <= (kick || !watchdog_enable) ? 0 : ((&f_unkicked) ? f_unkicked : f_unkicked + 1'b1);
        end
    end

    always @(*) if (f_past_valid && !rst) begin
        if (f_held >= {3'b000, filter_length} + 3) assert (halt && fault_estop);
        if (watchdog_enable && f_unkicked >= {2'b00, watchdog_timeout} + 2) assert (fault_watchdog);
        // The counter is the timeout less the clocks since the last kick, down to zero.
        if (watchdog_enable)
            assert ({2'b00, watchdog_count_reg} == ((f_unkicked >= {2'b00, watchdog_timeout})
                                                   ? {(WD_W+2){1'b0}} : {2'b00, watchdog_timeout} - f_unkicked));
        assert (estop_count_reg < filter_length);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(estop_now)) assert (fault_estop);
        if ($past(expired)) assert (fault_watchdog);
        if ($past(fault_estop) && !$past(clear_faults)) assert (fault_estop);
        if ($past(fault_watchdog) && !$past(clear_faults)) assert (fault_watchdog);
        // The filtered level only changes after FILTER differing samples.
        if ($changed(estop_level_reg)) assert ($past(estop_count_reg) + FILTER_ONE >= $past(filter_length));
        cover (fault_estop && !$past(fault_estop));
        cover (fault_watchdog && !$past(fault_watchdog));
        cover ($fell(fault_estop));
    end
`endif

endmodule

`default_nettype wire
