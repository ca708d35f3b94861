`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/spi_slave_phy.md
// SPI mode-0 slave, byte level: the pins of the host link (an STM32 or a Raspberry Pi
// as master) brought into the core clock domain. CS_n, SCK and MOSI pass two-flop
// synchronisers; a rising SCK edge samples MOSI, a falling one shifts MISO. Bytes go
// MSB first. A frame is everything between CS_n falling and rising: frame_start and
// frame_end pulse at those edges, and frame_end says whether the frame ended on a byte
// boundary, so the frame layer can drop a frame whose chip select was released early.
//
// Timing: the core clock must be at least 8x SCK (6.25 MHz SCK at 50 MHz) and the
// master must leave 4 core clocks between CS_n falling and the first SCK edge: MISO
// changes 3-4 clocks after the SCK edge that asks for it.
//
// Latency: a byte is on rx_byte with rx_valid 3 clocks after its 8th rising SCK edge.
// tx_byte is sampled at frame start and with every rx_valid, for the next byte out.
module spi_slave_phy (
    // clock, reset
    input  wire       clk,
    input  wire       rst,
    // pins (asynchronous)
    input  wire       spi_cs_n,
    input  wire       spi_sck,
    input  wire       spi_mosi,
    output wire       spi_miso,
    output wire       spi_miso_oe,   // drive MISO only while selected
    // byte stream
    output wire       frame_start,
    output wire       frame_end,
    output wire       frame_whole,   // with frame_end: the frame ended on a byte boundary
    output wire       rx_valid,
    output wire [7:0] rx_byte,
    input  wire [7:0] tx_byte
);

    localparam [2:0] LAST_BIT = 3'd7;

    // Two-flop synchronisers, then one more flop for edge detection.
    reg [1:0] cs_n_sync_reg;
    reg [2:0] sck_sync_reg;
    reg [1:0] mosi_sync_reg;

    reg       selected_reg;
    reg [2:0] bit_count_reg;
    reg [6:0] rx_shift_reg;   // the first seven bits of the byte being received
    reg [7:0] tx_shift_reg;
    reg       rx_valid_reg;
    reg [7:0] rx_byte_reg;
    reg       frame_start_reg;
    reg       frame_end_reg;
    reg       frame_whole_reg;

    wire cs_active  = !cs_n_sync_reg[1];
    wire select     = cs_active && !selected_reg;
    wire deselect   = !cs_active && selected_reg;
    wire sck_rise   = selected_reg && cs_active && sck_sync_reg[1] && !sck_sync_reg[2];
    wire sck_fall   = selected_reg && cs_active && !sck_sync_reg[1] && sck_sync_reg[2];
    wire byte_done  = sck_rise && (bit_count_reg == LAST_BIT);

    always @(posedge clk) begin
        cs_n_sync_reg <= {cs_n_sync_reg[0], spi_cs_n};
        sck_sync_reg  <= {sck_sync_reg[1:0], spi_sck};
        mosi_sync_reg <= {mosi_sync_reg[0], spi_mosi};

        frame_start_reg <= select;
        frame_end_reg   <= deselect;
        frame_whole_reg <= deselect && (bit_count_reg == 3'd0);
        rx_valid_reg    <= byte_done;

        if (select) selected_reg <= 1'b1;
        else if (deselect) selected_reg <= 1'b0;

        if (select) begin
            bit_count_reg <= 3'd0;
            tx_shift_reg  <= tx_byte;
        end else if (sck_rise) begin
            bit_count_reg <= bit_count_reg + 3'd1;
            rx_shift_reg  <= {rx_shift_reg[5:0], mosi_sync_reg[1]};
            if (byte_done) rx_byte_reg <= {rx_shift_reg[6:0], mosi_sync_reg[1]};
        end else if (sck_fall) begin
            // The next bit out; after the 8th bit the next byte's MSB.
            tx_shift_reg <= (bit_count_reg == 3'd0) ? tx_byte : {tx_shift_reg[6:0], 1'b0};
        end

        if (rst) begin
            cs_n_sync_reg   <= 2'b11;
            sck_sync_reg    <= 3'b000;
            mosi_sync_reg   <= 2'b00;
            rx_shift_reg    <= 7'd0;
            tx_shift_reg    <= 8'd0;
            rx_byte_reg     <= 8'd0;
            selected_reg    <= 1'b0;
            bit_count_reg   <= 3'd0;
            rx_valid_reg    <= 1'b0;
            frame_start_reg <= 1'b0;
            frame_end_reg   <= 1'b0;
            frame_whole_reg <= 1'b0;
        end
    end

    assign spi_miso    = tx_shift_reg[7];
    assign spi_miso_oe = selected_reg;
    assign frame_start = frame_start_reg;
    assign frame_end   = frame_end_reg;
    assign frame_whole = frame_whole_reg;
    assign rx_valid    = rx_valid_reg;
    assign rx_byte     = rx_byte_reg;

`ifdef FORMAL
`ifndef F_FRAMES
    // An abstract master at the fastest timing above (but for two half periods one clock
    // longer, below) sends two arbitrary bytes in one
    // frame and reads MISO; the frame layer offers two arbitrary bytes, the second from
    // the first rx_valid on. The slave must receive exactly the bytes sent and the master
    // read exactly the bytes offered (BMC over the whole frame).
    localparam F_HALF = 4;   // core clocks per SCK half period (SCK = clk / 8)
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    (* anyconst *) reg [15:0] f_sent;      // the bytes the master sends, first in [15:8]
    (* anyconst *) reg [15:0] f_offered;   // the bytes the frame layer offers
    reg [3:0] f_phase;                     // clocks into the current half period
    reg [5:0] f_edge;                      // SCK edges so far in the frame (16 a byte)
    reg       f_lead;                      // waiting out the lead time after CS falls
    reg [15:0] f_read;                     // what the master sampled on MISO
    reg [1:0] f_received;                  // rx_valid pulses so far
    reg       f_cs_n, f_sck;
    // Two half periods last one clock more (the core clock at least 8x SCK allows slower,
    // uneven SCKs): those ending in the 1st and in the 7th falling edge, so that MISO's
    // first shift and the 8th rising edge come an odd number of clocks after the event
    // before them.
    wire      f_stretch  = !f_lead && (f_edge == 6'd1 || f_edge == 6'd13);
    wire      f_half_end = f_phase == F_HALF - 1 + f_stretch;

    always @(*) begin
        assume (spi_cs_n == f_cs_n && spi_sck == f_sck);
        assume (tx_byte == ((f_received == 2'd0) ? f_offered[15:8] : f_offered[7:0]));
        // MOSI carries bit (15 - rising edges so far) and changes after falling edges.
        assume (spi_mosi == f_sent[4'd15 - f_edge[4:1]]);
    end

    always @(posedge clk) begin
        if (rst) begin
            f_cs_n <= 1'b1; f_sck <= 1'b0; f_phase <= 4'd0; f_edge <= 6'd0; f_lead <= 1'b1;
            f_received <= 2'd0;
        end else begin
            if (rx_valid) f_received <= f_received + 2'd1;
            if (f_cs_n) begin
                f_cs_n <= 1'b0; f_phase <= 4'd0; f_lead <= 1'b1; f_edge <= 6'd0;
            end else if (!f_half_end) begin
                f_phase <= f_phase + 4'd1;
            end else if (f_lead) begin
                f_lead <= 1'b0; f_phase <= 4'd0;
            end else if (f_edge != 6'd32) begin
                f_sck <= !f_sck; f_phase <= 4'd0; f_edge <= f_edge + 6'd1;
                if (!f_sck) f_read <= {f_read[14:0], spi_miso};   // sampled at the rising edge
            end
        end
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && rx_valid)
        assert (rx_byte == ((f_received == 2'd0) ? f_sent[15:8] : f_sent[7:0]));
    always @(*) if (f_past_valid && !rst) begin
        assert (f_received <= 2'd2);
        if (f_edge == 6'd32) assert (f_read == f_offered);
    end
    always @(posedge clk) if (f_past_valid) cover (rx_valid && f_received == 2'd1);
`else
    // Frames of any length (task frames, the pins free): FRAME_WHOLE is the spec's "the
    // frame ended on a byte boundary", counted at the pins: the SCK rises between CS's
    // fall and its rise, both seen through a two-flop synchroniser, a multiple of 8.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    reg [1:0] f_cs;
    reg [2:0] f_sck;
    reg       f_in;
    reg [2:0] f_rises;   // mod 8
    always @(posedge clk) begin
        f_cs  <= {f_cs[0], spi_cs_n};
        f_sck <= {f_sck[1:0], spi_sck};
        if (!f_cs[1] && !f_in) begin
            f_in    <= 1'b1;
            f_rises <= 3'd0;
        end else if (f_cs[1] && f_in) begin
            f_in <= 1'b0;
        end else if (f_in && f_sck[1] && !f_sck[2]) begin
            f_rises <= f_rises + 3'd1;
        end
        if (rst) begin
            f_cs    <= 2'b11;
            f_sck   <= 3'b000;
            f_in    <= 1'b0;
            f_rises <= 3'd0;
        end
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if (frame_end) assert (frame_whole == (f_rises == 3'd0));
        if (!frame_end) assert (!frame_whole);
    end
    // What makes the above inductive: the pin-side view is the slave's own.
    always @(*) if (f_past_valid && !rst)
        assert (f_cs == cs_n_sync_reg && f_sck == sck_sync_reg && f_in == selected_reg && f_rises == bit_count_reg);
`endif
`endif

endmodule

`default_nettype wire
