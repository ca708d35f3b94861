`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/led_menu.md
// The gantry card's LED menu (seed 001), working without the host: a multiplexed
// 7-segment display of N_DIG digits (one digit enabled at a time, each for
// refresh_div + 1 clocks; segment and digit levels by parameter), the text of a page
// rendered into it, and a menu driven by keypad_scan's press events:
//   page 0 MODE   "    Sync" / "     Frd": the gantry mode (forward or synchronised);
//                 '#' toggles it (not while the host overrides it: then 'h' at the left)
//   page 1 ERROR  "E -32768": the signed sync error in decimal (sign against the
//                 number, leading zeros blank), or "E  hFFF6" in hex; '#' toggles
//   page 2 ALARM  "AL  0101": the latched alarm flags 3..0; '#' acknowledges (clears
//                 the latched flags whose input is low)
// 'A' next page, 'B' previous page. A flag rising at alarm_in latches and shows the
// alarm page; the decimal point of digit 0 is lit while a flag is latched. The host
// side: four 16-bit registers (write strobe, address, data; read data registered):
//   0 MODE   [0] card mode (1 sync) rw, [1] override enable rw, [2] override mode rw,
//            [3] effective mode r
//   1 PAGE   [1:0] page rw (3 ignored), [2] display override rw, [3] its hex rw,
//            [4] the error page's hex rw
//   2 VALUE  [15:0] the display override's value rw (shown instead of every page)
//   3 ALARM  [3:0] latched flags r, write 1 to clear; [7:4] alarm_in r
// Decimal: a double-dabble converter runs all the time (17 clocks a value) on the
// shown value; the decimal text shows the last finished conversion.
module led_menu #(
    parameter N_DIG          = 8,    // digits, 1..8 (the texts are 8 wide: the left ones cut)
    parameter PRE_W          = 16,   // refresh_div
    parameter SEG_ACTIVE_LOW = 0,    // segments lit low (common anode)
    parameter DIG_ACTIVE_LOW = 0     // digit enables active low
) (
    input  wire             clk,
    input  wire             rst,
    input  wire [PRE_W-1:0] refresh_div,   // each digit shown refresh_div + 1 clocks
    // keypad_scan's events
    input  wire             key_valid,
    input  wire [3:0]       key_code,      // 4 * row + column: 'A' 3, 'B' 7, '#' 14
    // the gantry's state
    input  wire [15:0]      sync_err,      // signed
    input  wire [3:0]       alarm_in,      // levels
    // host registers
    input  wire             host_wr,
    input  wire [1:0]       host_addr,
    input  wire [15:0]      host_wdata,
    output wire [15:0]      host_rdata,    // of host_addr, one clock later
    // display
    output wire [7:0]       seg,           // a..g in bits 0..6, dp in bit 7
    output wire [N_DIG-1:0] dig,           // one digit enabled at a time
    // to the gantry block and the board
    output wire             sync_mode,     // 1 synchronised, 0 forward
    output wire             alarm_pending, // a flag is latched
    output wire [1:0]       page
);

    localparam [PRE_W-1:0] PRE_ONE = {{(PRE_W-1){1'b0}}, 1'b1};
    localparam [2:0]       DIG_LAST = N_DIG[2:0] - 3'd1;   // N_DIG = 8: 7
    localparam [3:0] KEY_NEXT = 4'd3, KEY_PREV = 4'd7, KEY_ACT = 4'd14;
    localparam [1:0] PAGE_MODE = 2'd0, PAGE_ERR = 2'd1, PAGE_ALARM = 2'd2;
    // Glyphs: 0-15 hexadecimal digits, then these.
    localparam [4:0] G_BLANK = 5'd16, G_MINUS = 5'd17, G_R = 5'd18, G_N = 5'd19,
                     G_Y = 5'd20, G_C = 5'd21, G_H = 5'd22, G_L = 5'd23;
    localparam [4:0] G_0 = 5'd0, G_1 = 5'd1, G_5 = 5'd5, G_A = 5'd10, G_D = 5'd13,
                     G_E = 5'd14, G_F = 5'd15;

    // Menu and host state.
    reg [1:0]   page_reg;
    reg         card_mode_reg;
    reg         ovr_en_reg;
    reg         ovr_mode_reg;
    reg         disp_en_reg;
    reg         disp_hex_reg;
    reg         err_hex_reg;
    reg [15:0]  disp_val_reg;
    reg [3:0]   latched_reg;
    reg         sync_mode_reg;
    reg         pending_reg;
    reg [15:0]  rdata_reg;
    // Display scan.
    reg [PRE_W-1:0] ref_reg;
    reg [2:0]       dig_idx_reg;
    reg [7:0]       seg_reg;
    reg [N_DIG-1:0] dig_reg;
    // Decimal converter: step 0 loads, steps 1..16 shift.
    reg [4:0]   conv_step_reg;
    reg [15:0]  conv_bin_reg;
    reg [19:0]  conv_bcd_reg;
    reg         conv_neg_reg;
    reg [19:0]  bcd_reg;         // the last finished conversion
    reg         neg_reg;

    // The value shown in a number: the host's while it overrides the display.
    wire [15:0] value     = disp_en_reg ? disp_val_reg : sync_err;
    wire        value_hex = disp_en_reg ? disp_hex_reg : err_hex_reg;
    wire [15:0] value_abs = value[15] ? (~value + 16'h0001) : value;

    // One double-dabble step: 3 added to each BCD digit of 5 or more, then the shift.
    reg [19:0] bcd_adj;
    integer n;
    always @(*) begin
        bcd_adj = conv_bcd_reg;
        for (n = 0; n < 5; n = n + 1)
            if (conv_bcd_reg[4*n +: 4] >= 4'd5) bcd_adj[4*n +: 4] = conv_bcd_reg[4*n +: 4] + 4'd3;
    end
    // A digit of 5..9 plus 3 is 8..12: its bit 3 moves to the next digit. The top
    // digit's stays below 8 (a 16-bit magnitude has at most 32768).
    wire [19:0] bcd_shifted = {bcd_adj[18:0], conv_bin_reg[15]};
    wire        unused_top  = bcd_adj[19];

    // The number's text, characters 0..6 (0 the rightmost).
    wire [4:0] d0 = {1'b0, bcd_reg[3:0]};
    wire [4:0] d1 = {1'b0, bcd_reg[7:4]};
    wire [4:0] d2 = {1'b0, bcd_reg[11:8]};
    wire [4:0] d3 = {1'b0, bcd_reg[15:12]};
    wire [4:0] d4 = {1'b0, bcd_reg[19:16]};
    wire z4 = (bcd_reg[19:16] == 4'd0);     // digits 4 and up are zero
    wire z3 = z4 && (bcd_reg[15:12] == 4'd0);
    wire z2 = z3 && (bcd_reg[11:8] == 4'd0);
    wire z1 = z2 && (bcd_reg[7:4] == 4'd0);
    wire [34:0] num_dec = {G_BLANK,
                           (neg_reg && !z4) ? G_MINUS : G_BLANK,
                           !z4 ? d4 : ((neg_reg && !z3) ? G_MINUS : G_BLANK),
                           !z3 ? d3 : ((neg_reg && !z2) ? G_MINUS : G_BLANK),
                           !z2 ? d2 : ((neg_reg && !z1) ? G_MINUS : G_BLANK),
                           !z1 ? d1 : (neg_reg ? G_MINUS : G_BLANK),
                           d0};
    wire [34:0] num_hex = {G_BLANK, G_BLANK, G_H,
                           {1'b0, value[15:12]}, {1'b0, value[11:8]},
                           {1'b0, value[7:4]}, {1'b0, value[3:0]}};
    wire [34:0] num     = value_hex ? num_hex : num_dec;

    // The page's text, characters 7..0.
    wire        eff_mode = ovr_en_reg ? ovr_mode_reg : card_mode_reg;
    wire [39:0] text_mode = eff_mode
        ? {ovr_en_reg ? G_H : G_BLANK, G_BLANK, G_BLANK, G_BLANK, G_5, G_Y, G_N, G_C}
        : {ovr_en_reg ? G_H : G_BLANK, G_BLANK, G_BLANK, G_BLANK, G_BLANK, G_F, G_R, G_D};
    wire [39:0] text_alarm = {G_A, G_L, G_BLANK, G_BLANK,
                              latched_reg[3] ? G_1 : G_0, latched_reg[2] ? G_1 : G_0,
                              latched_reg[1] ? G_1 : G_0, latched_reg[0] ? G_1 : G_0};
    reg [39:0] text;
    always @(*) begin
        if (disp_en_reg) text = {G_BLANK, num};
        else case (page_reg)
            PAGE_MODE:  text = text_mode;
            PAGE_ERR:   text = {G_E, num};
            PAGE_ALARM: text = text_alarm;
            default:    text = {8{G_BLANK}};
        endcase
    end
    wire [4:0] glyph = text[5*dig_idx_reg +: 5];

    // Segments a..g (bits 0..6) of a glyph.
    reg [6:0] segs;
    always @(*) begin
        case (glyph)
            5'd0:  segs = 7'h3f;
            5'd1:  segs = 7'h06;
            5'd2:  segs = 7'h5b;
            5'd3:  segs = 7'h4f;
            5'd4:  segs = 7'h66;
            5'd5:  segs = 7'h6d;
            5'd6:  segs = 7'h7d;
            5'd7:  segs = 7'h07;
            5'd8:  segs = 7'h7f;
            5'd9:  segs = 7'h6f;
            5'd10: segs = 7'h77;
            5'd11: segs = 7'h7c;
            5'd12: segs = 7'h39;
            5'd13: segs = 7'h5e;
            5'd14: segs = 7'h79;
            5'd15: segs = 7'h71;
            G_MINUS: segs = 7'h40;
            G_R:   segs = 7'h50;
            G_N:   segs = 7'h54;
            G_Y:   segs = 7'h6e;
            G_C:   segs = 7'h58;
            G_H:   segs = 7'h74;
            G_L:   segs = 7'h38;
            default: segs = 7'h00;
        endcase
    end
    wire       dp       = pending_reg && (dig_idx_reg == 3'd0);
    wire [7:0] seg_on   = {dp, segs};
    wire [7:0] dig_on8  = 8'h01 << dig_idx_reg;
    wire [N_DIG-1:0] dig_on = dig_on8[N_DIG-1:0];

    // Keys and the host.
    wire key_next = key_valid && key_code == KEY_NEXT;
    wire key_prev = key_valid && key_code == KEY_PREV;
    wire key_act  = key_valid && key_code == KEY_ACT;
    wire wr_mode  = host_wr && host_addr == 2'd0;
    wire wr_page  = host_wr && host_addr == 2'd1;
    wire wr_val   = host_wr && host_addr == 2'd2;
    wire wr_alarm = host_wr && host_addr == 2'd3;
    wire [3:0] ack = ((key_act && page_reg == PAGE_ALARM && !disp_en_reg) ? 4'hf : 4'h0)
                   | (wr_alarm ? host_wdata[3:0] : 4'h0);
    wire new_alarm = (alarm_in & ~latched_reg) != 4'h0;

    reg [15:0] rdata_next;
    always @(*) begin
        case (host_addr)
            2'd0:    rdata_next = {12'h000, eff_mode, ovr_mode_reg, ovr_en_reg, card_mode_reg};
            2'd1:    rdata_next = {11'h000, err_hex_reg, disp_hex_reg, disp_en_reg, page_reg};
            2'd2:    rdata_next = disp_val_reg;
            default: rdata_next = {8'h00, alarm_in, latched_reg};
        endcase
    end

    always @(posedge clk) begin
        // The menu (keys act on the page shown; not while the host overrides the display).
        if (!disp_en_reg) begin
            if (key_next) page_reg <= (page_reg == PAGE_ALARM) ? PAGE_MODE : page_reg + 2'd1;
            if (key_prev) page_reg <= (page_reg == PAGE_MODE) ? PAGE_ALARM : page_reg - 2'd1;
            if (key_act && page_reg == PAGE_MODE && !ovr_en_reg) card_mode_reg <= !card_mode_reg;
            if (key_act && page_reg == PAGE_ERR) err_hex_reg <= !err_hex_reg;
        end
        if (wr_mode) begin
            card_mode_reg <= host_wdata[0];
            ovr_en_reg    <= host_wdata[1];
            ovr_mode_reg  <= host_wdata[2];
        end
        if (wr_page) begin
            if (host_wdata[1:0] != 2'd3) page_reg <= host_wdata[1:0];
            disp_en_reg  <= host_wdata[2];
            disp_hex_reg <= host_wdata[3];
            err_hex_reg  <= host_wdata[4];
        end
        if (wr_val) disp_val_reg <= host_wdata;
        latched_reg <= (latched_reg & ~ack) | alarm_in;
        if (new_alarm) page_reg <= PAGE_ALARM;
        sync_mode_reg <= eff_mode;
        pending_reg   <= (latched_reg != 4'h0);
        rdata_reg     <= rdata_next;

        // The converter.
        if (conv_step_reg == 5'd0) begin
            conv_bin_reg  <= value_abs;
            conv_neg_reg  <= value[15];
            conv_bcd_reg  <= 20'h00000;
            conv_step_reg <= 5'd1;
        end else begin
            conv_bin_reg <= {conv_bin_reg[14:0], 1'b0};
            conv_bcd_reg <= bcd_shifted;
            if (conv_step_reg == 5'd16) begin
                conv_step_reg <= 5'd0;
                bcd_reg       <= bcd_shifted;
                neg_reg       <= conv_neg_reg;
            end else begin
                conv_step_reg <= conv_step_reg + 5'd1;
            end
        end

        // The display scan.
        seg_reg <= SEG_ACTIVE_LOW ? ~seg_on : seg_on;
        dig_reg <= DIG_ACTIVE_LOW ? ~dig_on : dig_on;
        if (ref_reg >= refresh_div) begin
            ref_reg     <= {PRE_W{1'b0}};
            dig_idx_reg <= (dig_idx_reg >= DIG_LAST) ? 3'd0 : dig_idx_reg + 3'd1;
        end else begin
            ref_reg <= ref_reg + PRE_ONE;
        end

        if (rst) begin
            page_reg      <= PAGE_MODE;
            card_mode_reg <= 1'b0;
            ovr_en_reg    <= 1'b0;
            ovr_mode_reg  <= 1'b0;
            disp_en_reg   <= 1'b0;
            disp_hex_reg  <= 1'b0;
            err_hex_reg   <= 1'b0;
            disp_val_reg  <= 16'h0000;
            latched_reg   <= 4'h0;
            sync_mode_reg <= 1'b0;
            pending_reg   <= 1'b0;
            rdata_reg     <= 16'h0000;
            conv_step_reg <= 5'd0;
            conv_bin_reg  <= 16'h0000;
            conv_bcd_reg  <= 20'h00000;
            conv_neg_reg  <= 1'b0;
            bcd_reg       <= 20'h00000;
            neg_reg       <= 1'b0;
            ref_reg       <= {PRE_W{1'b0}};
            dig_idx_reg   <= 3'd0;
            seg_reg       <= SEG_ACTIVE_LOW ? 8'hff : 8'h00;
            dig_reg       <= DIG_ACTIVE_LOW ? {N_DIG{1'b1}} : {N_DIG{1'b0}};
        end
    end

    assign host_rdata    = rdata_reg;
    assign seg           = seg_reg;
    assign dig           = dig_reg;
    assign sync_mode     = sync_mode_reg;
    assign alarm_pending = pending_reg;
    assign page          = page_reg;

`ifdef FORMAL
    reg f_past_valid;
    reg [15:0] f_abs;      // the value the conversion under way started from
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (conv_step_reg == 5'd0) f_abs <= value_abs;

    function [16:0] f_dec;   // the BCD word's value
        input [19:0] b;
        f_dec = b[3:0] + 17'd10 * b[7:4] + 17'd100 * b[11:8] + 17'd1000 * b[15:12]
              + 17'd10000 * b[19:16];
    endfunction
    function f_bcd_ok;       // every digit 0..9
        input [19:0] b;
        f_bcd_ok = b[3:0] <= 4'd9 && b[7:4] <= 4'd9 && b[11:8] <= 4'd9
                && b[15:12] <= 4'd9 && b[19:16] <= 4'd9;
    endfunction
    wire [31:0] f_abs_ext = {16'h0000, f_abs};

    wire [N_DIG-1:0] f_dig_on = DIG_ACTIVE_LOW ? ~dig : dig;
    always @(*) if (f_past_valid && !rst) begin
        // One digit enabled at a time; never a page 3.
        assert ((f_dig_on & (f_dig_on - 1'b1)) == {N_DIG{1'b0}});
        assert (dig_idx_reg <= DIG_LAST);
        assert (page_reg != 2'd3);
        // The converter: BCD digits, and what it has shifted in is the value's top bits.
        assert (conv_step_reg <= 5'd16);
        assert (f_bcd_ok(conv_bcd_reg) && f_bcd_ok(bcd_reg));
        if (conv_step_reg != 5'd0) begin
            assert ({15'd0, f_dec(conv_bcd_reg)} == (f_abs_ext >> (32'd17 - {27'd0, conv_step_reg})));
            assert (conv_bin_reg == f_abs << (conv_step_reg - 5'd1));
            // A 16-bit value's magnitude: at most 32768, and then negative; never -0.
            assert (f_abs <= 16'h8000 && (f_abs != 16'h8000 || conv_neg_reg));
            assert (!conv_neg_reg || f_abs != 16'h0000);
        end
        assert (f_dec(bcd_reg) <= 17'd32768);
        assert (!(neg_reg && bcd_reg == 20'h00000));
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // A finished conversion is the value's magnitude and sign.
        if ($past(conv_step_reg) == 5'd16) begin
            assert ({15'd0, f_dec(bcd_reg)} == f_abs_ext);
            assert (neg_reg == $past(conv_neg_reg));
        end
        if ($past(conv_step_reg) == 5'd0) assert (conv_neg_reg == $past(value[15]) && f_abs == $past(value_abs));
        if (conv_step_reg != 5'd0 && $past(conv_step_reg) != 5'd0) assert (conv_neg_reg == $past(conv_neg_reg));
        assert (f_dig_on != {N_DIG{1'b0}});
        // The mode output follows the override, else the card's mode.
        assert (sync_mode == ($past(ovr_en_reg) ? $past(ovr_mode_reg) : $past(card_mode_reg)));
        // The card's mode changes only by '#' on the mode page (no override) or the host.
        if (card_mode_reg != $past(card_mode_reg))
            assert ($past(wr_mode) || ($past(key_act) && $past(page_reg) == PAGE_MODE
                                       && !$past(ovr_en_reg) && !$past(disp_en_reg)));
        // Alarms: an input flag is latched the next clock; a latched flag clears only by
        // an acknowledgement; a new flag shows the alarm page.
        assert ((latched_reg & $past(alarm_in)) == $past(alarm_in));
        if (($past(latched_reg) & ~latched_reg) != 4'h0) assert ($past(ack) != 4'h0);
        if ($past(new_alarm)) assert (page_reg == PAGE_ALARM);
        assert (alarm_pending == ($past(latched_reg) != 4'h0));
        // The page changes only by a key, the host or an alarm.
        if (page_reg != $past(page_reg))
            assert ($past(key_next) || $past(key_prev) || $past(wr_page) || $past(new_alarm));
        // The digit shown moves on only after refresh_div + 1 clocks.
        if (dig_idx_reg != $past(dig_idx_reg)) assert ($past(ref_reg) >= $past(refresh_div));
        cover (page_reg == PAGE_ALARM && $past(key_act) && latched_reg == 4'h0 && $past(latched_reg) != 4'h0);
        cover (sync_mode && !ovr_en_reg);
        cover ($past(conv_step_reg) == 5'd16 && neg_reg && bcd_reg == 20'h32768);
    end
`endif

endmodule

`default_nettype wire
