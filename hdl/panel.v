`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/finestep_top.md#panel-and-gantry
// The gantry card's panel on the chip's register bus (seed 001): keypad_scan on the 4x4
// matrix pins and led_menu on the 7-segment pins, with three registers: PANEL_SCAN (the
// scan, debounce and refresh settings), PANEL_KEYS (the debounced keys, the last press
// and a count of presses) and PANEL_MENU (the menu's four 16-bit registers in one word).
//
// The menu's host port takes one register a clock: a selector `sel` counts 0, 1, 2, 3
// every clock; a PANEL_MENU write marks all four pending with its word, and each is
// written to the menu in the clock `sel` names it (so within 4 clocks, a later write
// winning); the menu's registered read of `sel` is copied into a shadow of that register
// the clock after, and PANEL_MENU reads the shadows (the menu as it was 2 to 5 clocks
// before). The menu's mode drives the gantry (sync_mode); sync_err and alarm_in come in.
//
// Latency: a PANEL_SCAN write acts the clock after; PANEL_KEYS shows a press event the
// clock after keypad_scan's key_valid. Every pin is a register (the blocks' outputs).
module panel #(
    parameter N_DIG = 8
) (
    // clock, reset
    input  wire             clk,
    input  wire             rst,
    // register bus (the spindle's and the feedback registers' port)
    input  wire             write,
    input  wire [6:0]       addr,
    input  wire [31:0]      wdata,
    output reg  [31:0]      rdata,          // the read value of addr, this cycle
    // the gantry
    input  wire [15:0]      sync_err,       // signed, saturated
    input  wire [3:0]       alarm_in,       // {watchdog, E-stop, gantry refused, gantry alarm}
    output wire             sync_mode,      // 1 synchronised
    // pins
    input  wire [3:0]       row_n,          // asynchronous, pulled up
    output wire [3:0]       col_drive,      // one-hot: the column driven low
    output wire [7:0]       seg,            // active high
    output wire [N_DIG-1:0] dig             // active high
);

`include "finestep_regs.vh"

    localparam [1:0] M_MODE = 2'd0, M_PAGE = 2'd1, M_VALUE = 2'd2, M_ALARM = 2'd3;

    reg [15:0] scan_div_reg;
    reg [3:0]  deb_scans_reg;
    reg [11:0] refresh_reg;
    reg [7:0]  key_count_reg;
    reg [1:0]  sel_reg;
    reg [1:0]  sel_prev_reg;
    reg [3:0]  pend_reg;
    reg [31:0] pend_word_reg;
    reg [3:0]  sh_mode_reg;       // the menu's MODE register [3:0]
    reg [4:0]  sh_page_reg;       // PAGE [4:0]
    reg [15:0] sh_value_reg;      // VALUE
    reg [3:0]  sh_alarm_reg;      // ALARM [3:0], the latched flags

    wire        key_valid;
    wire [3:0]  key_code;
    wire [15:0] key_down;
    wire [15:0] menu_rdata;
    wire        alarm_pending_unused;
    wire [1:0]  page_unused;

    keypad_scan #(.PRE_W(16), .DEB_W(4)) keypad (
        .clk(clk), .rst(rst),
        .scan_div(scan_div_reg), .deb_scans(deb_scans_reg),
        .row_n(row_n), .col_drive(col_drive),
        .key_valid(key_valid), .key_code(key_code), .key_down(key_down)
    );

    // The menu's register `sel` in the PANEL_MENU layout's field of it.
    reg [15:0] menu_wdata;
    always @* begin
        menu_wdata = 16'd0;
        case (sel_reg)
            M_MODE: menu_wdata[2:0] = {pend_word_reg[FS_PANEL_MENU_OVR_MODE_LSB],
                                       pend_word_reg[FS_PANEL_MENU_OVR_EN_LSB],
                                       pend_word_reg[FS_PANEL_MENU_CARD_MODE_LSB]};
            M_PAGE: menu_wdata[4:0] = {pend_word_reg[FS_PANEL_MENU_ERR_HEX_LSB],
                                       pend_word_reg[FS_PANEL_MENU_DISP_HEX_LSB],
                                       pend_word_reg[FS_PANEL_MENU_DISP_EN_LSB],
                                       pend_word_reg[FS_PANEL_MENU_PAGE_LSB +: FS_PANEL_MENU_PAGE_WIDTH]};
            M_VALUE: menu_wdata = pend_word_reg[FS_PANEL_MENU_VALUE_LSB +: FS_PANEL_MENU_VALUE_WIDTH];
            M_ALARM: menu_wdata[3:0] = pend_word_reg[FS_PANEL_MENU_ALARM_LSB +: FS_PANEL_MENU_ALARM_WIDTH];
            default: ;
        endcase
    end

    led_menu #(.N_DIG(N_DIG), .PRE_W(16), .SEG_ACTIVE_LOW(0), .DIG_ACTIVE_LOW(0)) menu (
        .clk(clk), .rst(rst),
        .refresh_div({refresh_reg, 4'hF}),
        .key_valid(key_valid), .key_code(key_code),
        .sync_err(sync_err), .alarm_in(alarm_in),
        .host_wr(pend_reg[sel_reg]), .host_addr(sel_reg), .host_wdata(menu_wdata),
        .host_rdata(menu_rdata),
        .seg(seg), .dig(dig), .sync_mode(sync_mode),
        .alarm_pending(alarm_pending_unused), .page(page_unused)
    );
    wire unused_menu = &{1'b0, alarm_pending_unused, page_unused};

    wire scan_write = write && (addr == FS_PANEL_SCAN_ADDR);
    wire menu_write = write && (addr == FS_PANEL_MENU_ADDR);

    always @(posedge clk) begin
        if (rst) begin
            scan_div_reg  <= FS_PANEL_SCAN_SCAN_DIV_RESET;
            deb_scans_reg <= FS_PANEL_SCAN_DEB_SCANS_RESET;
            refresh_reg   <= FS_PANEL_SCAN_REFRESH_DIV_RESET;
            key_count_reg <= 8'd0;
            sel_reg       <= 2'd0;
            sel_prev_reg  <= 2'd0;
            pend_reg      <= 4'd0;
            pend_word_reg <= 32'd0;
            sh_mode_reg   <= 4'd0;
            sh_page_reg   <= 5'd0;
            sh_value_reg  <= 16'd0;
            sh_alarm_reg  <= 4'd0;
        end else begin
            if (scan_write) begin
                scan_div_reg  <= wdata[FS_PANEL_SCAN_SCAN_DIV_LSB +: FS_PANEL_SCAN_SCAN_DIV_WIDTH];
                deb_scans_reg <= wdata[FS_PANEL_SCAN_DEB_SCANS_LSB +: FS_PANEL_SCAN_DEB_SCANS_WIDTH];
                refresh_reg   <= wdata[FS_PANEL_SCAN_REFRESH_DIV_LSB +: FS_PANEL_SCAN_REFRESH_DIV_WIDTH];
            end
            if (key_valid) key_count_reg <= key_count_reg + 8'd1;
            sel_reg      <= sel_reg + 2'd1;
            sel_prev_reg <= sel_reg;
            // The register named now is written now; a new write marks all four again.
            if (menu_write) begin
                pend_reg      <= 4'b1111;
                pend_word_reg <= wdata;
            end else begin
                pend_reg[sel_reg] <= 1'b0;
            end
            // menu_rdata is the register the menu was asked for in the clock before.
            case (sel_prev_reg)
                M_MODE:  sh_mode_reg  <= menu_rdata[3:0];
                M_PAGE:  sh_page_reg  <= menu_rdata[4:0];
                M_VALUE: sh_value_reg <= menu_rdata;
                default: sh_alarm_reg <= menu_rdata[3:0];
            endcase
        end
    end

    always @* begin
        rdata = 32'd0;
        case (addr)
            FS_CAPS_ADDR: rdata[FS_CAPS_HAS_PANEL_LSB] = 1'b1;
            FS_PANEL_SCAN_ADDR: begin
                rdata[FS_PANEL_SCAN_SCAN_DIV_LSB +: FS_PANEL_SCAN_SCAN_DIV_WIDTH]       = scan_div_reg;
                rdata[FS_PANEL_SCAN_DEB_SCANS_LSB +: FS_PANEL_SCAN_DEB_SCANS_WIDTH]     = deb_scans_reg;
                rdata[FS_PANEL_SCAN_REFRESH_DIV_LSB +: FS_PANEL_SCAN_REFRESH_DIV_WIDTH] = refresh_reg;
            end
            FS_PANEL_KEYS_ADDR: begin
                rdata[FS_PANEL_KEYS_KEY_DOWN_LSB +: FS_PANEL_KEYS_KEY_DOWN_WIDTH]   = key_down;
                rdata[FS_PANEL_KEYS_LAST_KEY_LSB +: FS_PANEL_KEYS_LAST_KEY_WIDTH]   = key_code;
                rdata[FS_PANEL_KEYS_KEY_COUNT_LSB +: FS_PANEL_KEYS_KEY_COUNT_WIDTH] = key_count_reg;
            end
            FS_PANEL_MENU_ADDR: begin
                rdata[FS_PANEL_MENU_CARD_MODE_LSB] = sh_mode_reg[0];
                rdata[FS_PANEL_MENU_OVR_EN_LSB]    = sh_mode_reg[1];
                rdata[FS_PANEL_MENU_OVR_MODE_LSB]  = sh_mode_reg[2];
                rdata[FS_PANEL_MENU_MODE_LSB]      = sh_mode_reg[3];
                rdata[FS_PANEL_MENU_PAGE_LSB +: FS_PANEL_MENU_PAGE_WIDTH] = sh_page_reg[1:0];
                rdata[FS_PANEL_MENU_DISP_EN_LSB]   = sh_page_reg[2];
                rdata[FS_PANEL_MENU_DISP_HEX_LSB]  = sh_page_reg[3];
                rdata[FS_PANEL_MENU_ERR_HEX_LSB]   = sh_page_reg[4];
                rdata[FS_PANEL_MENU_ALARM_LSB +: FS_PANEL_MENU_ALARM_WIDTH] = sh_alarm_reg;
                rdata[FS_PANEL_MENU_VALUE_LSB +: FS_PANEL_MENU_VALUE_WIDTH] = sh_value_reg;
            end
            default: ;
        endcase
    end

`ifdef FORMAL
    // The sequencer (the menu's host port one register a clock): the selector turns
    // every clock; a register is written only while pending, with its field of the last
    // PANEL_MENU word; a write is taken whole in the 4 clocks after it; and, the menu
    // left alone (no key event, no alarm input), the shadows PANEL_MENU reads equal the
    // last word's fields (10 clocks after it: the last register written 4 clocks after
    // the write, read 4 later, copied the clock after). Keys: every press event counts.
    // Registers: PANEL_SCAN holds the last word written to it.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    reg        f_written;      // a PANEL_MENU write since reset
    reg [31:0] f_word;         // the last one
    reg [3:0]  f_age;          // clocks since it (saturates at 15)
    reg        f_quiet;        // no key event and no alarm input since it
    reg [3:0]  f_done;         // the registers written since it
    reg [7:0]  f_presses;      // key events since reset
    always @(posedge clk) begin
        if (rst) begin
            f_written <= 1'b0;
            f_age     <= 4'd0;
            f_quiet   <= 1'b0;
            f_done    <= 4'd0;
            f_presses <= 8'd0;
        end else begin
            if (key_valid) f_presses <= f_presses + 8'd1;
            if (menu_write) begin
                f_written <= 1'b1;
                f_word    <= wdata;
                f_age     <= 4'd1;
                f_quiet   <= 1'b1;
                f_done    <= 4'd0;
            end else begin
                if (f_age != 4'd15 && f_age != 4'd0) f_age <= f_age + 4'd1;
                if (key_valid || alarm_in != 4'd0) f_quiet <= 1'b0;
                if (pend_reg[sel_reg]) f_done[sel_reg] <= 1'b1;
            end
        end
    end

    // The menu's registers as the last word sets them (PAGE 3 leaves the page).
    wire [2:0] f_mode  = {f_word[FS_PANEL_MENU_OVR_MODE_LSB], f_word[FS_PANEL_MENU_OVR_EN_LSB],
                          f_word[FS_PANEL_MENU_CARD_MODE_LSB]};
    wire [1:0] f_page  = f_word[FS_PANEL_MENU_PAGE_LSB +: FS_PANEL_MENU_PAGE_WIDTH];
    wire [2:0] f_pflag = {f_word[FS_PANEL_MENU_ERR_HEX_LSB], f_word[FS_PANEL_MENU_DISP_HEX_LSB],
                          f_word[FS_PANEL_MENU_DISP_EN_LSB]};
    wire [15:0] f_value = f_word[FS_PANEL_MENU_VALUE_LSB +: FS_PANEL_MENU_VALUE_WIDTH];
    wire [3:0]  f_clear = f_word[FS_PANEL_MENU_ALARM_LSB +: FS_PANEL_MENU_ALARM_WIDTH];

    always @(*) if (f_past_valid && !rst) begin
        // Pending registers: only after a write, still to be written, its word kept.
        if (pend_reg != 4'd0) assert (f_written && pend_word_reg == f_word);
        if (f_age != 4'd0) assert ((pend_reg & f_done) == 4'd0 && (pend_reg | f_done) == 4'b1111);
        if (f_age >= 4'd5) assert (pend_reg == 4'd0);
        // The register written now is the one named now, with its field of the word.
        if (pend_reg[sel_reg]) begin
            case (sel_reg)
                M_MODE:  assert (menu_wdata == {13'd0, f_mode});
                M_PAGE:  assert (menu_wdata == {11'd0, f_pflag, f_page});
                M_VALUE: assert (menu_wdata == f_value);
                default: assert (menu_wdata == {12'd0, f_clear});
            endcase
        end
        // Keys are never lost: the count is the press events (mod 256).
        assert (key_count_reg == f_presses);
        // The read side: the shadows are the written word once the sequence is through.
        if (f_written && f_quiet && f_age >= 4'd10) begin
            assert (sh_mode_reg[2:0] == f_mode);
            assert (sh_mode_reg[3] == (f_mode[1] ? f_mode[2] : f_mode[0]));
            if (f_page != 2'd3) assert (sh_page_reg[1:0] == f_page);
            assert (sh_page_reg[4:2] == f_pflag);
            assert (sh_value_reg == f_value);
            assert ((sh_alarm_reg & f_clear) == 4'd0);
            // ... and so does the bus's read of PANEL_MENU.
            if (addr == FS_PANEL_MENU_ADDR)
                assert (rdata[FS_PANEL_MENU_VALUE_LSB +: FS_PANEL_MENU_VALUE_WIDTH] == f_value
                        && rdata[FS_PANEL_MENU_CARD_MODE_LSB] == f_mode[0]
                        && rdata[FS_PANEL_MENU_DISP_EN_LSB] == f_pflag[0]);
        end
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (sel_prev_reg == sel_reg - 2'd1);   // the selector turns every clock
        // PANEL_SCAN: the last word written, unchanged otherwise.
        if ($past(scan_write))
            assert (scan_div_reg == $past(wdata[FS_PANEL_SCAN_SCAN_DIV_LSB +: FS_PANEL_SCAN_SCAN_DIV_WIDTH])
                    && deb_scans_reg == $past(wdata[FS_PANEL_SCAN_DEB_SCANS_LSB +: FS_PANEL_SCAN_DEB_SCANS_WIDTH])
                    && refresh_reg == $past(wdata[FS_PANEL_SCAN_REFRESH_DIV_LSB +: FS_PANEL_SCAN_REFRESH_DIV_WIDTH]));
        else
            assert ($stable(scan_div_reg) && $stable(deb_scans_reg) && $stable(refresh_reg));
        // A press event is counted the clock after.
        assert (key_count_reg == $past(key_count_reg) + {7'd0, $past(key_valid)});
        cover (f_written && f_quiet && f_age == 4'd10 && f_value == 16'hBEEF && f_mode == 3'b101);
        cover (f_written && $past(menu_write) && $past(pend_reg) != 4'd0);   // a later write wins
        cover ($past(key_valid) && key_count_reg == 8'd2);
    end
`endif

endmodule

`default_nettype wire
