`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/spindle.md
// Spindle: one level drives either a PWM pin (high for the first `level` clocks of each
// period of SPINDLE_PERIOD clocks) or a 12-bit SPI DAC (MCP4921 frame: CS_n low, 16 bits
// MSB first on SDI, each sampled at a rising SCK, the code min(level, 4095)), beside
// the enable and direction pins. The level ramps toward its target (SPINDLE_LEVEL while
// ENABLE, else 0) by at most SPINDLE_RAMP.STEP at each period's end. The block holds its
// own registers on the arbitrated register bus, as feedback_registers does.
//
// Latency: a register write reaches the enable, direction and DAC pins the clock after
// the serving edge; a new level the next period. A halt drops the enable and PWM pins
// and the level to 0, aborts a DAC frame (CS_n high) and restarts the period, all on
// the edge ending the halt's first cycle; the next clock starts a DAC frame of code 0.
// Invariants (proven): pwm == (!DAC && count < level) while not halted; the level moves
// only at a period's end, by at most STEP, never past its target; every DAC frame that
// ends is 16 rising SCK edges carrying the word latched at its start.
module spindle #(
    parameter LEVEL_W = 16
) (
    // clock, reset
    input  wire        clk,
    input  wire        rst,
    // arbitrated register bus (register_file's bus stage)
    input  wire        write,
    input  wire [6:0]  addr,
    input  wire [31:0] wdata,
    output reg  [31:0] rdata,        // the read value of addr, this cycle
    // safety
    input  wire        halt,
    // pins
    output wire        spindle_pwm,
    output wire        spindle_dir,
    output wire        spindle_en,
    output wire        dac_cs_n,
    output wire        dac_sck,
    output wire        dac_sdi
);

`include "finestep_regs.vh"
`include "spindle_checks.vh"

    localparam DAC_BITS   = 12;                       // MCP4921: 12-bit code
    localparam [31:0] DAC_MAX = 32'd4095;
    localparam FRAME_BITS = 16;                       // config nibble + code
    localparam LAST_TICK  = 2 * FRAME_BITS;           // ticks 0..32 with CS_n low
    localparam [3:0] DAC_CONFIG = 4'b0011;            // DAC A, unbuffered, gain 1x, active
    localparam DIV_W      = FS_SPINDLE_CONTROL_DAC_DIV_WIDTH;

    // registers
    reg               enable_reg, dir_reg, dac_reg;
    reg [DIV_W-1:0]   div_reg;
    reg [LEVEL_W-1:0] period_reg, command_reg, ramp_reg;
    // output state
    reg [LEVEL_W-1:0] count_reg, level_reg;
    reg               halt_prev_reg;
    reg               pwm_reg, en_reg, dir_pin_reg;
    reg               frame_reg, sck_reg;
    reg [5:0]         tick_reg;
    reg [DIV_W-1:0]   div_count_reg;
    reg [FRAME_BITS-1:0] shift_reg;

    // next state
    reg               enable_next, dir_next, dac_next;
    reg [DIV_W-1:0]   div_next;
    reg [LEVEL_W-1:0] period_next, command_next, ramp_next;
    reg [LEVEL_W-1:0] count_next, level_next;
    reg               frame_next, sck_next;
    reg [5:0]         tick_next;
    reg [DIV_W-1:0]   div_count_next;
    reg [FRAME_BITS-1:0] shift_next;

    // The period's last count (a period of 0 acts as 1) and the end of the period.
    wire [LEVEL_W-1:0] last_count = (period_reg == {LEVEL_W{1'b0}}) ? {LEVEL_W{1'b0}}
                                                                      : period_reg - {{(LEVEL_W-1){1'b0}}, 1'b1};
    wire               period_end = (count_reg >= last_count);
    wire               halt_rise  = halt && !halt_prev_reg;

    // The ramp: toward the target by at most the step (0: no limit), never past it.
    wire [LEVEL_W-1:0] target   = enable_reg ? command_reg : {LEVEL_W{1'b0}};
    wire               rising   = (level_reg < target);
    wire [LEVEL_W-1:0] distance = rising ? (target - level_reg) : (level_reg - target);
    wire               limited  = (ramp_reg != {LEVEL_W{1'b0}}) && (distance > ramp_reg);
    wire [LEVEL_W-1:0] ramped   = !limited ? target : (rising ? level_reg + ramp_reg : level_reg - ramp_reg);

    // The DAC word of the current level.
    wire [31:0]        level_wide = {{(32-LEVEL_W){1'b0}}, level_reg};
    wire [DAC_BITS-1:0] code      = (level_wide > DAC_MAX) ? DAC_MAX[DAC_BITS-1:0] : level_wide[DAC_BITS-1:0];
    wire [FRAME_BITS-1:0] word    = {DAC_CONFIG, code};
    wire               tick_done  = (div_count_reg >= div_reg);

    always @* begin
        enable_next  = enable_reg;
        dir_next     = dir_reg;
        dac_next     = dac_reg;
        div_next     = div_reg;
        period_next  = period_reg;
        command_next = command_reg;
        ramp_next    = ramp_reg;
        if (write) begin
            case (addr)
                FS_SPINDLE_CONTROL_ADDR: begin
                    enable_next = wdata[FS_SPINDLE_CONTROL_ENABLE_LSB];
                    dir_next    = wdata[FS_SPINDLE_CONTROL_DIR_LSB];
                    dac_next    = wdata[FS_SPINDLE_CONTROL_DAC_LSB];
                    div_next    = wdata[FS_SPINDLE_CONTROL_DAC_DIV_LSB +: DIV_W];
                end
                FS_SPINDLE_PERIOD_ADDR: period_next  = wdata[FS_SPINDLE_PERIOD_CLOCKS_LSB +: LEVEL_W];
                FS_SPINDLE_LEVEL_ADDR:  command_next = wdata[FS_SPINDLE_LEVEL_LEVEL_LSB +: LEVEL_W];
                FS_SPINDLE_RAMP_ADDR:   ramp_next    = wdata[FS_SPINDLE_RAMP_STEP_LSB +: LEVEL_W];
                default: ;
            endcase
        end
        // A halt switches the spindle off; the host enables it again after the fault.
        if (halt) enable_next = 1'b0;

        // The period counter restarts at the period's end and when a halt begins.
        count_next = (period_end || halt_rise) ? {LEVEL_W{1'b0}} : count_reg + {{(LEVEL_W-1){1'b0}}, 1'b1};
        level_next = halt ? {LEVEL_W{1'b0}} : (period_end ? ramped : level_reg);

        // The DAC frame: ticks of div + 1 clocks; tick 0 CS_n low with bit 15 on SDI,
        // odd ticks SCK high, even ticks SCK low with the next bit; after tick 32 CS_n
        // rises. A frame starts in a period's first clock (count 0) when none is running,
        // carrying that clock's level; a halt's first clock or DAC = 0 aborts it.
        frame_next     = frame_reg;
        sck_next       = sck_reg;
        tick_next      = tick_reg;
        div_count_next = div_count_reg;
        shift_next     = shift_reg;
        if (halt_rise || !dac_reg) begin
            frame_next     = 1'b0;
            sck_next       = 1'b0;
            tick_next      = 6'd0;
            div_count_next = {DIV_W{1'b0}};
            shift_next     = {FRAME_BITS{1'b0}};
        end else if (!frame_reg) begin
            if (count_reg == {LEVEL_W{1'b0}}) begin
                frame_next     = 1'b1;
                tick_next      = 6'd0;
                div_count_next = {DIV_W{1'b0}};
                shift_next     = word;
            end
        end else if (!tick_done) begin
            div_count_next = div_count_reg + {{(DIV_W-1){1'b0}}, 1'b1};
        end else begin
            div_count_next = {DIV_W{1'b0}};
            if (tick_reg == LAST_TICK[5:0]) begin
                frame_next = 1'b0;
                sck_next   = 1'b0;
                tick_next  = 6'd0;
                shift_next = {FRAME_BITS{1'b0}};
            end else begin
                tick_next = tick_reg + 6'd1;
                sck_next  = !tick_reg[0];               // the next tick is odd: SCK high
                if (tick_reg[0]) shift_next = {shift_reg[FRAME_BITS-2:0], 1'b0};
            end
        end
    end

    always @(posedge clk) begin
        enable_reg    <= enable_next;
        dir_reg       <= dir_next;
        dac_reg       <= dac_next;
        div_reg       <= div_next;
        period_reg    <= period_next;
        command_reg   <= command_next;
        ramp_reg      <= ramp_next;
        count_reg     <= count_next;
        level_reg     <= level_next;
        halt_prev_reg <= halt;
        pwm_reg       <= !halt && !dac_next && (count_next < level_next);
        en_reg        <= !halt && enable_next;
        dir_pin_reg   <= dir_next;
        frame_reg     <= frame_next;
        sck_reg       <= sck_next;
        tick_reg      <= tick_next;
        div_count_reg <= div_count_next;
        shift_reg     <= shift_next;
        if (rst) begin
            enable_reg    <= FS_SPINDLE_CONTROL_ENABLE_RESET;
            dir_reg       <= FS_SPINDLE_CONTROL_DIR_RESET;
            dac_reg       <= FS_SPINDLE_CONTROL_DAC_RESET;
            div_reg       <= FS_SPINDLE_CONTROL_DAC_DIV_RESET;
            period_reg    <= FS_SPINDLE_PERIOD_CLOCKS_RESET[LEVEL_W-1:0];
            command_reg   <= FS_SPINDLE_LEVEL_LEVEL_RESET[LEVEL_W-1:0];
            ramp_reg      <= FS_SPINDLE_RAMP_STEP_RESET[LEVEL_W-1:0];
            count_reg     <= {LEVEL_W{1'b0}};
            level_reg     <= {LEVEL_W{1'b0}};
            halt_prev_reg <= 1'b1;
            pwm_reg       <= 1'b0;
            en_reg        <= 1'b0;
            dir_pin_reg   <= 1'b0;
            frame_reg     <= 1'b0;
            sck_reg       <= 1'b0;
            tick_reg      <= 6'd0;
            div_count_reg <= {DIV_W{1'b0}};
            shift_reg     <= {FRAME_BITS{1'b0}};
        end
    end

    // Reads: the rw fields and the status; CAPS.HAS_SPINDLE from here, since the block
    // knows it is built (finestep_top's feedback word takes it, ORed into the read data).
    always @* begin
        rdata = 32'd0;
        case (addr)
            FS_CAPS_ADDR: rdata[FS_CAPS_HAS_SPINDLE_LSB] = 1'b1;
            FS_SPINDLE_CONTROL_ADDR: begin
                rdata[FS_SPINDLE_CONTROL_ENABLE_LSB] = enable_reg;
                rdata[FS_SPINDLE_CONTROL_DIR_LSB]    = dir_reg;
                rdata[FS_SPINDLE_CONTROL_DAC_LSB]    = dac_reg;
                rdata[FS_SPINDLE_CONTROL_DAC_DIV_LSB +: DIV_W] = div_reg;
            end
            FS_SPINDLE_PERIOD_ADDR: rdata[FS_SPINDLE_PERIOD_CLOCKS_LSB +: LEVEL_W] = period_reg;
            FS_SPINDLE_LEVEL_ADDR:  rdata[FS_SPINDLE_LEVEL_LEVEL_LSB +: LEVEL_W]   = command_reg;
            FS_SPINDLE_RAMP_ADDR:   rdata[FS_SPINDLE_RAMP_STEP_LSB +: LEVEL_W]     = ramp_reg;
            FS_SPINDLE_STATUS_ADDR: begin
                rdata[FS_SPINDLE_STATUS_LEVEL_LSB +: LEVEL_W] = level_reg;
                rdata[FS_SPINDLE_STATUS_AT_SPEED_LSB]         = (level_reg == target);
                rdata[FS_SPINDLE_STATUS_ENABLED_LSB]          = en_reg;
            end
            default: ;
        endcase
    end

    assign spindle_pwm = pwm_reg;
    assign spindle_dir = dir_pin_reg;
    assign spindle_en  = en_reg;
    assign dac_cs_n    = !frame_reg;
    assign dac_sck     = sck_reg;
    assign dac_sdi     = shift_reg[FRAME_BITS-1];

`ifdef FORMAL
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    reg f_reset_seen;   // a reset edge has set the state
    initial f_reset_seen = 1'b0;
    always @(posedge clk) if (rst) f_reset_seen <= 1'b1;
    always @(*) if (f_past_valid) assert (f_reset_seen);

    wire [31:0] f_level_wide = {{(32-LEVEL_W){1'b0}}, level_reg};
    // The frame as the DAC sees it: the word latched at CS_n's fall, the bits sampled at
    // each rising SCK, their count.
    reg [FRAME_BITS-1:0] f_word, f_bits;
    reg [5:0]            f_rises;
    reg                  f_zero_frame;   // the frame started in a cycle after a halt
    always @(posedge clk) begin
        if (!frame_reg && frame_next) begin
            f_word       <= word;
            f_bits       <= {FRAME_BITS{1'b0}};
            f_rises      <= 6'd0;
            f_zero_frame <= halt_prev_reg;
        end else if (!sck_reg && sck_next && frame_next) begin
            f_bits  <= {f_bits[FRAME_BITS-2:0], dac_sdi};
            f_rises <= f_rises + 6'd1;
        end
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // Safe state within one clock of a halt.
        if ($past(halt)) assert (!spindle_en && !spindle_pwm && level_reg == {LEVEL_W{1'b0}} && !enable_reg);
        if ($past(halt_rise)) assert (dac_cs_n && !dac_sck && count_reg == {LEVEL_W{1'b0}});
        // A frame started after a halt commands code 0.
        if (!dac_cs_n && f_zero_frame) assert (f_word[DAC_BITS-1:0] == {DAC_BITS{1'b0}});
        // The word a frame carries (spec): 0x3000 | min(level, 4095), the level of the
        // clock it starts in.
        if ($past(!frame_reg && frame_next))
            assert (f_word == (16'h3000 | (($past(f_level_wide) > 32'd4095) ? 16'd4095 : $past(f_level_wide[15:0]))));
        // The ramp: the level moves only at a period's end (or to 0 on a halt), by at most
        // the step, and never past the target.
        if (!$past(halt) && level_reg != $past(level_reg)) begin
            assert ($past(period_end));
            if ($past(ramp_reg) != {LEVEL_W{1'b0}}) begin
                if (level_reg > $past(level_reg)) assert (level_reg - $past(level_reg) <= $past(ramp_reg));
                else assert ($past(level_reg) - level_reg <= $past(ramp_reg));
            end
            if ($past(level_reg) < $past(target)) assert (level_reg > $past(level_reg) && level_reg <= $past(target));
            else assert (level_reg < $past(level_reg) && level_reg >= $past(target));
        end
        if (!$past(halt) && $past(period_end)) begin
            if ($past(ramp_reg) == {LEVEL_W{1'b0}}) assert (level_reg == $past(target));
        end
        // Pins in and out of a frame: SCK and SDI move only with CS_n low; SDI never
        // changes at a rising SCK nor while SCK is high.
        if (dac_cs_n) assert (!dac_sck && !dac_sdi);
        if ($rose(dac_sck) || ($past(dac_sck) && dac_sck)) assert ($stable(dac_sdi));
        // A frame that ends (CS_n rises without an abort) is 16 rises carrying its word.
        if ($rose(dac_cs_n) && !$past(halt_rise) && $past(dac_reg)) assert (f_rises == FRAME_BITS && f_bits == f_word);
        // The count stays in its period unless the period was just shortened.
        if (!$past(write)) assert (count_reg <= last_count);
        cover ($rose(dac_cs_n) && !$past(halt_rise) && $past(dac_reg) && f_bits != {FRAME_BITS{1'b0}});
        cover ($past(halt) && $past(spindle_en, 2));
        cover (level_reg != $past(level_reg) && !$past(halt) && $past(ramp_reg) != {LEVEL_W{1'b0}});
    end
    // SPINDLE_PERIOD, SPINDLE_LEVEL and SPINDLE_RAMP read back, at the read port, the
    // value last written to their own address (the map's reset value before any write):
    // a write elsewhere leaves them (mutant 199 of the list at dd15ecb: a LEVEL bit
    // flipped by writes to the other spindle registers).
    reg [LEVEL_W-1:0] f_period, f_command, f_ramp;
    always @(posedge clk) begin
        if (rst) begin
            f_period  <= FS_SPINDLE_PERIOD_CLOCKS_RESET[LEVEL_W-1:0];
            f_command <= FS_SPINDLE_LEVEL_LEVEL_RESET[LEVEL_W-1:0];
            f_ramp    <= FS_SPINDLE_RAMP_STEP_RESET[LEVEL_W-1:0];
        end else if (write) begin
            if (addr == FS_SPINDLE_PERIOD_ADDR) f_period  <= wdata[FS_SPINDLE_PERIOD_CLOCKS_LSB +: LEVEL_W];
            if (addr == FS_SPINDLE_LEVEL_ADDR)  f_command <= wdata[FS_SPINDLE_LEVEL_LEVEL_LSB +: LEVEL_W];
            if (addr == FS_SPINDLE_RAMP_ADDR)   f_ramp    <= wdata[FS_SPINDLE_RAMP_STEP_LSB +: LEVEL_W];
        end
    end
    always @(*) if (f_reset_seen) begin
        if (addr == FS_SPINDLE_PERIOD_ADDR) assert (rdata[FS_SPINDLE_PERIOD_CLOCKS_LSB +: LEVEL_W] == f_period);
        if (addr == FS_SPINDLE_LEVEL_ADDR)  assert (rdata[FS_SPINDLE_LEVEL_LEVEL_LSB +: LEVEL_W] == f_command);
        if (addr == FS_SPINDLE_RAMP_ADDR)   assert (rdata[FS_SPINDLE_RAMP_STEP_LSB +: LEVEL_W] == f_ramp);
`ifndef F_PINS_ONLY
        // The induction's link (the read above is a function of these).
        assert (period_reg == f_period && command_reg == f_command && ramp_reg == f_ramp);
`endif
    end
    // The PWM pin is high exactly for the first `level` counts of a period (PWM mode).
    always @(*) if (f_reset_seen && !halt_prev_reg) assert (spindle_pwm == (!dac_reg && count_reg < level_reg));
    always @(*) if (f_reset_seen && frame_reg) assert (tick_reg <= LAST_TICK[5:0] && sck_reg == tick_reg[0]);
    always @(*) if (f_reset_seen && frame_reg) assert (f_rises == (tick_reg + 6'd1) / 6'd2);
    always @(*) if (f_reset_seen && frame_reg) assert (shift_reg == (f_word << (tick_reg / 6'd2)));
    always @(*) if (f_reset_seen && frame_reg) assert (f_bits == (f_word >> (FRAME_BITS - f_rises)));
    always @(*) if (f_reset_seen && frame_reg && f_zero_frame) assert (f_word[DAC_BITS-1:0] == {DAC_BITS{1'b0}});
    always @(*) if (f_reset_seen && !frame_reg) assert (!sck_reg && shift_reg == {FRAME_BITS{1'b0}} && tick_reg == 6'd0);

    // A tick lasts DAC_DIV + 1 clocks (spec), seen at the pins: a tick begins when CS_n
    // falls or SCK changes with CS_n low; f_tick_n counts its clocks from 0. A write may
    // change DAC_DIV within a tick: the tick then lasts at most the largest DAC_DIV + 1
    // it saw, and exactly DAC_DIV + 1 when DAC_DIV held through it.
    reg              f_cs_n_prev, f_sck_prev, f_div_held_reg;
    reg [DIV_W-1:0]  f_tick_n_reg, f_div_max_reg, f_div_first_reg;
    initial f_cs_n_prev = 1'b1;
    wire             f_tick_start = !dac_cs_n && (f_cs_n_prev || dac_sck != f_sck_prev);
    wire [DIV_W-1:0] f_tick_n     = f_tick_start ? {DIV_W{1'b0}} : f_tick_n_reg + {{(DIV_W-1){1'b0}}, 1'b1};
    wire [DIV_W-1:0] f_div_max    = (f_tick_start || div_reg > f_div_max_reg) ? div_reg : f_div_max_reg;
    wire             f_div_held   = f_tick_start ? 1'b1 : (f_div_held_reg && div_reg == f_div_first_reg);
    always @(posedge clk) begin
        f_cs_n_prev     <= dac_cs_n;
        f_sck_prev      <= dac_sck;
        f_tick_n_reg    <= f_tick_n;
        f_div_max_reg   <= f_div_max;
        f_div_held_reg  <= f_div_held;
        f_div_first_reg <= f_tick_start ? div_reg : f_div_first_reg;
    end
    always @(*) if (f_reset_seen && !dac_cs_n) begin
        assert (f_tick_n <= f_div_max);
`ifndef F_PINS_ONLY
        assert (f_tick_n == div_count_reg);   // the inductive link to the divider
`endif
    end
    // A tick that ends (SCK changes or CS_n rises, no abort) with DAC_DIV held lasted exactly
    // DAC_DIV + 1 clocks.
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst && f_reset_seen && !$past(dac_cs_n) &&
                              (dac_cs_n || dac_sck != $past(dac_sck)) && !$past(halt_rise) &&
                              $past(dac_reg) && $past(f_div_held))
        assert ($past(f_tick_n) == $past(div_reg));
`endif

endmodule

`default_nettype wire
