`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/encoder_bank.md (the store)
// A small simple-dual-port RAM with a registered read: the word at `rd_addr` appears on
// `rd_data` after an edge with `rd_en` (and stays until the next), `wr_data` is written
// at `wr_addr` at the edge when `wr_en`.
// The owner never reads and writes one word on one clock (the encoder bank's stall and
// schedule guarantee it, and its formal properties prove it), so the RAM is marked
// `no_rw_check`: the tools need no logic for read-during-write. BLOCK = 1 asks for block
// RAM (the iCE40, which has no distributed RAM, otherwise builds it from flip-flops);
// BLOCK = 0 lets the tool choose (distributed RAM on the ECP5 and MachXO2, flip-flops
// where a part has no RAM). Contents are not reset: the owner masks words not yet
// written.
//
// Latency: 1 clock for a read.
module store_ram #(
    parameter WIDTH  = 32,
    parameter DEPTH  = 4,
    parameter ADDR_W = 2,
    parameter BLOCK  = 0
) (
    input  wire              clk,
    input  wire              wr_en,
    input  wire [ADDR_W-1:0] wr_addr,
    input  wire [WIDTH-1:0]  wr_data,
    input  wire              rd_en,
    input  wire [ADDR_W-1:0] rd_addr,
    output wire [WIDTH-1:0]  rd_data
`ifdef FORMAL
    ,
    // Formal only: the word at f_peek_addr, unregistered, for the owner's invariants.
    input  wire [ADDR_W-1:0] f_peek_addr,
    output wire [WIDTH-1:0]  f_peek_data
`endif
);

    generate
        if (BLOCK != 0) begin : block
            (* no_rw_check, ram_style = "block" *) reg [WIDTH-1:0] mem [0:DEPTH-1];
            reg [WIDTH-1:0] rd_reg;
            always @(posedge clk) if (wr_en) mem[wr_addr] <= wr_data;
            always @(posedge clk) if (rd_en) rd_reg <= mem[rd_addr];
            assign rd_data = rd_reg;
`ifdef FORMAL
            assign f_peek_data = mem[f_peek_addr];
`endif
        end else begin : any
            (* no_rw_check *) reg [WIDTH-1:0] mem [0:DEPTH-1];
            reg [WIDTH-1:0] rd_reg;
            always @(posedge clk) if (wr_en) mem[wr_addr] <= wr_data;
            always @(posedge clk) if (rd_en) rd_reg <= mem[rd_addr];
            assign rd_data = rd_reg;
`ifdef FORMAL
            assign f_peek_data = mem[f_peek_addr];
`endif
        end
    endgenerate

endmodule

`default_nettype wire
