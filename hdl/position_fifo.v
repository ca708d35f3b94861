`timescale 1ns / 1ps
`default_nettype none
// Position-control FIFO: the buffer of period records between the host's coarse
// interpolation and the period timer (seed 000's position-control buffer, PMAC's rotary
// buffer). First-word-fall-through: the head record is on rd_data whenever rd_valid.
//
// The storage is a simple dual-port RAM with a registered read, so it infers block RAM;
// the read address looks one entry ahead on a pop, and a write to the entry being read
// is forwarded, so rd_data is valid in the cycle after the write that fills an empty
// FIFO. A write to a full FIFO is refused (nothing is overwritten) and sets the sticky
// overflow; a pop of an empty FIFO does nothing.
//
// Writes are staged: they enter the RAM behind the committed records and become
// readable (and count in level) only at wr_commit; wr_abort drops every staged record.
// A bus slave writes a frame's records as they arrive and commits them only when the
// frame's CRC checks, so a corrupted or aborted frame never reaches the period timer.
//
// Latency: write to rd_valid 1 clock. Invariants: level == written - read, level <= DEPTH,
// and rd_data is the oldest unread record whenever rd_valid.
module position_fifo #(
    parameter WIDTH      = 136,
    parameter DEPTH_LOG2 = 8
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    input  wire                flush,          // empty the FIFO (pointers only)
    input  wire                clear_errors,
    // write side
    input  wire                wr_en,          // stage a record
    input  wire [WIDTH-1:0]    wr_data,
    input  wire                wr_commit,      // make the staged records (and this cycle's) readable
    input  wire                wr_abort,       // drop the staged records (and this cycle's)
    // read side
    output wire                rd_valid,
    input  wire                rd_pop,
    output wire [WIDTH-1:0]    rd_data,
    // status
    output wire [DEPTH_LOG2:0] level,          // committed records
    output wire [DEPTH_LOG2:0] staged,         // records written but not yet committed
    output wire                full,           // committed + staged == DEPTH
    output wire                overflow
);

    localparam DEPTH = 1 << DEPTH_LOG2;
    localparam [DEPTH_LOG2:0] LEVEL_FULL = DEPTH[DEPTH_LOG2:0];

    reg [WIDTH-1:0]      mem [0:DEPTH-1];
    reg [DEPTH_LOG2-1:0] wr_ptr_reg;      // end of the committed records
    reg [DEPTH_LOG2-1:0] stage_ptr_reg;   // end of the staged records
    reg [DEPTH_LOG2-1:0] rd_ptr_reg;
    reg [DEPTH_LOG2:0]   level_reg;
    reg [DEPTH_LOG2:0]   staged_reg;
    reg [WIDTH-1:0]      ram_q_reg;          // the RAM's registered read port
    reg [WIDTH-1:0]      bypass_reg;         // a record written into the head slot
    reg                  use_bypass_reg;
    reg                  overflow_reg;

    wire not_empty = (level_reg != {(DEPTH_LOG2+1){1'b0}});
    wire [DEPTH_LOG2:0] occupied = level_reg + staged_reg;
    wire is_full   = (occupied == LEVEL_FULL);
    wire write     = wr_en && !is_full && !flush;
    wire pop       = rd_pop && not_empty && !flush;
    wire commit    = wr_commit && !wr_abort && !flush;
    wire [DEPTH_LOG2:0] staged_now = staged_reg + {{DEPTH_LOG2{1'b0}}, write};
    wire [DEPTH_LOG2:0] one = {{DEPTH_LOG2{1'b0}}, 1'b1};

    // The head after this edge: the next entry on a pop, else the same one.
    wire [DEPTH_LOG2-1:0] head_addr = pop ? rd_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, 1'b1} : rd_ptr_reg;
    // The head entry is being written now exactly when it is the slot written.
    wire head_written = write && (head_addr == stage_ptr_reg);

    always @(posedge clk) begin
        if (write) mem[stage_ptr_reg] <= wr_data;
        ram_q_reg <= mem[head_addr];
    end

    // The forwarding sits outside the RAM so that the read port is a plain registered
    // read, which every block RAM has, whatever drives the address.
    always @(posedge clk) begin
        bypass_reg     <= wr_data;
        use_bypass_reg <= head_written;
    end
    wire [WIDTH-1:0] head = use_bypass_reg ? bypass_reg : ram_q_reg;

    always @(posedge clk) begin
        if (flush) begin
            wr_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            stage_ptr_reg <= {DEPTH_LOG2{1'b0}};
            rd_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            level_reg     <= {(DEPTH_LOG2+1){1'b0}};
            staged_reg    <= {(DEPTH_LOG2+1){1'b0}};
        end else begin
            if (pop) rd_ptr_reg <= rd_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, 1'b1};
            if (wr_abort) begin
                stage_ptr_reg <= wr_ptr_reg;
                staged_reg    <= {(DEPTH_LOG2+1){1'b0}};
                level_reg     <= level_reg - (pop ? one : {(DEPTH_LOG2+1){1'b0}});
            end else if (commit) begin
                wr_ptr_reg    <= stage_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, write};
                stage_ptr_reg <= stage_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, write};
                staged_reg    <= {(DEPTH_LOG2+1){1'b0}};
                level_reg     <= level_reg + staged_now - (pop ? one : {(DEPTH_LOG2+1){1'b0}});
            end else begin
                stage_ptr_reg <= stage_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, write};
                staged_reg    <= staged_now;
                level_reg     <= level_reg - (pop ? one : {(DEPTH_LOG2+1){1'b0}});
            end
        end

        if (wr_en && is_full && !flush) overflow_reg <= 1'b1;
        else if (clear_errors) overflow_reg <= 1'b0;

        if (rst) begin
            wr_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            stage_ptr_reg <= {DEPTH_LOG2{1'b0}};
            rd_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            level_reg     <= {(DEPTH_LOG2+1){1'b0}};
            staged_reg    <= {(DEPTH_LOG2+1){1'b0}};
            overflow_reg  <= 1'b0;
        end
    end

    assign rd_valid = not_empty;
    assign rd_data  = head;
    assign level    = level_reg;
    assign staged   = staged_reg;
    assign full     = is_full;
    assign overflow = overflow_reg;

`ifdef FORMAL
    // Never overwrites, never reads empty, the levels are always right, staged records
    // are invisible until committed and gone after an abort, and records come out in the
    // order they went in: an arbitrary record written at an arbitrary time is the head
    // exactly when everything committed before it has been popped.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire [DEPTH_LOG2-1:0] f_used   = wr_ptr_reg - rd_ptr_reg;
    wire [DEPTH_LOG2-1:0] f_staged = stage_ptr_reg - wr_ptr_reg;
    always @(*) if (f_past_valid && !rst) begin
        assert ({1'b0, level_reg} + {1'b0, staged_reg} <= {1'b0, LEVEL_FULL});
        assert (f_used == level_reg[DEPTH_LOG2-1:0] && f_staged == staged_reg[DEPTH_LOG2-1:0]);
        if (not_empty) assert (head == mem[rd_ptr_reg]);
    end

    // Track one record: f_tag is written when chosen, then must come out unchanged.
    (* anyconst *) reg [WIDTH-1:0] f_tag;
    (* anyseq *) reg f_choose;
    reg f_armed, f_inside, f_committed;
    reg [DEPTH_LOG2-1:0] f_slot;
    wire f_take = write && !f_armed && (wr_data == f_tag) && f_choose;
    always @(posedge clk) begin
        if (rst || flush) begin
            f_armed     <= 1'b0;
            f_inside    <= 1'b0;
            f_committed <= 1'b0;
        end else begin
            if (f_take) begin
                f_armed  <= 1'b1;
                f_inside <= !wr_abort;
                f_slot   <= stage_ptr_reg;
                f_committed <= commit;
            end else if (f_inside && !f_committed) begin
                if (wr_abort) f_inside <= 1'b0;
                else if (commit) f_committed <= 1'b1;
            end else if (f_inside && f_committed && pop && rd_ptr_reg == f_slot) begin
                f_inside <= 1'b0;
            end
        end
    end
    wire [DEPTH_LOG2-1:0] f_ahead = f_slot - rd_ptr_reg;   // committed records in front of it
    wire [DEPTH_LOG2-1:0] f_behind_commit = f_slot - wr_ptr_reg;
    always @(*) if (f_past_valid && !rst && f_inside) begin
        assert (mem[f_slot] == f_tag);
        if (f_committed) begin
            assert ({1'b0, f_ahead} < level_reg);
            if (f_ahead == {DEPTH_LOG2{1'b0}}) assert (rd_valid && rd_data == f_tag);
        end else begin
            assert ({1'b0, f_behind_commit} < staged_reg);
        end
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(wr_en && is_full && !flush)) assert (overflow_reg);
        // Only a commit makes records readable.
        if (!$past(commit)) assert (level_reg <= $past(level_reg) || $past(flush));
        if ($past(wr_abort) && !$past(flush)) assert (staged_reg == 0);
        if ($past(rd_pop) && !$past(not_empty)) assert (rd_ptr_reg == $past(rd_ptr_reg) || $past(flush));
        cover (is_full && staged_reg != 0 && level_reg != 0);
        cover (f_armed && !f_inside && f_committed);
        cover ($past(write && pop && commit && level_reg == 1));
        cover ($past(wr_abort && staged_reg == 2));
    end
`endif

endmodule

`default_nettype wire
