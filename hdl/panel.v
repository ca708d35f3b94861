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

endmodule

`default_nettype wire
