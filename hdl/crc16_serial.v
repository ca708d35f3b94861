`timescale 1ns / 1ps
`default_nettype none
// Bit-serial CRC-16/IBM-3740 (the "CCITT-FALSE" CRC: polynomial 0x1021, initial value
// 0xFFFF, MSB first, no reflection, no final XOR), one bit per clock as an SPI slave
// receives it. Feeding a frame followed by its own CRC, most significant bit first,
// leaves the register at zero: the receiver checks a frame by testing `zero`.
//
// Latency: a bit in cycle n is in crc in cycle n+1.
module crc16_serial (
    // clock, reset
    input  wire        clk,
    input  wire        rst,
    // bits
    input  wire        init,        // start a new frame (wins over bit_valid)
    input  wire        bit_valid,
    input  wire        bit_in,
    // result
    output wire [15:0] crc,
    output wire        zero
);

    localparam [15:0] POLYNOMIAL = 16'h1021;
    localparam [15:0] INITIAL    = 16'hFFFF;

    reg [15:0] crc_reg;

    wire feedback = crc_reg[15] ^ bit_in;
    wire [15:0] shifted = {crc_reg[14:0], 1'b0} ^ (feedback ? POLYNOMIAL : 16'h0000);

    always @(posedge clk) begin
        if (rst || init) crc_reg <= INITIAL;
        else if (bit_valid) crc_reg <= shifted;
    end

    assign crc  = crc_reg;
    assign zero = (crc_reg == 16'h0000);

`ifdef FORMAL
    // Appending the CRC of what was fed so far, MSB first, always leaves zero.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    (* anyseq *) reg f_start;
    reg [15:0] f_snapshot;
    reg [4:0]  f_fed;        // CRC bits appended so far; 0: not appending
    always @(posedge clk) begin
        if (rst) begin
            f_fed <= 5'd0;
        end else if (f_fed == 5'd0 && f_start && !init && !bit_valid) begin
            f_snapshot <= crc_reg;
            f_fed <= 5'd1;
        end else if (f_fed != 5'd0 && f_fed != 5'd17 && bit_valid) begin
            f_fed <= f_fed + 5'd1;
        end
    end
    // While appending, the environment feeds the snapshot's bits and never restarts.
    always @(*) if (f_fed != 5'd0 && f_fed != 5'd17) begin
        assume (!init && !rst);
        assume (bit_in == f_snapshot[5'd16 - f_fed]);
    end
    always @(posedge clk) if (f_past_valid && $past(f_fed == 5'd16 && bit_valid)) begin
        assert (zero);
        cover (f_snapshot != INITIAL);
    end
`endif

endmodule

`default_nettype wire
