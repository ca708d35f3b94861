`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/position_fifo.md
// Position-control FIFO: the buffer of period records between the host's coarse
// interpolation and the period timer (seed 000's position-control buffer, PMAC's rotary
// buffer). First-word-fall-through: the head record is on rd_data whenever rd_valid.
//
// The store is a simple dual-port RAM with a registered read, so it infers block RAM;
// the read address looks one entry ahead on an internal pop. In front of it sits an
// output register (out stage) that holds the head record: the RAM's read data only ever
// goes to that register, never into the consumer's logic. The out stage is loaded from
// the store whenever the store has a committed record and the out stage is empty or
// popped by rd_pop in this cycle, so a pop with another committed record behind the head
// keeps rd_valid high (no bubble). A write to a full FIFO is refused (nothing is
// overwritten) and sets the sticky overflow; a pop of an empty FIFO does nothing.
//
// A record is written into the slot behind the staged ones in lanes of LANE_W bits
// (wr_lane, the last lane the remaining bits), in any cycles and order, and staged by
// wr_en together with that cycle's lanes: a bus slave writes a record's words as they
// arrive and holds no copy of the record. A lane written while the FIFO is full (or
// flushing) is lost, and the record it belongs to is refused at its wr_en as a write to
// a full FIFO is (overflow).
//
// Writes are staged: they enter the RAM behind the committed records and become
// readable (and count in level) only at a wr_commit in a later cycle (a commit takes the
// records staged before its cycle: one written in the same cycle stays staged);
// wr_abort drops every staged record, this cycle's included. A bus slave writes a
// frame's records as they arrive and commits them only when the frame's CRC checks, so
// a corrupted or aborted frame never reaches the period timer. Because a record is
// committed at least one edge after it was written, the RAM is never read at the edge
// that writes a committed entry: no read-during-write forwarding.
// level and full count the record in the out stage: the capacity is exactly DEPTH.
//
// Latency: commit to rd_valid 2 clocks when the FIFO is empty (write to rd_valid 3).
// With L the committed records (out stage included) and v = rd_valid before an edge, and
// pop = rd_pop && v && !flush: after the edge rd_valid = !flush && (pop ? L >= 2 :
// (v || L >= 1)). Invariants: level == written - read, level + staged <= DEPTH, and
// rd_data is the oldest unread record whenever rd_valid.
module position_fifo #(
    parameter WIDTH      = 136,
    parameter DEPTH_LOG2 = 8,
    parameter LANE_W     = 32,
    parameter HEAD_REG   = 1,     // 1: the out stage a fabric register; 0: the RAM's read register;
                                  // 2: no out stage register: the store read at the slot it left (flip-flops)
    parameter LANES      = (WIDTH + LANE_W - 1) / LANE_W   // derived
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    input  wire                flush,          // empty the FIFO (pointers and out stage)
    input  wire                clear_errors,
    // write side
    input  wire [LANES-1:0]    wr_lane,        // write these lanes of wr_data into the record being written
    input  wire [WIDTH-1:0]    wr_data,
    input  wire                wr_en,          // stage that record (with this cycle's lanes)
    input  wire                wr_commit,      // make the records staged before this cycle readable
    input  wire                wr_abort,       // drop the staged records (and this cycle's)
    // read side
    output wire                rd_valid,
    input  wire                rd_pop,
    output wire [WIDTH-1:0]    rd_data,
    // status
    output wire [DEPTH_LOG2:0] level,          // committed records (out stage included)
    output wire [DEPTH_LOG2:0] staged,         // records written but not yet committed
    output wire [DEPTH_LOG2:0] free,           // DEPTH - committed - staged, from a register
    output wire                full,           // committed + staged == DEPTH
    output wire                overflow
);

    localparam DEPTH = 1 << DEPTH_LOG2;
    localparam [DEPTH_LOG2:0] LEVEL_FULL = DEPTH[DEPTH_LOG2:0];

    // A slot read at the edge that writes it is staged, never committed, after that edge
    // (a commit does not take this cycle's write), and the RAM is read again at every
    // edge: the RAM's own read-during-write result is never used. no_rw_check spares the
    // tools' emulation of it (a second register and multiplexer, WIDTH wide).
    (* no_rw_check *) reg [WIDTH-1:0] mem [0:DEPTH-1];
    reg [DEPTH_LOG2-1:0] wr_ptr_reg;      // end of the committed records
    reg [DEPTH_LOG2-1:0] stage_ptr_reg;   // end of the staged records
    reg [DEPTH_LOG2-1:0] rd_ptr_reg;
    reg [DEPTH_LOG2:0]   level_reg;          // committed records, out stage included
    reg [DEPTH_LOG2:0]   level_int_reg;      // committed records in the RAM
    reg [DEPTH_LOG2:0]   staged_reg;
    reg [WIDTH-1:0]      ram_q_reg;          // the RAM's registered read port
    reg                  out_valid_reg;      // the out stage holds the head record
    reg [WIDTH-1:0]      out_data_reg;
    reg                  overflow_reg;
    reg                  lane_lost_reg;      // a lane of the record being written was refused

    wire [DEPTH_LOG2:0] zero = {(DEPTH_LOG2+1){1'b0}};
    wire [DEPTH_LOG2:0] one  = {{DEPTH_LOG2{1'b0}}, 1'b1};
    wire int_valid = (level_int_reg != zero);
    // free_reg == DEPTH - level - staged, kept by its own updates so that the space a bus
    // slave checks comes from a register, not from two subtractions.
    reg  [DEPTH_LOG2:0] free_reg;
    wire is_full   = (free_reg == zero);
    wire write     = wr_en && !is_full && !lane_lost_reg && !flush;
    wire [LANES-1:0] lane_write = wr_lane & {LANES{!is_full && !flush}};
    localparam LAST_LO = (LANES - 1) * LANE_W;   // the last lane: bits WIDTH-1 .. LAST_LO
    wire pop       = rd_pop && out_valid_reg && !flush;                  // the out stage
    wire pop_int   = int_valid && (!out_valid_reg || pop) && !flush;     // the RAM, into the out stage
    wire commit    = wr_commit && !wr_abort && !flush;
    wire [DEPTH_LOG2:0] staged_now = staged_reg + {{DEPTH_LOG2{1'b0}}, write};

    // The counts after this edge as selections between sums of registers only: the
    // control decisions (a pop - the period timer's boundary, from across the die - a
    // write refused when full, a commit, an abort) only choose between finished sums
    // and never enter a carry chain. With staged_now = staged + write and added =
    // commit ? staged : 0 (an abort frees staged_now, so free + staged is kept):
    wire [DEPTH_LOG2:0] free_plus_staged = free_reg + staged_reg;
    wire [DEPTH_LOG2:0] free_minus_one   = free_reg - one;
    wire [DEPTH_LOG2:0] free_plus_one    = free_reg + one;
    wire [DEPTH_LOG2:0] free_kept   = wr_abort ? free_plus_staged : (write ? free_minus_one : free_reg);
    wire [DEPTH_LOG2:0] free_popped = wr_abort ? free_plus_staged + one : (write ? free_reg : free_plus_one);
    // level + added - pop and level_int + added - pop_int, for both commit outcomes and
    // both outcomes of the pop.
    function [DEPTH_LOG2:0] count_next;
        input [DEPTH_LOG2:0] count, staged_count;
        input                commit_now, popped;
        reg   [DEPTH_LOG2:0] sum;
        begin
            sum = count + staged_count;
            if (!commit_now) count_next = popped ? count - one : count;
            else             count_next = popped ? sum - one : sum;
        end
    endfunction
    wire [DEPTH_LOG2:0] level_kept       = count_next(level_reg, staged_reg, commit, 1'b0);
    wire [DEPTH_LOG2:0] level_popped     = count_next(level_reg, staged_reg, commit, 1'b1);
    wire [DEPTH_LOG2:0] level_int_kept   = count_next(level_int_reg, staged_reg, commit, 1'b0);
    wire [DEPTH_LOG2:0] level_int_popped = count_next(level_int_reg, staged_reg, commit, 1'b1);
    wire [DEPTH_LOG2-1:0] rd_ptr_next    = rd_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, 1'b1};

    // The RAM's head after this edge: the next entry on an internal pop, else the same one.
    wire [DEPTH_LOG2-1:0] head_addr = pop_int ? rd_ptr_next : rd_ptr_reg;

    integer lane;
    always @(posedge clk) begin
        for (lane = 0; lane < LANES - 1; lane = lane + 1)
            if (lane_write[lane]) mem[stage_ptr_reg][lane*LANE_W +: LANE_W] <= wr_data[lane*LANE_W +: LANE_W];
        if (lane_write[LANES-1]) mem[stage_ptr_reg][WIDTH-1:LAST_LO] <= wr_data[WIDTH-1:LAST_LO];
    end

    // The out stage. HEAD_REG = 1: the RAM reads its head at every edge (ram_q), and
    // the out stage, a fabric register, takes it on an internal pop: the RAM's read data
    // goes only into that register. HEAD_REG = 0: the RAM's read register is the out
    // stage, read (enabled) on an internal pop from the head slot: the same contents at
    // the same edges, without a second copy of the record.
    generate
        if (HEAD_REG == 1) begin : fabric_head
            always @(posedge clk) begin
                ram_q_reg <= mem[head_addr];
                if (pop_int) out_data_reg <= ram_q_reg;
            end
        end else if (HEAD_REG == 0) begin : ram_head
            always @(posedge clk) begin
                if (pop_int) out_data_reg <= mem[rd_ptr_reg];
            end
`ifdef FORMAL
            always @(*) ram_q_reg = mem[rd_ptr_reg];   // for the properties' sake
`endif
        end else begin : store_head
            // The out stage's record is still in the slot it was loaded from, rd_ptr - 1:
            // that slot is written again only when the stage pointer reaches it, i.e.
            // with DEPTH - 1 records behind the out stage, which is full (no write). So
            // a store in flip-flops is read there, through a multiplexer, instead of
            // holding a second copy (the properties prove the two equal).
            wire [DEPTH_LOG2-1:0] head_slot = rd_ptr_reg - {{(DEPTH_LOG2-1){1'b0}}, 1'b1};
            always @(*) out_data_reg = mem[head_slot];
`ifdef FORMAL
            always @(*) ram_q_reg = mem[rd_ptr_reg];   // for the properties' sake
`endif
        end
    endgenerate

    always @(posedge clk) begin
        if (flush) begin
            wr_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            stage_ptr_reg <= {DEPTH_LOG2{1'b0}};
            rd_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            level_reg     <= zero;
            level_int_reg <= zero;
            staged_reg    <= zero;
            out_valid_reg <= 1'b0;
            free_reg      <= LEVEL_FULL;
        end else begin
            // A write takes a slot, a pop frees one, an abort frees the staged ones
            // (this cycle's write included); a commit moves records, freeing none.
            free_reg <= pop ? free_popped : free_kept;
            if (pop_int) rd_ptr_reg <= rd_ptr_next;
            out_valid_reg <= pop_int || (out_valid_reg && !pop);
            level_reg     <= pop ? level_popped : level_kept;
            level_int_reg <= pop_int ? level_int_popped : level_int_kept;
            if (wr_abort) begin
                stage_ptr_reg <= wr_ptr_reg;
                staged_reg    <= zero;
            end else if (commit) begin
                wr_ptr_reg    <= stage_ptr_reg;
                stage_ptr_reg <= stage_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, write};
                staged_reg    <= {{DEPTH_LOG2{1'b0}}, write};
            end else begin
                stage_ptr_reg <= stage_ptr_reg + {{(DEPTH_LOG2-1){1'b0}}, write};
                staged_reg    <= staged_now;
            end
        end

        if (wr_en && (is_full || lane_lost_reg) && !flush) overflow_reg <= 1'b1;
        else if (clear_errors) overflow_reg <= 1'b0;
        // A lane lost while full spoils the record being written until it is staged
        // (refused) or dropped.
        if (flush || wr_en || wr_abort) lane_lost_reg <= 1'b0;
        if (|wr_lane && is_full && !flush && !wr_en && !wr_abort) lane_lost_reg <= 1'b1;

        if (rst) begin
            wr_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            stage_ptr_reg <= {DEPTH_LOG2{1'b0}};
            rd_ptr_reg    <= {DEPTH_LOG2{1'b0}};
            level_reg     <= zero;
            level_int_reg <= zero;
            staged_reg    <= zero;
            out_valid_reg <= 1'b0;
            free_reg      <= LEVEL_FULL;
            overflow_reg  <= 1'b0;
            lane_lost_reg <= 1'b0;
        end
    end

    assign rd_valid = out_valid_reg;
    assign rd_data  = out_data_reg;
    assign level    = level_reg;
    assign staged   = staged_reg;
    assign free     = free_reg;
    assign full     = is_full;
    assign overflow = overflow_reg;

`ifdef FORMAL
    // Never overwrites, never reads empty, the levels are always right, staged records
    // are invisible until committed and gone after an abort, rd_valid follows the latency
    // rule of the header, the out stage holds the record it took from the RAM, and records
    // come out in the order they went in: an arbitrary record written at an arbitrary time
    // passes through the out stage unchanged and is rd_data exactly when everything
    // committed before it has been popped.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire [DEPTH_LOG2-1:0] f_used   = wr_ptr_reg - rd_ptr_reg;
    wire [DEPTH_LOG2-1:0] f_staged = stage_ptr_reg - wr_ptr_reg;
    // The out stage's shadow: the RAM's oldest committed entry, as the spec says, when
    // it was moved (not the read port's idea of it).
    reg [WIDTH-1:0] f_out_shadow;
    always @(posedge clk) if (pop_int) f_out_shadow <= mem[rd_ptr_reg];
    always @(*) if (f_past_valid && !rst) begin
        assert (free_reg == LEVEL_FULL - level_reg - staged_reg);
        assert ({1'b0, level_reg} + {1'b0, staged_reg} <= {1'b0, LEVEL_FULL});
        // The capacity on the ports: full (and a write refused) exactly at DEPTH records.
        assert (full == ({1'b0, level} + {1'b0, staged} == {1'b0, LEVEL_FULL}));
        assert ({1'b0, level_reg} == {1'b0, level_int_reg} + {{(DEPTH_LOG2+1){1'b0}}, out_valid_reg});
        assert (f_used == level_int_reg[DEPTH_LOG2-1:0] && f_staged == staged_reg[DEPTH_LOG2-1:0]);
        if (int_valid) assert (ram_q_reg == mem[rd_ptr_reg]);
        if (out_valid_reg) assert (out_data_reg == f_out_shadow);
    end

    // Track one record: f_tag is staged when chosen (the slot with this cycle's lanes
    // written), then must come out unchanged.
    (* anyconst *) reg [WIDTH-1:0] f_tag;
    (* anyseq *) reg f_choose;
    reg f_armed, f_inside, f_committed, f_out;
    reg [DEPTH_LOG2-1:0] f_slot;
    reg [WIDTH-1:0] f_lane_mask;
    integer f_bit;
    always @(*) for (f_bit = 0; f_bit < WIDTH; f_bit = f_bit + 1) f_lane_mask[f_bit] = lane_write[f_bit / LANE_W];
    wire [WIDTH-1:0] f_staging = (mem[stage_ptr_reg] & ~f_lane_mask) | (wr_data & f_lane_mask);
    wire f_take = write && !f_armed && (f_staging == f_tag) && f_choose;
    always @(posedge clk) begin
        if (rst || flush) begin
            f_armed     <= 1'b0;
            f_inside    <= 1'b0;
            f_committed <= 1'b0;
            f_out       <= 1'b0;
        end else begin
            if (f_take) begin
                f_armed  <= 1'b1;
                f_inside <= !wr_abort;
                f_slot   <= stage_ptr_reg;
                f_committed <= 1'b0;   // a commit takes the records staged before its cycle
            end else if (f_inside && !f_committed) begin
                if (wr_abort) f_inside <= 1'b0;
                else if (commit) f_committed <= 1'b1;
            end else if (f_inside && f_committed && !f_out && pop_int && rd_ptr_reg == f_slot) begin
                f_out <= 1'b1;
            end else if (f_inside && f_out && pop) begin
                f_inside <= 1'b0;
                f_out    <= 1'b0;
            end
        end
    end
    wire [DEPTH_LOG2-1:0] f_ahead = f_slot - rd_ptr_reg;   // committed records in front of it in the RAM
    wire [DEPTH_LOG2-1:0] f_behind_commit = f_slot - wr_ptr_reg;
    always @(*) if (f_past_valid && !rst) begin
        if (f_inside) assert (f_armed);
        if (f_out) assert (f_inside && f_committed);
        if (f_inside && f_out) begin
            assert (rd_valid && rd_data == f_tag);
        end else if (f_inside) begin
            assert (mem[f_slot] == f_tag);
            if (f_committed) begin
                // Behind the out stage and the f_ahead records in the RAM.
                assert ({1'b0, f_ahead} < level_int_reg);
                if (f_ahead == {DEPTH_LOG2{1'b0}}) assert (ram_q_reg == f_tag);
            end else begin
                assert ({1'b0, f_behind_commit} < staged_reg);
            end
        end
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(wr_en && is_full && !flush)) assert (overflow_reg);
        // A record with a lane lost while full is refused whole, and flagged.
        if ($past(|wr_lane && is_full && !flush && !wr_en && !wr_abort)) assert (lane_lost_reg);
        // ... and only that record: the next one (after its wr_en, a flush or an abort) starts
        // with no lane lost, even when a lane came with the wr_en into a full FIFO.
        if ($past(wr_en || flush || wr_abort)) assert (!lane_lost_reg);
        if ($past(wr_en && lane_lost_reg && !flush)) assert (overflow_reg && staged_reg <= $past(staged_reg));
        // Only a commit makes records readable.
        if (!$past(commit)) assert (level_reg <= $past(level_reg) || $past(flush));
        if ($past(wr_abort) && !$past(flush)) assert (staged_reg == 0);
        // An empty FIFO (or store) is never popped.
        if (!$past(int_valid)) assert (rd_ptr_reg == $past(rd_ptr_reg) || $past(flush));
        if ($past(rd_pop) && !$past(rd_valid) && !$past(flush)) assert (level_reg >= $past(level_reg));
        // The latency rule: records committed at an edge do not count at that edge.
        assert (rd_valid == (!$past(flush) && ($past(pop) ? ($past(level_reg) >= 2)
                                                          : ($past(rd_valid) || $past(level_reg) >= 1))));
        cover (is_full && staged_reg != 0 && level_reg != 0);
        cover ($past(write && wr_lane != {LANES{1'b1}}) && f_armed);
        cover (f_armed && !f_inside && f_committed);
        cover ($past(write && pop && commit && level_reg == 1));
        cover ($past(wr_abort && staged_reg == 2));
        // Write to rd_valid 2 clocks into an empty FIFO; a pop with a record behind it.
        cover (rd_valid && !$past(rd_valid) && $past(commit && level_reg == 0, 2));
        cover ($past(pop && level_reg == 2) && rd_valid && f_out);
    end
`endif

endmodule

`default_nettype wire
