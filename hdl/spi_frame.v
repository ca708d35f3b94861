`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/spi_frame.md
// SPI frame layer: turns the byte stream of spi_slave_phy into register reads and
// writes and into period records for the position FIFO. Every frame is
// `cmd, addr, count`, then data; a write is applied only when the frame's CRC-16 checks
// (the FIFO stages a frame's records and commits them only then), so a corrupted,
// truncated or aborted frame changes nothing. The result of a write frame is the byte
// the host reads after the CRC; a read frame returns its data followed by a CRC of the
// header and the data.
//
// Latency: a byte's effect is decided in the clock its rx_valid arrives; the next byte
// out (tx_byte) is valid from the next clock, as spi_slave_phy needs.
module spi_frame #(
    parameter N_AXES  = 4,
    parameter LEVEL_W = 9
) (
    // clock, reset
    input  wire                     clk,
    input  wire                     rst,
    // byte stream from spi_slave_phy
    input  wire                     frame_start,
    input  wire                     frame_end,
    input  wire                     frame_whole,
    input  wire                     rx_valid,
    input  wire [7:0]               rx_byte,
    output wire [7:0]               tx_byte,
    // machine state
    input  wire [7:0]               status_byte,
    input  wire [LEVEL_W-1:0]       fifo_free,
    input  wire                     fifo_flush,
    // register bus master
    output wire                     bus_req,
    output wire                     bus_we,
    output wire [6:0]               bus_addr,
    output wire [31:0]              bus_wdata,
    input  wire                     bus_grant,
    input  wire [31:0]              bus_rdata,
    // position FIFO write port: a record's words go into its lanes as they complete
    // (lane i = axis i, lane N_AXES = the flags), and wr_en stages it
    output wire [N_AXES:0]          fifo_wr_lane,
    output wire [32*N_AXES+7:0]     fifo_wr_data,
    output wire                     fifo_wr_en,
    output wire                     fifo_wr_commit,
    output wire                     fifo_wr_abort,
    output wire                     fifo_busy,      // a FIFO frame owns the write port
    // to the register file
    output wire                     latch_hold,     // a read frame is in progress
    output wire                     crc_error,      // events, in the cycle deciding them
    output wire                     frame_error,
    output wire                     refused,
    output wire [7:0]               refused_count
);

`include "finestep_interface.vh"

    // Command and result bytes, the record layout and the CRC: FS_SPI_*, FS_REC_*.
    localparam REC_BYTES = (FS_REC_INC_WIDTH / 8) * N_AXES + FS_REC_FLAGS_WIDTH / 8;
    // The FIFO lanes are the 32-bit word register's: one increment each.
    generate
        if (FS_REC_INC_WIDTH != 32 || FS_REC_FLAGS_WIDTH > 32) begin : fs_check_lanes
            spi_frame_needs_32_bit_increments out_of_range ();
        end
    endgenerate

    localparam [3:0] PHASE_IDLE        = 4'd0;
    localparam [3:0] PHASE_ADDR        = 4'd1;
    localparam [3:0] PHASE_COUNT       = 4'd2;
    localparam [3:0] PHASE_DATA        = 4'd3;
    localparam [3:0] PHASE_CRC_HI      = 4'd4;
    localparam [3:0] PHASE_CRC_LO      = 4'd5;
    localparam [3:0] PHASE_RESULT      = 4'd6;
    localparam [3:0] PHASE_READ_DATA   = 4'd7;
    localparam [3:0] PHASE_READ_CRC_HI = 4'd8;
    localparam [3:0] PHASE_READ_CRC_LO = 4'd9;
    localparam [3:0] PHASE_READ_TAIL   = 4'd10;

    reg [3:0]       phase_reg;
    reg [7:0]       cmd_reg;
    reg [6:0]       addr_reg;
    reg [7:0]       items_left_reg;
    reg [5:0]       byte_in_item_reg;
    reg [15:0]      crc_reg;
    reg [7:0]       result_reg;
    reg [31:0]      word_reg;          // the data word of a WRITE frame, a record's last 4 bytes
    reg [31:0]      tx_word_reg;       // the word being sent by a READ frame
    reg [31:0]      next_word_reg;     // the word after it, read ahead
    reg [6:0]       read_addr_reg;     // address of the next read ahead
    reg             any_bits_reg;
    reg             fifo_busy_reg;
    reg             bus_req_reg;
    reg             bus_we_reg;
    reg [6:0]       bus_addr_reg;
    reg [31:0]      bus_wdata_reg;
    reg             read_granted_reg;  // a read granted last cycle: the register file serves it now
    reg             capture_reg;       // bus_rdata holds a read for next_word
    reg             wr_en_reg;
    reg [N_AXES:0]  wr_lane_reg;
    reg             wr_commit_reg;
    reg             wr_abort_reg;

    // The byte offered for the next byte out.
    reg [7:0] tx_now;
    always @* begin
        case (phase_reg)
            PHASE_IDLE:        tx_now = status_byte;
            PHASE_RESULT:      tx_now = result_reg;
            PHASE_READ_DATA:
                case (byte_in_item_reg[1:0])
                    2'd0:    tx_now = tx_word_reg[31:24];
                    2'd1:    tx_now = tx_word_reg[23:16];
                    2'd2:    tx_now = tx_word_reg[15:8];
                    default: tx_now = tx_word_reg[7:0];
                endcase
            PHASE_READ_CRC_HI: tx_now = crc_reg[15:8];
            PHASE_READ_CRC_LO: tx_now = crc_reg[7:0];
            default:           tx_now = 8'h00;
        endcase
    end

    wire [15:0] crc_with_rx;
    wire [15:0] crc_with_tx;
    crc16_byte crc_received (.crc_in(crc_reg), .data(rx_byte), .crc_out(crc_with_rx));
    crc16_byte crc_sent (.crc_in(crc_reg), .data(tx_now), .crc_out(crc_with_tx));

    wire is_read  = (cmd_reg == FS_SPI_CMD_READ);
    wire is_write = (cmd_reg == FS_SPI_CMD_WRITE);
    wire is_fifo  = (cmd_reg == FS_SPI_CMD_FIFO);
    wire [5:0] item_last = is_fifo ? REC_BYTES[5:0] - 6'd1 : 6'd3;
    wire count_nonzero = (rx_byte != 8'd0);
    wire fifo_room     = ({8'd0, rx_byte} <= {{(16-LEVEL_W){1'b0}}, fifo_free});   // LEVEL_W <= 16

    // Which event this cycle handles (the first that applies).
    wire do_end   = frame_end;
    wire do_start = !do_end && frame_start;
    wire do_flush = !do_end && !do_start && fifo_flush && fifo_busy_reg;
    wire do_byte  = !do_end && !do_start && !do_flush && rx_valid;

    wire incomplete = (phase_reg == PHASE_ADDR) || (phase_reg == PHASE_COUNT) ||
                      (phase_reg == PHASE_DATA) || (phase_reg == PHASE_CRC_HI) ||
                      (phase_reg == PHASE_CRC_LO) || (phase_reg == PHASE_IDLE && !frame_whole);
    wire end_error   = do_end && any_bits_reg && incomplete;
    wire count_byte  = do_byte && (phase_reg == PHASE_COUNT);
    wire fifo_refuse = count_byte && is_fifo && count_nonzero && !fifo_room;
    wire bad_header  = count_byte && !(is_read && count_nonzero) && !(is_write && rx_byte == 8'd1) &&
                       !(is_fifo && count_nonzero);
    wire crc_checked = do_byte && (phase_reg == PHASE_CRC_LO);
    // The FIFO lane a record byte completes: axis k's word at its byte 4k + 3, the flags
    // at the record's last byte (4 N_AXES).
    wire [N_AXES:0] lane_done;
    genvar lane;
    generate
        for (lane = 0; lane < N_AXES; lane = lane + 1) begin : lanes
            assign lane_done[lane] = (byte_in_item_reg == 4 * lane + 3);
        end
    endgenerate
    assign lane_done[N_AXES] = (byte_in_item_reg == item_last);
    wire crc_good    = (crc_with_rx == 16'h0000);

    always @(posedge clk) begin
        wr_en_reg     <= 1'b0;
        wr_lane_reg   <= {(N_AXES+1){1'b0}};
        wr_commit_reg <= 1'b0;
        wr_abort_reg  <= 1'b0;
        read_granted_reg <= bus_grant && !bus_we_reg;
        capture_reg      <= read_granted_reg;
        if (capture_reg) next_word_reg <= bus_rdata;
        if (bus_grant) bus_req_reg <= 1'b0;

        if (do_end) begin
            if (fifo_busy_reg) wr_abort_reg <= 1'b1;
            fifo_busy_reg <= 1'b0;
            phase_reg     <= PHASE_IDLE;
            any_bits_reg  <= 1'b0;
        end else if (do_start) begin
            phase_reg    <= PHASE_IDLE;
            crc_reg      <= FS_SPI_CRC_INITIAL;
            any_bits_reg <= 1'b1;
        end else if (do_flush) begin
            wr_abort_reg  <= 1'b1;
            fifo_busy_reg <= 1'b0;
            result_reg    <= FS_SPI_RESULT_FIFO_FLUSHED;
            phase_reg     <= PHASE_RESULT;
        end else if (do_byte) begin
            case (phase_reg)
                PHASE_IDLE: begin
                    cmd_reg   <= rx_byte;
                    crc_reg   <= crc_with_rx;
                    phase_reg <= PHASE_ADDR;
                end
                PHASE_ADDR: begin
                    addr_reg  <= rx_byte[6:0];
                    crc_reg   <= crc_with_rx;
                    phase_reg <= PHASE_COUNT;
                    if (is_read) begin
                        bus_req_reg   <= 1'b1;
                        bus_we_reg    <= 1'b0;
                        bus_addr_reg  <= rx_byte[6:0];
                        read_addr_reg <= rx_byte[6:0] + 7'd1;
                    end
                end
                PHASE_COUNT: begin
                    crc_reg          <= crc_with_rx;
                    byte_in_item_reg <= 6'd0;
                    items_left_reg   <= rx_byte;
                    if (bad_header) begin
                        result_reg <= FS_SPI_RESULT_BAD_COMMAND;
                        phase_reg  <= PHASE_RESULT;
                    end else if (fifo_refuse) begin
                        result_reg <= FS_SPI_RESULT_FIFO_REFUSED;
                        phase_reg  <= PHASE_RESULT;
                    end else if (is_read) begin
                        phase_reg     <= PHASE_READ_DATA;
                        tx_word_reg   <= next_word_reg;
                        bus_req_reg   <= 1'b1;
                        bus_we_reg    <= 1'b0;
                        bus_addr_reg  <= read_addr_reg;
                        read_addr_reg <= read_addr_reg + 7'd1;
                    end else begin
                        phase_reg <= PHASE_DATA;
                        if (is_fifo) fifo_busy_reg <= 1'b1;
                    end
                end
                PHASE_DATA: begin
                    crc_reg    <= crc_with_rx;
                    word_reg   <= {word_reg[23:0], rx_byte};
                    if (is_fifo) wr_lane_reg <= lane_done;
                    if (byte_in_item_reg == item_last) begin
                        byte_in_item_reg <= 6'd0;
                        items_left_reg   <= items_left_reg - 8'd1;
                        if (is_fifo) wr_en_reg <= 1'b1;
                        if (items_left_reg == 8'd1) phase_reg <= PHASE_CRC_HI;
                    end else begin
                        byte_in_item_reg <= byte_in_item_reg + 6'd1;
                    end
                end
                PHASE_CRC_HI: begin
                    crc_reg   <= crc_with_rx;
                    phase_reg <= PHASE_CRC_LO;
                end
                PHASE_CRC_LO: begin
                    crc_reg   <= crc_with_rx;
                    phase_reg <= PHASE_RESULT;
                    if (is_fifo) fifo_busy_reg <= 1'b0;
                    if (crc_good) begin
                        result_reg <= FS_SPI_RESULT_ACK;
                        if (is_fifo) wr_commit_reg <= 1'b1;
                        if (is_write) begin
                            bus_req_reg   <= 1'b1;
                            bus_we_reg    <= 1'b1;
                            bus_addr_reg  <= addr_reg;
                            bus_wdata_reg <= word_reg;
                        end
                    end else begin
                        result_reg <= FS_SPI_RESULT_CRC_MISMATCH;
                        if (is_fifo) wr_abort_reg <= 1'b1;
                    end
                end
                PHASE_READ_DATA: begin
                    crc_reg <= crc_with_tx;
                    if (byte_in_item_reg == 6'd3) begin
                        byte_in_item_reg <= 6'd0;
                        items_left_reg   <= items_left_reg - 8'd1;
                        if (items_left_reg == 8'd1) begin
                            phase_reg <= PHASE_READ_CRC_HI;
                        end else begin
                            tx_word_reg   <= next_word_reg;
                            bus_req_reg   <= 1'b1;
                            bus_we_reg    <= 1'b0;
                            bus_addr_reg  <= read_addr_reg;
                            read_addr_reg <= read_addr_reg + 7'd1;
                        end
                    end else begin
                        byte_in_item_reg <= byte_in_item_reg + 6'd1;
                    end
                end
                PHASE_READ_CRC_HI: phase_reg <= PHASE_READ_CRC_LO;
                PHASE_READ_CRC_LO: phase_reg <= PHASE_READ_TAIL;
                default: ;   // RESULT, READ_TAIL: the rest of the frame is ignored
            endcase
        end

        if (rst) begin
            phase_reg        <= PHASE_IDLE;
            cmd_reg          <= 8'h00;
            addr_reg         <= 7'd0;
            items_left_reg   <= 8'd0;
            byte_in_item_reg <= 6'd0;
            crc_reg          <= FS_SPI_CRC_INITIAL;
            result_reg       <= 8'h00;
            word_reg         <= 32'd0;
            tx_word_reg      <= 32'd0;
            next_word_reg    <= 32'd0;
            read_addr_reg    <= 7'd0;
            any_bits_reg     <= 1'b0;
            fifo_busy_reg    <= 1'b0;
            bus_req_reg      <= 1'b0;
            bus_we_reg       <= 1'b0;
            bus_addr_reg     <= 7'd0;
            bus_wdata_reg    <= 32'd0;
            read_granted_reg <= 1'b0;
            capture_reg      <= 1'b0;
            wr_en_reg        <= 1'b0;
            wr_lane_reg      <= {(N_AXES+1){1'b0}};
            wr_commit_reg    <= 1'b0;
            wr_abort_reg     <= 1'b0;
        end
    end

    // The record's bytes are axis 0, 1, ... (each most significant first), then flags;
    // in the FIFO axis i sits at [32i +: 32] and the flags on top. The word register
    // holds the bytes of the lane just completed, so every lane is offered the word.
    assign fifo_wr_data = {word_reg[FS_REC_FLAGS_WIDTH-1:0], {N_AXES{word_reg}}};

    assign tx_byte        = tx_now;
    assign bus_req        = bus_req_reg;
    assign bus_we         = bus_we_reg;
    assign bus_addr       = bus_addr_reg;
    assign bus_wdata      = bus_wdata_reg;
    assign fifo_wr_en     = wr_en_reg;
    assign fifo_wr_lane   = wr_lane_reg;
    assign fifo_wr_commit = wr_commit_reg;
    assign fifo_wr_abort  = wr_abort_reg;
    assign fifo_busy      = fifo_busy_reg;
    assign latch_hold     = is_read && (phase_reg != PHASE_IDLE);
    assign crc_error      = crc_checked && !crc_good;
    assign frame_error    = end_error || do_flush || bad_header;
    assign refused        = fifo_refuse;
    assign refused_count  = rx_byte;

`ifdef FORMAL
    // Nothing reaches the FIFO or the registers unless its frame's CRC checked: a
    // commit comes only in the clock after a good CRC of a FIFO frame, with exactly
    // the frame's count of records staged since its header; a register write only after
    // a good CRC of a WRITE frame; a FIFO frame that ends any other way is aborted.
    reg f_past_valid;
    reg [8:0] f_staged;       // records staged by the current FIFO frame
    reg [7:0] f_count;        // its count byte
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    // The phy's frames: a start, bytes, an end, one event per clock at most; the bus
    // grants only a request.
    reg f_open;
    always @(posedge clk) f_open <= !rst && (frame_start || (f_open && !frame_end));
    always @(*) begin
        assume (!(frame_start && frame_end) && !(frame_start && rx_valid) && !(frame_end && rx_valid));
        assume (!frame_start || !f_open);
        assume (!(frame_end || rx_valid) || f_open);
        assume (!bus_grant || bus_req);
    end
    always @(posedge clk) begin
        if (rst || (fifo_accept_now)) f_staged <= 9'd0;
        else if (wr_en_reg) f_staged <= f_staged + 9'd1;
        if (fifo_accept_now) f_count <= rx_byte;
    end
    // The lanes written since the last staged record (or the frame's header): a record
    // is staged only with every lane of it written in its own frame, in order.
    reg [N_AXES:0] f_lanes;
    always @(posedge clk) begin
        if (rst || fifo_accept_now || wr_en_reg) f_lanes <= {(N_AXES+1){1'b0}};
        else f_lanes <= f_lanes | wr_lane_reg;
    end
    wire fifo_accept_now = count_byte && is_fifo && count_nonzero && fifo_room && !bad_header;

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if (wr_commit_reg) assert ($past(crc_checked && crc_good && is_fifo));
        if (wr_commit_reg) assert (f_staged == {1'b0, f_count} && !wr_abort_reg);
        if (wr_en_reg) assert ($past(fifo_busy_reg) && $past(do_byte) && $past(phase_reg) == PHASE_DATA);
        if (wr_lane_reg != 0) assert ($past(fifo_busy_reg) && $past(do_byte) && $past(phase_reg) == PHASE_DATA);
        assert (wr_en_reg == wr_lane_reg[N_AXES]);
        if (wr_en_reg) assert ((f_lanes | wr_lane_reg) == {(N_AXES+1){1'b1}});
        if (wr_lane_reg != 0) assert ((f_lanes & wr_lane_reg) == 0 && (f_lanes & (wr_lane_reg - 1'b1)) == (wr_lane_reg - 1'b1));
        if (bus_req_reg && bus_we_reg && !$past(bus_req_reg))
            assert ($past(crc_checked && crc_good && is_write));
        if ($past(fifo_busy_reg) && !fifo_busy_reg) assert (wr_commit_reg || wr_abort_reg);
        // A register request waits unchanged for its grant: requests are made only at a
        // byte, so in a clock without one the request, its address and its data hold.
        if ($past(bus_req && !bus_grant && !rx_valid))
            assert (bus_req && bus_we == $past(bus_we) && bus_addr == $past(bus_addr) && bus_wdata == $past(bus_wdata));
        if (fifo_busy_reg) assert (is_fifo && (phase_reg == PHASE_DATA || phase_reg == PHASE_CRC_HI || phase_reg == PHASE_CRC_LO));
        cover (wr_commit_reg && f_count == 8'd2);
        cover (bus_req_reg && bus_we_reg);
    end

`ifdef F_PORTS
    // The frame at the block's ports, from docs/spec/spi_frame.md alone (no internal
    // state of the layer is read, except one lemma below that ties the layer's CRC
    // register to the spec's CRC to help the solver): the bytes handled since the frame's start, the header
    // they carry and the spec's CRC over them say what every byte out is (status, zeros,
    // the read words most significant byte first, the read CRC, the result code), which
    // register reads and writes are requested, what a FIFO record's lanes carry, and when
    // each event is counted.
    wire f_byte = rx_valid && !frame_end && !frame_start && !(fifo_flush && fifo_busy);
    wire f_flush_now = fifo_flush && fifo_busy && !frame_end && !frame_start;
    reg  [15:0] f_n;          // bytes handled since the frame's start (saturating)
    reg  [7:0]  f_cmd;        // the header
    reg  [6:0]  f_addr;
    reg  [7:0]  f_cnt;
    reg         f_room;       // FIFO: count <= FREE at the count byte
    reg         f_flushed;    // a flush of the FIFO took the frame
    reg  [15:0] f_crc;        // 0xFFFF at the start, then every byte of the frame's CRC
    reg  [31:0] f_word;       // the last four data bytes received
    reg  [31:0] f_next;       // the register bus's answer to the last read granted
    reg  [31:0] f_txw;        // the word being sent
    reg         f_rgrant, f_rserve;
    wire f_read  = (f_cmd == FS_SPI_CMD_READ);
    wire f_write = (f_cmd == FS_SPI_CMD_WRITE);
    wire f_fifo  = (f_cmd == FS_SPI_CMD_FIFO);
    // The header as the spec accepts it (after the count byte), and the data bytes after it.
    wire f_ok = (f_read && f_cnt != 8'd0) || (f_write && f_cnt == 8'd1) || (f_fifo && f_cnt != 8'd0 && f_room);
    wire [15:0] f_body = f_read ? {6'd0, f_cnt, 2'b00} : (f_write ? 16'd4 : f_cnt * REC_BYTES);
    // The byte the CRC takes: a read frame's data bytes are the bytes sent.
    wire f_crc_on = f_n < 16'd3 || (f_ok && !f_flushed && (f_read ? f_n < 16'd3 + f_body : f_n < 16'd5 + f_body));
    wire [7:0]  f_crc_byte = (f_read && f_n >= 16'd3) ? tx_byte : rx_byte;
    wire [15:0] f_crc_next;
    crc16_byte f_crc_step (.crc_in(f_crc), .data(f_crc_byte), .crc_out(f_crc_next));
    wire f_count_now = f_byte && f_n == 16'd2;
    always @(posedge clk) begin
        f_rgrant <= bus_grant && !bus_we;
        f_rserve <= f_rgrant;
        if (f_rserve) f_next <= bus_rdata;
        if (frame_end || frame_start || rst) begin
            f_n       <= 16'd0;
            f_flushed <= 1'b0;
            if (rst || frame_start) f_crc <= FS_SPI_CRC_INITIAL;
        end else if (f_flush_now) begin
            f_flushed <= 1'b1;
        end else if (f_byte) begin
            if (f_n != 16'hFFFF) f_n <= f_n + 16'd1;
            if (f_crc_on) f_crc <= f_crc_next;
            if (f_n == 16'd0) f_cmd <= rx_byte;
            if (f_n == 16'd1) f_addr <= rx_byte[6:0];
            if (f_n == 16'd2) begin
                f_cnt  <= rx_byte;
                f_room <= ({8'd0, rx_byte} <= {{(16-LEVEL_W){1'b0}}, fifo_free});
                f_txw  <= f_next;
            end
            if (f_ok && !f_read && f_n >= 16'd3 && f_n < 16'd3 + f_body) f_word <= {f_word[23:0], rx_byte};
            if (f_ok && f_read && f_n >= 16'd3 && f_n[1:0] == 2'd2 && f_n + 16'd1 < 16'd3 + f_body) f_txw <= f_next;
        end
        if (rst) begin
            f_rgrant <= 1'b0;
            f_rserve <= 1'b0;
            f_cmd    <= 8'h00;
            f_next   <= 32'd0;    // a read served too late for the host's timing sends this
            f_txw    <= 32'd0;
        end
    end
    // The byte out after f_n bytes of the frame.
    reg [7:0] f_tx;
    always @(*) begin
        if (f_flushed)                          f_tx = FS_SPI_RESULT_FIFO_FLUSHED;
        else if (f_n == 16'd0)                  f_tx = status_byte;
        else if (f_n < 16'd3)                   f_tx = 8'h00;
        else if (f_fifo && f_cnt != 8'd0 && !f_room) f_tx = FS_SPI_RESULT_FIFO_REFUSED;
        else if (!f_ok)                         f_tx = FS_SPI_RESULT_BAD_COMMAND;
        else if (f_read) begin
            if (f_n < 16'd3 + f_body)
                case (f_n[1:0])
                    2'd3:    f_tx = f_txw[31:24];   // byte 4j of the data: n = 3 + 4j
                    2'd0:    f_tx = f_txw[23:16];
                    2'd1:    f_tx = f_txw[15:8];
                    default: f_tx = f_txw[7:0];
                endcase
            else if (f_n == 16'd3 + f_body)     f_tx = f_crc[15:8];
            else if (f_n == 16'd4 + f_body)     f_tx = f_crc[7:0];
            else                                f_tx = 8'h00;
        end
        else if (f_n < 16'd5 + f_body)          f_tx = 8'h00;
        else                                    f_tx = (f_crc == 16'h0000) ? FS_SPI_RESULT_ACK : FS_SPI_RESULT_CRC_MISMATCH;
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // A lemma for the solver, no port: the layer's CRC is the spec's (two CRC chains
        // over the same free bytes are beyond the SAT solver at this depth unless it is
        // told they agree a byte at a time).
        assert (crc_reg == f_crc);
        assert (tx_byte == f_tx);
        assert (latch_hold == (f_read && f_n != 16'd0));
        assert (fifo_busy == (f_fifo && f_ok && !f_flushed && f_n >= 16'd3 && f_n < 16'd5 + f_body));
        // The register read made after byte f_n of a read frame: `addr` after the address
        // byte, then addr + 1, addr + 2, ... after the count byte and each word but the last.
        if ($past(f_byte) && f_read && (f_n == 16'd2 || (f_ok && f_n >= 16'd3 && f_n[1:0] == 2'd3 && f_n < 16'd3 + f_body)))
            assert (bus_req && !bus_we && bus_addr == ((f_n == 16'd2) ? f_addr : f_addr + 7'd1 + f_n[8:2]));
        if ($past(f_byte) && f_write && f_ok && f_n == 16'd9 && f_crc == 16'h0000)
            assert (bus_req && bus_we && bus_addr == f_addr && bus_wdata == f_word);
        // A record's lane k carries the record's bytes 4k .. 4k + 3, the flags lane its last.
        if (fifo_wr_lane[N_AXES]) assert (fifo_wr_data[32*N_AXES +: FS_REC_FLAGS_WIDTH] == f_word[FS_REC_FLAGS_WIDTH-1:0]);
    end
    genvar f_k;
    generate
        for (f_k = 0; f_k < N_AXES; f_k = f_k + 1) begin : f_lane_data
            always @(posedge clk) if (f_past_valid && !$past(rst) && !rst && fifo_wr_lane[f_k])
                assert (fifo_wr_data[32*f_k +: 32] == f_word);
        end
    endgenerate
    // The events, in the cycle deciding them.
    always @(*) if (f_past_valid && !rst) begin
        assert (refused == (f_count_now && f_fifo && rx_byte != 8'd0 &&
                            {8'd0, rx_byte} > {{(16-LEVEL_W){1'b0}}, fifo_free}));
        if (refused) assert (refused_count == rx_byte);
        assert (crc_error == (f_byte && !f_flushed && f_ok && !f_read && f_n == 16'd4 + f_body && f_crc_next != 16'h0000));
        assert (frame_error == (f_flush_now ||
            (f_count_now && !((f_read && rx_byte != 8'd0) || (f_write && rx_byte == 8'd1) || (f_fifo && rx_byte != 8'd0))) ||
            (frame_end && (f_n == 16'd1 || f_n == 16'd2 || (f_n == 16'd0 && !frame_whole) ||
                           (!f_read && f_ok && !f_flushed && f_n >= 16'd3 && f_n < 16'd5 + f_body)))));
    end
`endif
`endif

endmodule

`default_nettype wire
