`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/logic_outputs.md
// Logic outputs and the interlock: mist and flood coolant (M7/M8/M9), the work light and
// N_GPIO general outputs (M62-M65) are register bits driven to their pins; while the
// machine halts, the outputs take their safe levels (OUTPUTS_SAFE) and keep them until
// the host writes OUTPUTS again. The interlock input (e.g. a door) passes a two-flop
// synchroniser and a glitch filter (input_filter, sampled every clock: the E-stop's
// rule); while INTERLOCK.ENABLE is set and it is active, `inhibit` holds the FIFO gate
// shut (motion_control), so no run starts; BLOCKED is sticky when that held a gate
// that would have opened. The block holds its own registers on the register bus.
//
// Latency: a written OUTPUTS reaches the pins on the clock after the serving edge; a
// halt's safe levels on the clock after the halt's first cycle. An interlock change
// reaches `inhibit` 2 clocks plus max(FILTER, 1) clocks after the pin.
// Invariant (proven): one clock after any cycle with halt, the pins equal the safe
// levels of that cycle.
module logic_outputs #(
    parameter N_GPIO = 4
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // arbitrated register bus (register_file's bus stage)
    input  wire                write,
    input  wire [6:0]          addr,
    input  wire [31:0]         wdata,
    output reg  [31:0]         rdata,          // the read value of addr, this cycle
    // safety and motion
    input  wire                halt,
    input  wire                clear_errors,
    input  wire                start_blocked,  // motion_control: the interlock held a gate shut
    output wire                inhibit,        // to motion_control: no gate may open
    // pins
    input  wire                interlock_pin,  // asynchronous
    output wire                coolant_mist,
    output wire                coolant_flood,
    output wire                light,
    output wire [GPIO_W-1:0]   gpio
);

`include "finestep_regs.vh"
`include "logic_outputs_checks.vh"

    localparam GPIO_W   = (N_GPIO > 0) ? N_GPIO : 1;
    localparam OUT_W    = 3 + GPIO_W;                    // mist, flood, light, gpio
    localparam FILTER_W = FS_INTERLOCK_FILTER_WIDTH;
    localparam PRESC_W  = FS_INTERLOCK_PRESCALE_WIDTH;
    localparam [OUT_W-1:0] GPIO_MASK = {((N_GPIO > 0) ? 1'b1 : 1'b0), {(OUT_W-1){1'b1}}};   // GPIO_W is 1 then

    localparam [31:0] OUTPUTS_RESET = ({24'd0, FS_OUTPUTS_GPIO_RESET} << FS_OUTPUTS_GPIO_LSB)
                                    | ({31'd0, FS_OUTPUTS_LIGHT_RESET} << FS_OUTPUTS_LIGHT_LSB)
                                    | ({31'd0, FS_OUTPUTS_FLOOD_RESET} << FS_OUTPUTS_FLOOD_LSB)
                                    | ({31'd0, FS_OUTPUTS_MIST_RESET} << FS_OUTPUTS_MIST_LSB);
    localparam [31:0] SAFE_RESET    = ({24'd0, FS_OUTPUTS_SAFE_GPIO_RESET} << FS_OUTPUTS_SAFE_GPIO_LSB)
                                    | ({31'd0, FS_OUTPUTS_SAFE_LIGHT_RESET} << FS_OUTPUTS_SAFE_LIGHT_LSB)
                                    | ({31'd0, FS_OUTPUTS_SAFE_FLOOD_RESET} << FS_OUTPUTS_SAFE_FLOOD_LSB)
                                    | ({31'd0, FS_OUTPUTS_SAFE_MIST_RESET} << FS_OUTPUTS_SAFE_MIST_LSB);

    reg [OUT_W-1:0]    outputs_reg, safe_reg;
    reg                enable_reg, active_high_reg, blocked_reg;
    reg [FILTER_W-1:0] filter_reg;
    reg [PRESC_W-1:0]  prescale_reg;
    reg [OUT_W-1:0]    outputs_next, safe_next;

    // The filter's sampling prescaler (the hand wheel's): a sample every PRESCALE + 1
    // clocks, the first in the third cycle after reset (both synchroniser flops hold the
    // pin by then).
    reg  [PRESC_W-1:0] presc_reg;
    wire               sample = (presc_reg == {PRESC_W{1'b0}});
    always @(posedge clk) begin
        presc_reg <= sample ? prescale_reg : presc_reg - {{(PRESC_W-1){1'b0}}, 1'b1};
        if (rst) presc_reg <= {{(PRESC_W-2){1'b0}}, 2'd2};
    end

    wire level, primed;
    input_filter #(.FILTER_W(FILTER_W)) interlock_filter (
        .clk(clk), .rst(rst), .filter_len(filter_reg), .sample(sample), .pin(interlock_pin),
        .level(level), .primed(primed)
    );
    wire active = primed && (level == active_high_reg);

    // A register word's outputs: mist, flood, light at their bits, then the GPIO bits.
    function [OUT_W-1:0] unpack;
        input [31:0] w;
        unpack = {w[FS_OUTPUTS_GPIO_LSB +: GPIO_W], w[FS_OUTPUTS_LIGHT_LSB], w[FS_OUTPUTS_FLOOD_LSB],
                  w[FS_OUTPUTS_MIST_LSB]} & GPIO_MASK;
    endfunction
    function [31:0] pack;
        input [OUT_W-1:0] o;
        begin
            pack = 32'd0;
            pack[FS_OUTPUTS_MIST_LSB]  = o[0];
            pack[FS_OUTPUTS_FLOOD_LSB] = o[1];
            pack[FS_OUTPUTS_LIGHT_LSB] = o[2];
            if (N_GPIO > 0) pack[FS_OUTPUTS_GPIO_LSB +: GPIO_W] = o[OUT_W-1:3];
        end
    endfunction

    always @* begin
        outputs_next = outputs_reg;
        safe_next    = safe_reg;
        if (write && addr == FS_OUTPUTS_ADDR)      outputs_next = unpack(wdata);
        if (write && addr == FS_OUTPUTS_SAFE_ADDR) safe_next    = unpack(wdata);
        // A halt wins over a write in the same cycle: the pins go safe.
        if (halt) outputs_next = safe_reg;
    end

    always @(posedge clk) begin
        outputs_reg <= outputs_next;
        safe_reg    <= safe_next;
        if (write && addr == FS_INTERLOCK_ADDR) begin
            enable_reg      <= wdata[FS_INTERLOCK_ENABLE_LSB];
            active_high_reg <= wdata[FS_INTERLOCK_ACTIVE_HIGH_LSB];
            filter_reg      <= wdata[FS_INTERLOCK_FILTER_LSB +: FILTER_W];
            prescale_reg    <= wdata[FS_INTERLOCK_PRESCALE_LSB +: PRESC_W];
        end
        if (start_blocked) blocked_reg <= 1'b1;
        else if (clear_errors) blocked_reg <= 1'b0;
        if (rst) begin
            outputs_reg     <= unpack(OUTPUTS_RESET);
            safe_reg        <= unpack(SAFE_RESET);
            enable_reg      <= FS_INTERLOCK_ENABLE_RESET;
            active_high_reg <= FS_INTERLOCK_ACTIVE_HIGH_RESET;
            filter_reg      <= FS_INTERLOCK_FILTER_RESET;
            prescale_reg    <= FS_INTERLOCK_PRESCALE_RESET;
            blocked_reg     <= 1'b0;
        end
    end

    always @* begin
        rdata = 32'd0;
        case (addr)
            FS_CAPS_ADDR: rdata[FS_CAPS_HAS_OUTPUTS_LSB] = 1'b1;
            FS_OUTPUTS_ADDR: begin
                rdata = pack(outputs_reg);
                rdata[FS_OUTPUTS_N_GPIO_LSB +: FS_OUTPUTS_N_GPIO_WIDTH] = N_GPIO[FS_OUTPUTS_N_GPIO_WIDTH-1:0];
            end
            FS_OUTPUTS_SAFE_ADDR: rdata = pack(safe_reg);
            FS_INTERLOCK_ADDR: begin
                rdata[FS_INTERLOCK_ENABLE_LSB]                = enable_reg;
                rdata[FS_INTERLOCK_ACTIVE_HIGH_LSB]           = active_high_reg;
                rdata[FS_INTERLOCK_FILTER_LSB +: FILTER_W]    = filter_reg;
                rdata[FS_INTERLOCK_PRESCALE_LSB +: PRESC_W]   = prescale_reg;
                rdata[FS_INTERLOCK_ACTIVE_LSB]                = active;
                rdata[FS_INTERLOCK_BLOCKED_LSB]               = blocked_reg;
            end
            default: ;
        endcase
    end

    assign inhibit       = enable_reg && active;
    assign coolant_mist  = outputs_reg[0];
    assign coolant_flood = outputs_reg[1];
    assign light         = outputs_reg[2];
    assign gpio          = outputs_reg[OUT_W-1:3];

`ifdef FORMAL
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // The safe state within one clock of a halt, whatever was written.
        if ($past(halt)) assert ({gpio, light, coolant_flood, coolant_mist} == $past(safe_reg));
        // Otherwise the pins change only by a write of OUTPUTS, to the bits written.
        if (!$past(halt) && !($past(write) && $past(addr) == FS_OUTPUTS_ADDR)) assert ($stable(outputs_reg));
        if (!$past(halt) && $past(write) && $past(addr) == FS_OUTPUTS_ADDR) assert (outputs_reg == unpack($past(wdata)));
        // BLOCKED: set by a blocked start, held until cleared.
        if ($past(start_blocked)) assert (blocked_reg);
        if ($past(blocked_reg) && !$past(clear_errors)) assert (blocked_reg);
        if (!$past(start_blocked) && !$past(blocked_reg)) assert (!blocked_reg);
        // Samples every PRESCALE + 1 clocks: a sample reloads PRESCALE, others count down;
        // between samples the filtered input holds.
        if ($past(sample)) assert (presc_reg == $past(prescale_reg));
        else assert (presc_reg == $past(presc_reg) - 1);
        if (!$past(sample)) assert (level == $past(level) && primed == $past(primed));
        // OUTPUTS_SAFE and INTERLOCK take what is written to their fields and hold
        // otherwise (the fields from the register map, not through the RTL's helpers).
        if ($past(write) && $past(addr) == FS_OUTPUTS_SAFE_ADDR) begin
            assert (safe_reg[0] == $past(wdata[FS_OUTPUTS_SAFE_MIST_LSB]) && safe_reg[1] == $past(wdata[FS_OUTPUTS_SAFE_FLOOD_LSB]) &&
                    safe_reg[2] == $past(wdata[FS_OUTPUTS_SAFE_LIGHT_LSB]));
            if (N_GPIO > 0) assert (safe_reg[OUT_W-1:3] == $past(wdata[FS_OUTPUTS_SAFE_GPIO_LSB +: GPIO_W]));
        end else assert ($stable(safe_reg));
        if ($past(write) && $past(addr) == FS_INTERLOCK_ADDR)
            assert (enable_reg == $past(wdata[FS_INTERLOCK_ENABLE_LSB]) && active_high_reg == $past(wdata[FS_INTERLOCK_ACTIVE_HIGH_LSB]) &&
                    filter_reg == $past(wdata[FS_INTERLOCK_FILTER_LSB +: FILTER_W]) &&
                    prescale_reg == $past(wdata[FS_INTERLOCK_PRESCALE_LSB +: PRESC_W]));
        else assert ($stable(enable_reg) && $stable(active_high_reg) && $stable(filter_reg) && $stable(prescale_reg));
        cover ($past(halt) && $past(outputs_reg) != $past(safe_reg));
        cover (inhibit);
    end
    // Bits above N_GPIO never hold a 1.
    always @(*) if (f_past_valid && N_GPIO == 0) assert (outputs_reg[3] == 1'b0 && safe_reg[3] == 1'b0);
    // What a read returns, word by word from the register map's fields (a bit no field
    // names reads 0).
    wire [31:0] f_outputs_word = ({31'd0, coolant_mist} << FS_OUTPUTS_MIST_LSB) |
                                 ({31'd0, coolant_flood} << FS_OUTPUTS_FLOOD_LSB) |
                                 ({31'd0, light} << FS_OUTPUTS_LIGHT_LSB) |
                                 ((N_GPIO > 0 ? {{(32-GPIO_W){1'b0}}, gpio} : 32'd0) << FS_OUTPUTS_GPIO_LSB) |
                                 (N_GPIO << FS_OUTPUTS_N_GPIO_LSB);
    wire [31:0] f_safe_word    = ({31'd0, safe_reg[0]} << FS_OUTPUTS_SAFE_MIST_LSB) |
                                 ({31'd0, safe_reg[1]} << FS_OUTPUTS_SAFE_FLOOD_LSB) |
                                 ({31'd0, safe_reg[2]} << FS_OUTPUTS_SAFE_LIGHT_LSB) |
                                 ((N_GPIO > 0 ? {{(32-GPIO_W){1'b0}}, safe_reg[OUT_W-1:3]} : 32'd0)
                                  << FS_OUTPUTS_SAFE_GPIO_LSB);
    wire [31:0] f_interlock_word = ({31'd0, enable_reg} << FS_INTERLOCK_ENABLE_LSB) |
                                   ({31'd0, active_high_reg} << FS_INTERLOCK_ACTIVE_HIGH_LSB) |
                                   ({{(32-FILTER_W){1'b0}}, filter_reg} << FS_INTERLOCK_FILTER_LSB) |
                                   ({31'd0, active} << FS_INTERLOCK_ACTIVE_LSB) |
                                   ({31'd0, blocked_reg} << FS_INTERLOCK_BLOCKED_LSB) |
                                   ({{(32-PRESC_W){1'b0}}, prescale_reg} << FS_INTERLOCK_PRESCALE_LSB);
    always @(*) if (f_past_valid && !rst) begin
        if (addr == FS_CAPS_ADDR) assert (rdata == (32'd1 << FS_CAPS_HAS_OUTPUTS_LSB));
        if (addr == FS_OUTPUTS_ADDR) assert (rdata == f_outputs_word);
        if (addr == FS_OUTPUTS_SAFE_ADDR) assert (rdata == f_safe_word);
        if (addr == FS_INTERLOCK_ADDR) assert (rdata == f_interlock_word);
        if (addr != FS_CAPS_ADDR && addr != FS_OUTPUTS_ADDR && addr != FS_OUTPUTS_SAFE_ADDR && addr != FS_INTERLOCK_ADDR)
            assert (rdata == 32'd0);
    end
    // Out of reset INTERLOCK reads the register map's reset values in its writable fields
    // (a reset value's bit of PRESCALE tied to 0, mutant 82 of the list at dd15ecb, kept
    // every property above: they follow the register, not what reset puts in it).
    always @(posedge clk) if (f_past_valid && $past(rst) && !rst && addr == FS_INTERLOCK_ADDR)
        assert (rdata[FS_INTERLOCK_ENABLE_LSB] == FS_INTERLOCK_ENABLE_RESET &&
                rdata[FS_INTERLOCK_ACTIVE_HIGH_LSB] == FS_INTERLOCK_ACTIVE_HIGH_RESET &&
                rdata[FS_INTERLOCK_FILTER_LSB +: FILTER_W] == FS_INTERLOCK_FILTER_RESET &&
                rdata[FS_INTERLOCK_PRESCALE_LSB +: PRESC_W] == FS_INTERLOCK_PRESCALE_RESET);
    // inhibit only while enabled and the filtered input is active.
    always @(*) if (inhibit) assert (enable_reg && primed && level == active_high_reg);
`endif

endmodule

`default_nettype wire
