`timescale 1ns / 1ps
`default_nettype none
// Board reset: the reset the board tops give finestep_top. rst is 1 from configuration
// until the clock source is stable (PLL lock) and the reset button is released, and for
// 2**STRETCH_W - 1 clocks after that. The button and the lock are asynchronous: each
// passes a two-flop synchroniser before any logic sees it.
//
// Power-up relies on the flip-flops configuring to 0 (iCE40, ECP5, MachXO2, XP2,
// Cyclone IV E and MAX II all do so without an initial value): done_reg = 0 holds rst.
//
// Latency: rst rises 4 clocks after the button is pressed or the lock is lost (2 of
// synchroniser, 1 of the counter, 1 of done_reg) and falls 2**STRETCH_W + 2 clocks
// after both are released. Invariant: every rst pulse lasts at least 2**STRETCH_W
// clocks, well above the 2 that finestep_top requires.
module board_reset #(
    parameter STRETCH_W = 4
) (
    // clock
    input  wire clk,
    // asynchronous inputs
    input  wire button_n,   // reset button, active low (tie 1'b1 where there is none)
    input  wire locked,     // the clock source is stable (tie 1'b1 without a PLL)
    // reset for the core, synchronous, active high
    output wire rst
);

    localparam [STRETCH_W-1:0] COUNT_DONE = {STRETCH_W{1'b1}};

    reg [1:0]           button_n_sync_reg;
    reg [1:0]           locked_sync_reg;
    reg [STRETCH_W-1:0] count_reg;
    reg                 done_reg;

    wire release_now = button_n_sync_reg[1] && locked_sync_reg[1];

    always @(posedge clk) begin
        button_n_sync_reg <= {button_n_sync_reg[0], button_n};
        locked_sync_reg   <= {locked_sync_reg[0], locked};
        if (!release_now) begin
            count_reg <= {STRETCH_W{1'b0}};
        end else if (count_reg != COUNT_DONE) begin
            count_reg <= count_reg + {{(STRETCH_W-1){1'b0}}, 1'b1};
        end
        done_reg <= release_now && (count_reg == COUNT_DONE);
    end

    assign rst = !done_reg;

endmodule

`default_nettype wire
