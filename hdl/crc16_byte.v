`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/crc16_byte.md
// CRC-16/IBM-3740 (the "CCITT-FALSE" CRC: polynomial 0x1021, initial value 0xFFFF,
// MSB first, no reflection, no final XOR), one byte per step, combinational: the SPI
// frame layer updates its CRC register on the clock a byte arrives, so the frame's
// result is known in the very next clock. Feeding a frame followed by its own CRC,
// high byte first, leaves zero.
module crc16_byte (
    input  wire [15:0] crc_in,
    input  wire [7:0]  data,
    output wire [15:0] crc_out
);

`include "finestep_interface.vh"

    localparam [15:0] POLYNOMIAL = FS_SPI_CRC_POLYNOMIAL;

    function [15:0] next_crc(input [15:0] crc_before, input [7:0] byte_in);
        integer bit_index;
        begin
            next_crc = crc_before;
            for (bit_index = 7; bit_index >= 0; bit_index = bit_index - 1)
                next_crc = {next_crc[14:0], 1'b0} ^ ((next_crc[15] ^ byte_in[bit_index]) ? POLYNOMIAL : 16'h0000);
        end
    endfunction

    assign crc_out = next_crc(crc_in, data);

`ifdef FORMAL
    // Appending a value's CRC (high byte, then low byte) leaves zero, for every value;
    // and the standard check value: CRC("123456789") = 0x29B1.
    always @(*) begin
        assert (next_crc(next_crc(crc_in, crc_in[15:8]), crc_in[7:0]) == 16'h0000);
        // A frame checks (the CRC over its last byte is 0) exactly when that byte is the
        // register's high byte and the register's low byte is 0: the low bytes of T[1],
        // T[2] .. T[128] are independent. (As spi_frame's check, an 8-bit compare instead
        // of the zero test cost 180 LUT4 more in the ECP5 board build: not used.)
        assert ((crc_out == 16'h0000) == (data == crc_in[15:8] && crc_in[7:0] == 8'h00));
        assert (next_crc(next_crc(next_crc(next_crc(next_crc(next_crc(next_crc(next_crc(next_crc(
                FS_SPI_CRC_INITIAL, "1"), "2"), "3"), "4"), "5"), "6"), "7"), "8"), "9") == 16'h29B1);
    end
`endif

endmodule

`default_nettype wire
