`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/encoder_bank.md
// Encoder bank: N_ENC quadrature channels (gratings, motor encoders) served by one
// decoder in turn, and the probe input. Slot s of S = max(N_ENC, 2) is a visit of
// channel s: its state is read from the store (a RAM where the part has one) the clock
// before, updated by the one quadrature_channel datapath, and written back at the
// visit's edge (with LIVE_WR_REG, from a register at the edge after it). The copies the host reads (counts and edge times taken with the
// position latch, index and probe latches) are written at the channel's first visit at
// or after the cycle asking for them, from the values before the visit's update, which
// are the values of that cycle: one instant for every channel, within S clocks.
//
// A register read of a channel's copy served in the cycle of that channel's visit
// stalls the engine one clock, so a RAM never reads and writes one word on one clock.
// The read comes from the register bus's stage (flip-flops), not from its arbiter: no
// bus address decode in front of the grant reaches the schedule. The copy is read at
// the edge ending the serving cycle and shown from the next cycle until the next read
// (the register file ORs it after its read register, so a read's rdata still appears
// in the cycle after its serving cycle).
//
// Narrow words (COUNT_W 16, finestep_top's ENC_COUNT_W): each channel's count and edge
// time, in the store and in the copies, are COUNT_W bits (the count wraps at 2^COUNT_W, the
// edge time is TIMESTAMP's low COUNT_W bits); a read returns a count sign-extended and an
// edge time zero-extended, and the host extends them (docs/spec/encoder_bank.md#narrow-words).
//
// Latency: a pin change reaches the count 2 clocks plus max(FILTER, 1) samples later,
// samples of a channel coming every S * (PRESCALE + 1) clocks at its slot (plus stalls).
module encoder_bank #(
    parameter N_ENC    = 4,
    parameter N_AXES   = 4,
    parameter FILTER_W = 4,
    parameter RAM_BLOCK = 0,     // 1: the stores in block RAM (store_ram)
    parameter COPY_FF   = 0,     // 1: the stores in flip-flops (no RAM): the live state read in its
                                 // visit, the copies through one shared read register
    parameter PROBE_COPY = 1,    // 0: no probe snapshot of TIMESTAMP and the positions here (the
                                 // register file's latch takes it: finestep_top's ONE_SNAPSHOT)
    parameter COUNT_W    = 32    // 16: narrow words (finestep_top's ENC_COUNT_W): each channel's count
                                 // and edge time, and their copies, 16 bits; reads extend them
) (
    // clock, reset
    input  wire                         clk,
    input  wire                         rst,
    // pins (asynchronous)
    input  wire [N_ENC-1:0]             enc_a,
    input  wire [N_ENC-1:0]             enc_b,
    input  wire [N_ENC-1:0]             enc_z,
    input  wire                         probe_pin,
    // configuration
    input  wire [15:0]                  prescale,
    input  wire [2*N_ENC-1:0]           mode,
    input  wire [N_ENC-1:0]             z_active_high,
    input  wire [FILTER_W*N_ENC-1:0]    filter_len,
    // the three above as they will be after this clock's edge (a visit's are chosen ahead)
    input  wire [2*N_ENC-1:0]           mode_next,
    input  wire [N_ENC-1:0]             z_active_high_next,
    input  wire [FILTER_W*N_ENC-1:0]    filter_len_next,
    input  wire                         probe_active_high,
    input  wire [FILTER_W-1:0]          probe_filter_len,
    // host commands (one-cycle pulses)
    input  wire [N_ENC-1:0]             arm_index_latch,
    input  wire [N_ENC-1:0]             arm_index_clear,
    input  wire                         probe_arm,
    input  wire                         clear_errors,
    input  wire                         clear_counters,
    // register bus: the read served in this cycle (the bus stage's flip-flops)
    input  wire                         read_served,
    input  wire [6:0]                   read_addr,
    output wire [31:0]                  copy_rdata,     // the last served read's copy, else 0
    // shared state
    input  wire [31:0]                  timestamp,
    input  wire [32*N_AXES-1:0]         position,
    input  wire                         latch_now,
    // channel state (flip-flops)
    output wire [16*N_ENC-1:0]          illegal_count,
    output wire [N_ENC-1:0]             illegal,
    output wire [N_ENC-1:0]             index_seen,
    output wire [N_ENC-1:0]             index_latch_armed,
    output wire [N_ENC-1:0]             index_clear_armed,
    output wire [N_ENC-1:0]             a_level,
    output wire [N_ENC-1:0]             b_level,
    output wire [N_ENC-1:0]             z_level,        // after polarity
    // probe state
    output wire                         probe_armed,
    output wire                         probe_seen,
    output wire                         probe_active,
    output wire                         probe_event_now,   // the probe event of this clock
    output wire [31:0]                  probe_time,
    output wire [32*N_AXES-1:0]         probe_position
);

`include "finestep_regs.vh"

    localparam S      = (N_ENC < 2) ? 2 : N_ENC;
    localparam CH_W   = (S > 2) ? 2 : 1;
    localparam LIVE_W = 2 * COUNT_W + 3 * FILTER_W;   // count, edge time, three filter counters
    localparam integer    LAST      = S - 1;
    localparam [CH_W-1:0] LAST_SLOT = LAST[CH_W-1:0];
    localparam [CH_W-1:0] CH_ONE    = {{(CH_W-1){1'b0}}, 1'b1};
    // The live store written a clock after the visit, from a register of the visit's
    // result (three slots or more, the stores in distributed RAM: the ECP5 board build),
    // so the visit's decode ends at a register beside it, not at a RAM the placer may put
    // across the die (the ECP5 build's critical path at 100 MHz, seed 2: 2.65 ns of one
    // route; on also in the Cyclone IV build and the simulated chip, LIVE_W + 3 flip-flops).
    // The channel's next read comes at the edge ending the cycle before its next visit,
    // S - 1 >= 2 clocks after this one: after the write. Two slots would read it at the
    // write's own edge; block RAM (the iCE40) registers its write data anyway.
    localparam LIVE_WR_REG = (S >= 3 && RAM_BLOCK == 0 && COPY_FF == 0) ? 1 : 0;

    // ---- The read side: which copy the served read addresses --------------------------
    // The four copy arrays, one word per channel each, at bases aligned to the four
    // channels the map has room for (stride 1: both checked below), so the array is the
    // address's high bits and the channel its low two.
    localparam [1:0] KIND_COUNT = 2'd0, KIND_INDEX = 2'd1, KIND_PROBE = 2'd2, KIND_EDGE = 2'd3;
    localparam [2:0] N_CH = N_ENC[2:0];
    wire [1:0] rd_low    = read_addr[1:0];
    wire hit_count = (read_addr[6:2] == FS_ENC_COUNT_ADDR[6:2]);
    wire hit_index = (read_addr[6:2] == FS_ENC_INDEX_LATCH_ADDR[6:2]);
    wire hit_probe = (read_addr[6:2] == FS_ENC_PROBE_LATCH_ADDR[6:2]);
    wire hit_edge  = (read_addr[6:2] == FS_ENC_EDGE_TIME_ADDR[6:2]);
    wire [CH_W-1:0] rd_ch   = rd_low[CH_W-1:0];
    wire [1:0]      rd_kind = hit_count ? KIND_COUNT : hit_index ? KIND_INDEX : hit_probe ? KIND_PROBE : KIND_EDGE;
    wire            rd_copy = read_served && (hit_count || hit_index || hit_probe || hit_edge) && ({1'b0, rd_low} < N_CH);

    // ---- Schedule -----------------------------------------------------------------------
    reg  [CH_W-1:0] slot_reg;
    reg  [15:0]     presc_reg;
    reg             sampling_reg;
    wire            slot_is_channel = ({{(32-CH_W){1'b0}}, slot_reg} < N_ENC);
    wire            stall      = rd_copy && (rd_ch == slot_reg) && slot_is_channel;
    wire            visit      = slot_is_channel && !stall;
    wire            round_end  = (slot_reg == LAST_SLOT) && !stall;
    wire [CH_W-1:0] slot_next  = stall ? slot_reg : (slot_reg == LAST_SLOT) ? {CH_W{1'b0}} : slot_reg + CH_ONE;
    // The visit's datapath does not wait for the stall: only the writes do.
    wire            sample_now = sampling_reg;
    wire            probe_sample = (slot_reg == {CH_W{1'b0}}) && !stall && sampling_reg;

    always @(posedge clk) begin
        slot_reg <= slot_next;
        if (round_end) begin
            sampling_reg <= (presc_reg == 16'd0);
            presc_reg    <= (presc_reg == 16'd0) ? prescale : presc_reg - 16'd1;
        end
        if (rst) begin
            slot_reg     <= {CH_W{1'b0}};
            presc_reg    <= 16'd0;
            sampling_reg <= 1'b0;
        end
    end

    // ---- Per-channel flip-flops ---------------------------------------------------------
    reg [N_ENC-1:0] sync1_a_reg, sync1_b_reg, sync1_z_reg;   // two-flop synchronisers
`ifdef FORMAL
    reg [N_ENC-1:0] raw_a_reg, raw_b_reg, raw_z_reg;   // the synchronisers' second stage, per pin
`endif
    reg [N_ENC-1:0] primed_reg, a_reg, b_reg, z_reg;
    reg [N_ENC-1:0] illegal_reg, index_seen_reg, latch_armed_reg, clear_armed_reg;
    reg [N_ENC-1:0] latch_pending_reg, probe_pending_reg;
    reg [N_ENC-1:0] count_copied_reg, index_copied_reg, probe_copied_reg;   // copy written since reset
    reg [16*N_ENC-1:0] illegal_count_reg;

    // The visited channel's view of them (slot_reg < N_ENC at a visit).
    wire [CH_W-1:0] ch = slot_reg;
    wire [31:0]     ch_i = {{(32-CH_W){1'b0}}, ch};
    // The visited channel's flip-flops, configuration and synchronised pins are chosen a
    // clock ahead (by the next slot, into the v_*_reg below), so the visit's datapath
    // starts at flip-flops, not at multiplexers steered by the slot (the ECP5 board
    // build's critical path ran from the slot through that choice and the decoder into
    // the live store's write data). A channel's state changes only at its own visits (or
    // by the host's arm, or at reset), and the next slot is never the one visited now
    // (slot_next = slot only in a stall, which visits nothing), so the state chosen ahead
    // is the state at the visit; the configuration is taken as it will be after the edge
    // (mode_next ...), and the pins from the synchronisers' first stage, so that the
    // chosen flip-flop is the second stage of the visited pin's two-flop synchroniser.
    function [FILTER_W-1:0] filter_last;   // filter_step's last: max(len, 1) - 1
        input [FILTER_W-1:0] len;
        filter_last = (len == {FILTER_W{1'b0}}) ? {FILTER_W{1'b0}} : len - 1'b1;
    endfunction
    wire [CH_W-1:0] ahead = rst ? {CH_W{1'b0}} : slot_next;   // the slot after this edge
    wire [31:0]     nx_i = {{(32-CH_W){1'b0}}, ahead};
    wire            nx_is_channel = (nx_i < N_ENC);
    reg             v_primed_reg, v_a_reg, v_b_reg, v_z_reg, v_clear_armed_reg;
    reg             v_raw_a_reg, v_raw_b_reg, v_raw_z_reg;
    reg  [1:0]          v_mode_reg;
    reg                 v_zah_reg;
    reg  [FILTER_W-1:0] v_filter_reg;   // the visited channel's filter as filter_step's last
                                        // = max(filter_len, 1) - 1, from filter_len_next
    wire [1:0]          v_mode   = v_mode_reg;
    wire                v_zah    = v_zah_reg;
    wire [FILTER_W-1:0] v_filter = v_filter_reg;
    wire unused_config = &{1'b0, mode, filter_len};   // the visits read mode_next, filter_len_next
    wire                v_primed = v_primed_reg;

    // ---- The store: live state, read the clock before the visit -------------------------
    wire [LIVE_W-1:0] live_rd;
    wire [LIVE_W-1:0] live_wr;
`ifdef FORMAL
    // One channel's word of the live store, any channel (the proof's invariant below).
    (* anyconst *) reg [CH_W-1:0] f_peek_ch;
    wire [LIVE_W-1:0] f_peek_word;
`endif
    wire              live_w_en;     // the store's write: the visit's, or a clock later (LIVE_WR_REG)
    wire [CH_W-1:0]   live_w_addr;
    wire [LIVE_W-1:0] live_w_data;
    generate
        if (LIVE_WR_REG != 0) begin : live_wr_reg
            reg              en_reg;
            reg [CH_W-1:0]   addr_reg;
            reg [LIVE_W-1:0] data_reg;
            always @(posedge clk) begin
                en_reg   <= visit && !rst;
                addr_reg <= ch;
                data_reg <= live_wr;
            end
            assign live_w_en   = en_reg;
            assign live_w_addr = addr_reg;
            assign live_w_data = data_reg;
        end else begin : live_wr_direct
            assign live_w_en   = visit;
            assign live_w_addr = ch;
            assign live_w_data = live_wr;
        end
        if (COPY_FF == 0) begin : live_ram
            store_ram #(.WIDTH(LIVE_W), .DEPTH(S), .ADDR_W(CH_W), .BLOCK(RAM_BLOCK)) live_store (
                .clk(clk), .wr_en(live_w_en), .wr_addr(live_w_addr), .wr_data(live_w_data), .rd_en(1'b1),
                .rd_addr(slot_next), .rd_data(live_rd)
`ifdef FORMAL
                , .f_peek_addr(f_peek_ch), .f_peek_data(f_peek_word)
`endif
            );
        end else begin : live_ff
            // In flip-flops (COPY_FF) the visited word is read in the visit itself: the edge
            // before it wrote the previous slot's channel, never this one (slot_next differs
            // from slot_reg but at a stall, which writes nothing), so this is the word the
            // registered read took at that edge, without its register.
            reg [LIVE_W-1:0] live_mem [0:S-1];
            always @(posedge clk) if (live_w_en) live_mem[live_w_addr] <= live_w_data;
`ifdef FORMAL
            assign f_peek_word = live_mem[f_peek_ch];
`endif
            assign live_rd = live_mem[slot_reg];
        end
    endgenerate
    // Until its first sample a channel's live state is 0 (reset), whatever the RAM holds.
    wire [LIVE_W-1:0] live = v_primed ? live_rd : {LIVE_W{1'b0}};
    wire [COUNT_W-1:0]  v_count = live[0 +: COUNT_W];
    wire [COUNT_W-1:0]  v_edge  = live[COUNT_W +: COUNT_W];
    wire [FILTER_W-1:0] v_cnt_a = live[2*COUNT_W +: FILTER_W];
    wire [FILTER_W-1:0] v_cnt_b = live[2*COUNT_W + FILTER_W +: FILTER_W];
    wire [FILTER_W-1:0] v_cnt_z = live[2*COUNT_W + 2*FILTER_W +: FILTER_W];

    wire                n_primed, n_a, n_b, n_z, illegal_event, index_event;
    wire [FILTER_W-1:0] n_cnt_a, n_cnt_b, n_cnt_z;
    wire [COUNT_W-1:0]  n_count, n_edge;
    quadrature_channel #(.FILTER_W(FILTER_W), .COUNT_W(COUNT_W)) decoder (
        .mode(v_mode), .z_active_high(v_zah), .filter_last(v_filter),
        .sampling(sample_now), .raw_a(v_raw_a_reg), .raw_b(v_raw_b_reg),
        .raw_z(v_raw_z_reg), .timestamp(timestamp),
        .primed(v_primed), .a(v_a_reg), .b(v_b_reg), .z_level(v_z_reg),
        .cnt_a(v_cnt_a), .cnt_b(v_cnt_b), .cnt_z(v_cnt_z),
        .count(v_count), .edge_time(v_edge), .clear_armed(v_clear_armed_reg),
        .primed_next(n_primed), .a_next(n_a), .b_next(n_b), .z_level_next(n_z),
        .cnt_a_next(n_cnt_a), .cnt_b_next(n_cnt_b), .cnt_z_next(n_cnt_z),
        .count_next(n_count), .edge_time_next(n_edge),
        .illegal_event(illegal_event), .index_event(index_event)
    );

    assign live_wr = {n_cnt_z, n_cnt_b, n_cnt_a, n_edge, n_count};

    // ---- The copies ---------------------------------------------------------------------
    // Probe: filtered at the first visit of each sampling round, rising edge while armed.
    wire probe_level, probe_primed;
    input_filter #(.FILTER_W(FILTER_W)) probe_filter (
        .clk(clk), .rst(rst), .filter_len(probe_filter_len), .sample(probe_sample), .pin(probe_pin),
        .level(probe_level), .primed(probe_primed)
    );
    reg                  probe_live_reg;
    reg                  probe_active_prev_reg;
    reg                  probe_armed_reg;
    reg                  probe_seen_reg;
    reg [31:0]           probe_time_reg;
    reg [32*N_AXES-1:0]  probe_position_reg;
    wire active      = probe_active_high ? probe_level : !probe_level;
    wire probe_event = probe_live_reg && active && !probe_active_prev_reg && probe_armed_reg;

    wire copy_latch = visit && (latch_pending_reg[ch_i] || latch_now);
    wire copy_probe = visit && (probe_pending_reg[ch_i] || probe_event);
    wire copy_index = visit && index_event && latch_armed_reg[ch_i];

    wire [COUNT_W-1:0] count_rd, edge_rd, index_rd, probe_rd;
    generate
        if (COPY_FF == 0) begin : copy_stores
            store_ram #(.WIDTH(COUNT_W), .DEPTH(S), .ADDR_W(CH_W), .BLOCK(RAM_BLOCK)) count_store (
                .clk(clk), .wr_en(copy_latch), .wr_addr(ch), .wr_data(v_count), .rd_en(rd_copy), .rd_addr(rd_ch), .rd_data(count_rd)
            );
            store_ram #(.WIDTH(COUNT_W), .DEPTH(S), .ADDR_W(CH_W), .BLOCK(RAM_BLOCK)) edge_store (
                .clk(clk), .wr_en(copy_latch), .wr_addr(ch), .wr_data(v_edge), .rd_en(rd_copy), .rd_addr(rd_ch), .rd_data(edge_rd)
            );
            store_ram #(.WIDTH(COUNT_W), .DEPTH(S), .ADDR_W(CH_W), .BLOCK(RAM_BLOCK)) index_store (
                .clk(clk), .wr_en(copy_index), .wr_addr(ch), .wr_data(v_count), .rd_en(rd_copy), .rd_addr(rd_ch), .rd_data(index_rd)
            );
            store_ram #(.WIDTH(COUNT_W), .DEPTH(S), .ADDR_W(CH_W), .BLOCK(RAM_BLOCK)) probe_store (
                .clk(clk), .wr_en(copy_probe), .wr_addr(ch), .wr_data(v_count), .rd_en(rd_copy), .rd_addr(rd_ch), .rd_data(probe_rd)
            );
        end else begin : copy_ff
            // A part without RAM (COPY_FF): the four arrays are flip-flops, and a read takes
            // the addressed word of the addressed array into one register at the edge
            // ending its serving cycle (where each store_ram would take its own), so the
            // shown word is the same from one register instead of four. The stall keeps
            // the word read from being written at that edge, as for the stores.
            reg [COUNT_W-1:0] count_mem [0:S-1];
            reg [COUNT_W-1:0] edge_mem  [0:S-1];
            reg [COUNT_W-1:0] index_mem [0:S-1];
            reg [COUNT_W-1:0] probe_mem [0:S-1];
            reg [COUNT_W-1:0] copy_rd_reg;
            always @(posedge clk) begin
                if (copy_latch) begin
                    count_mem[ch] <= v_count;
                    edge_mem[ch]  <= v_edge;
                end
                if (copy_index) index_mem[ch] <= v_count;
                if (copy_probe) probe_mem[ch] <= v_count;
                if (rd_copy)
                    copy_rd_reg <= (rd_kind == KIND_COUNT) ? count_mem[rd_ch] :
                                   (rd_kind == KIND_INDEX) ? index_mem[rd_ch] :
                                   (rd_kind == KIND_PROBE) ? probe_mem[rd_ch] : edge_mem[rd_ch];
            end
            // served_kind_reg picks among the four below: all four are the one register.
            assign count_rd = copy_rd_reg;
            assign edge_rd  = copy_rd_reg;
            assign index_rd = copy_rd_reg;
            assign probe_rd = copy_rd_reg;
        end
    endgenerate
    // What the last served read shows, from the cycle after its serving cycle until the
    // next served read: the addressed copy, 0 before its first write (and 0 after a read
    // of anything else).
    reg        served_reg;
    reg [1:0]  served_kind_reg;
    reg        served_written_reg;
    wire written = (rd_kind == KIND_INDEX) ? index_copied_reg[rd_ch] :
                   (rd_kind == KIND_PROBE) ? probe_copied_reg[rd_ch] : count_copied_reg[rd_ch];
    always @(posedge clk) begin
        if (read_served) begin
            served_reg         <= rd_copy;
            served_kind_reg    <= rd_kind;
            // A copy written at this edge cannot be the read one (the stall), so the flag
            // of this cycle is the flag of the serving cycle for the addressed word.
            served_written_reg <= written;
        end
        if (rst) served_reg <= 1'b0;
    end
    wire [COUNT_W-1:0] copy_word = (served_kind_reg == KIND_COUNT) ? count_rd :
                                   (served_kind_reg == KIND_INDEX) ? index_rd :
                                   (served_kind_reg == KIND_PROBE) ? probe_rd : edge_rd;
    // Narrow words (COUNT_W < 32) read extended: the counts (ENC_COUNT, ENC_INDEX_LATCH,
    // ENC_PROBE_LATCH) sign-extended, the edge time (TIMESTAMP's low bits) zero-extended.
    wire [31:0] copy_word32;
    generate
        if (COUNT_W < 32) begin : extend
            wire fill = copy_word[COUNT_W-1] && (served_kind_reg != KIND_EDGE);
            assign copy_word32 = {{(32-COUNT_W){fill}}, copy_word};
        end else begin : full
            assign copy_word32 = copy_word;
        end
    endgenerate
    assign copy_rdata = !(served_reg && served_written_reg) ? 32'd0 : copy_word32;

    // ---- Flip-flop state updates ----------------------------------------------------------
    wire [15:0] v_illegal_count = illegal_count_reg[16*ch_i +: 16];
    integer c;
    always @(posedge clk) begin
        for (c = 0; c < N_ENC; c = c + 1) begin
            if (visit && ch_i == c) begin
                primed_reg[c] <= n_primed;
                a_reg[c]      <= n_a;
                b_reg[c]      <= n_b;
                z_reg[c]      <= n_z;
            end
            // Sticky flags and counters: visits set, host pulses clear (a set wins, a
            // clear of the counter wins).
            if (visit && ch_i == c && illegal_event) illegal_reg[c] <= 1'b1;
            else if (clear_errors) illegal_reg[c] <= 1'b0;
            if (clear_counters) illegal_count_reg[16*c +: 16] <= 16'd0;
            else if (visit && ch_i == c && illegal_event && v_illegal_count != 16'hFFFF)
                illegal_count_reg[16*c +: 16] <= v_illegal_count + 16'd1;
            // Index arms: an arm in the cycle of an event wins.
            if (arm_index_latch[c]) index_seen_reg[c] <= 1'b0;
            else if (copy_index && ch_i == c) index_seen_reg[c] <= 1'b1;
            if (arm_index_latch[c]) latch_armed_reg[c] <= 1'b1;
            else if (visit && ch_i == c && index_event) latch_armed_reg[c] <= 1'b0;
            if (arm_index_clear[c]) clear_armed_reg[c] <= 1'b1;
            else if (visit && ch_i == c && index_event) clear_armed_reg[c] <= 1'b0;
            // Copies asked for wait for the channel's visit.
            if (visit && ch_i == c) latch_pending_reg[c] <= 1'b0;
            else if (latch_now) latch_pending_reg[c] <= 1'b1;
            if (visit && ch_i == c) probe_pending_reg[c] <= 1'b0;
            else if (probe_event) probe_pending_reg[c] <= 1'b1;
            if (copy_latch && ch_i == c) count_copied_reg[c] <= 1'b1;
            if (copy_index && ch_i == c) index_copied_reg[c] <= 1'b1;
            if (copy_probe && ch_i == c) probe_copied_reg[c] <= 1'b1;
        end
        sync1_a_reg <= enc_a;
        sync1_b_reg <= enc_b;
        sync1_z_reg <= enc_z;
        // The next slot's channel, as its flip-flops will be at the next edge (see above).
        if (nx_is_channel) begin
            v_primed_reg      <= primed_reg[nx_i];
            v_a_reg           <= a_reg[nx_i];
            v_b_reg           <= b_reg[nx_i];
            v_z_reg           <= z_reg[nx_i];
            v_clear_armed_reg <= arm_index_clear[nx_i] || clear_armed_reg[nx_i];
            v_raw_a_reg       <= sync1_a_reg[nx_i];
            v_raw_b_reg       <= sync1_b_reg[nx_i];
            v_raw_z_reg       <= sync1_z_reg[nx_i];
            v_mode_reg        <= mode_next[2*nx_i +: 2];
            v_zah_reg         <= z_active_high_next[nx_i];
            v_filter_reg      <= filter_last(filter_len_next[FILTER_W*nx_i +: FILTER_W]);
        end
`ifdef FORMAL
        raw_a_reg   <= sync1_a_reg;
        raw_b_reg   <= sync1_b_reg;
        raw_z_reg   <= sync1_z_reg;
`endif
        if (rst) begin
            sync1_a_reg       <= {N_ENC{1'b0}};
            sync1_b_reg       <= {N_ENC{1'b0}};
            sync1_z_reg       <= {N_ENC{1'b0}};
`ifdef FORMAL
            raw_a_reg         <= {N_ENC{1'b0}};
            raw_b_reg         <= {N_ENC{1'b0}};
            raw_z_reg         <= {N_ENC{1'b0}};
`endif
            illegal_count_reg <= {16*N_ENC{1'b0}};
            primed_reg        <= {N_ENC{1'b0}};
            a_reg             <= {N_ENC{1'b0}};
            b_reg             <= {N_ENC{1'b0}};
            z_reg             <= {N_ENC{1'b0}};
            illegal_reg       <= {N_ENC{1'b0}};
            index_seen_reg    <= {N_ENC{1'b0}};
            latch_armed_reg   <= {N_ENC{1'b0}};
            clear_armed_reg   <= {N_ENC{1'b0}};
            latch_pending_reg <= {N_ENC{1'b0}};
            probe_pending_reg <= {N_ENC{1'b0}};
            count_copied_reg  <= {N_ENC{1'b0}};
            index_copied_reg  <= {N_ENC{1'b0}};
            probe_copied_reg  <= {N_ENC{1'b0}};
            v_primed_reg      <= 1'b0;
            v_a_reg           <= 1'b0;
            v_b_reg           <= 1'b0;
            v_z_reg           <= 1'b0;
            v_clear_armed_reg <= 1'b0;
            v_raw_a_reg       <= 1'b0;
            v_raw_b_reg       <= 1'b0;
            v_raw_z_reg       <= 1'b0;
        end
    end

    // Probe state (per clock).
    always @(posedge clk) begin
        probe_live_reg        <= probe_primed;
        probe_active_prev_reg <= active;
        // An arm written in the cycle of an event wins.
        if (probe_arm) begin
            probe_armed_reg <= 1'b1;
            probe_seen_reg  <= 1'b0;
        end else if (probe_event) begin
            probe_armed_reg <= 1'b0;
            probe_seen_reg  <= 1'b1;
        end
        if (rst) begin
            probe_live_reg        <= 1'b0;
            probe_active_prev_reg <= 1'b0;
            probe_armed_reg       <= 1'b0;
            probe_seen_reg        <= 1'b0;
        end
    end

    // The probe's snapshot (TIMESTAMP and every position of the event's clock), unless the
    // register file's position latch takes it (PROBE_COPY 0: the outputs are 0).
    generate
        if (PROBE_COPY != 0) begin : probe_copy
            always @(posedge clk) begin
                if (rst) begin
                    probe_time_reg     <= 32'd0;
                    probe_position_reg <= {32*N_AXES{1'b0}};
                end else if (probe_event) begin
                    probe_time_reg     <= timestamp;
                    probe_position_reg <= position;
                end
            end
        end else begin : no_probe_copy
            wire unused_position = &{1'b0, position};
            always @(*) begin
                probe_time_reg     = 32'd0;
                probe_position_reg = {32*N_AXES{1'b0}};
            end
        end
    endgenerate

    genvar g;
    generate
        for (g = 0; g < N_ENC; g = g + 1) begin : view
            assign z_level[g] = z_reg[g] ^ !z_active_high[g];
        end
        // The copy decode takes an array from the address's high bits, a channel from its low two.
        if (FS_ENC_COUNT_STRIDE != 1 || FS_ENC_INDEX_LATCH_STRIDE != 1 || FS_ENC_PROBE_LATCH_STRIDE != 1 ||
            FS_ENC_EDGE_TIME_STRIDE != 1 || FS_ENC_COUNT_ADDR[1:0] != 2'd0 || FS_ENC_INDEX_LATCH_ADDR[1:0] != 2'd0 ||
            FS_ENC_PROBE_LATCH_ADDR[1:0] != 2'd0 || FS_ENC_EDGE_TIME_ADDR[1:0] != 2'd0 || N_ENC > 4) begin : stride_check
            encoder_bank_copy_arrays_need_stride_1 unsupported_register_map ();
        end
        // A narrow count still tells the direction of a move between two reads (2^(COUNT_W-1)
        // counts) and fits the 32-bit register.
        if (COUNT_W < 2 || COUNT_W > 32) begin : width_check
            encoder_bank_COUNT_W_must_be_2_to_32 unsupported_count_width ();
        end
    endgenerate

    assign illegal_count     = illegal_count_reg;
    assign illegal           = illegal_reg;
    assign index_seen        = index_seen_reg;
    assign index_latch_armed = latch_armed_reg;
    assign index_clear_armed = clear_armed_reg;
    assign a_level           = a_reg;
    assign b_level           = b_reg;
    assign probe_armed       = probe_armed_reg;
    assign probe_seen        = probe_seen_reg;
    assign probe_active      = active;
    assign probe_event_now   = probe_event;
    assign probe_time        = probe_time_reg;
    assign probe_position    = probe_position_reg;

`ifdef FORMAL
    // The engine against one state per channel: a shadow count and edge time per channel,
    // updated at the channel's visits from the decoder's result, must be what the store
    // hands the next visit of that channel (so the store neither loses nor mixes a
    // channel's count); the stores never read and write one word on one clock (what
    // store_ram's no_rw_check relies on); the schedule moves one slot per clock unless
    // stalled. The register bus never serves reads in three cycles in a row (each master
    // has one request at a time and spaces its reads).
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid) assume (!(read_served && $past(read_served) && $past(read_served, 2)));
    always @(posedge clk) if (f_past_valid) assume ($stable(mode) && $stable(filter_len) && $stable(z_active_high));
    // The configuration's next value is its value (held still above; feedback_registers
    // makes the registers load exactly their next value).
    always @(*) assume (mode_next == mode && filter_len_next == filter_len && z_active_high_next == z_active_high);

    reg [COUNT_W-1:0] f_count [0:N_ENC-1];
    reg [COUNT_W-1:0] f_edge  [0:N_ENC-1];
    integer f;
    always @(posedge clk) begin
        for (f = 0; f < N_ENC; f = f + 1) begin
            if (visit && ch_i == f) begin
                f_count[f] <= n_count;
                f_edge[f]  <= n_edge;
            end
            if (rst) begin
                f_count[f] <= {COUNT_W{1'b0}};
                f_edge[f]  <= {COUNT_W{1'b0}};
            end
        end
    end
    always @(*) if (f_past_valid && !rst) begin
        // No read-during-write on any store.
        if (visit) assert (slot_next != ch);
        if (live_w_en) assert (slot_next != live_w_addr);
        if (rd_copy && (copy_latch || copy_index || copy_probe)) assert (rd_ch != ch);
        assert ({{(32-CH_W){1'b0}}, slot_reg} < S);
        // Before its first sample a channel has count 0 and nothing decoded.
        // (With LIVE_WR_REG stated for the channel the invariant below peeks at: any one, so
        // every one.)
        if (visit && !v_primed && (LIVE_WR_REG == 0 || ch == f_peek_ch))
            assert (f_count[ch_i] == {COUNT_W{1'b0}} && f_edge[ch_i] == {COUNT_W{1'b0}});
        if (visit && (LIVE_WR_REG == 0 || ch == f_peek_ch)) assert (v_count == f_count[ch_i] && v_edge == f_edge[ch_i]);
        // With the write a clock late (LIVE_WR_REG), the invariant that carries the shadow
        // from a visit to the channel's next one, for any channel p: a sampled channel's
        // word is in the write register while its write is pending, else in the store; and
        // the read register holds the store's word of the slot it serves.
        if (LIVE_WR_REG != 0 && {{(32-CH_W){1'b0}}, f_peek_ch} < N_ENC && !primed_reg[f_peek_ch])
            assert (f_count[f_peek_ch] == {COUNT_W{1'b0}} && f_edge[f_peek_ch] == {COUNT_W{1'b0}});
        if (LIVE_WR_REG != 0 && {{(32-CH_W){1'b0}}, f_peek_ch} < N_ENC && primed_reg[f_peek_ch]) begin
            if (live_w_en && live_w_addr == f_peek_ch)
                assert (live_w_data[0 +: COUNT_W] == f_count[f_peek_ch] &&
                        live_w_data[COUNT_W +: COUNT_W] == f_edge[f_peek_ch]);
            else
                assert (f_peek_word[0 +: COUNT_W] == f_count[f_peek_ch] &&
                        f_peek_word[COUNT_W +: COUNT_W] == f_edge[f_peek_ch]);
            if (slot_reg == f_peek_ch) assert (live_rd == f_peek_word);
        end
        // The visit's flip-flops, chosen a clock ahead, are the visited channel's.
        if (slot_is_channel) assert (v_primed_reg == primed_reg[ch_i] && v_a_reg == a_reg[ch_i] &&
                                     v_b_reg == b_reg[ch_i] && v_z_reg == z_reg[ch_i] &&
                                     v_clear_armed_reg == clear_armed_reg[ch_i] &&
                                     v_raw_a_reg == raw_a_reg[ch_i] && v_raw_b_reg == raw_b_reg[ch_i] &&
                                     v_raw_z_reg == raw_z_reg[ch_i] && v_mode_reg == mode[2*ch_i +: 2] &&
                                     v_zah_reg == z_active_high[ch_i] &&
                                     v_filter_reg == filter_last(filter_len[FILTER_W*ch_i +: FILTER_W]));
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(stall)) assert (slot_reg == $past(slot_reg));
        else assert (slot_reg == (($past(slot_reg) == LAST_SLOT) ? {CH_W{1'b0}} : $past(slot_reg) + CH_ONE));
        if ($past(round_end)) assert (sampling_reg == ($past(presc_reg) == 16'd0) &&
                                      presc_reg == (($past(presc_reg) == 16'd0) ? $past(prescale) : $past(presc_reg) - 16'd1));
        else assert (sampling_reg == $past(sampling_reg) && presc_reg == $past(presc_reg));
        // A copy asked for is taken at the channel's next visit: pending until then.
        if ($past(latch_now) && !($past(visit) && $past(ch_i) == 0)) assert (latch_pending_reg[0]);
        if ($past(probe_event)) assert (!probe_armed_reg || $past(probe_arm));
        // The probe's time and positions are those of the event's cycle, held until the next.
        if (PROBE_COPY == 0) assert (probe_time == 32'd0 && probe_position == {32*N_AXES{1'b0}});
        else if ($past(probe_event)) assert (probe_time == $past(timestamp) && probe_position == $past(position));
        else assert (probe_time == $past(probe_time) && probe_position == $past(probe_position));
        cover ($past(copy_latch) && $past(v_count) != {COUNT_W{1'b0}});
        cover ($past(stall));
        cover ($past(copy_probe) && $past(v_count) != {COUNT_W{1'b0}});
    end

    // LIVE_WR_REG: a sampled channel's moved count pending in the write register, and a
    // moved count read back from the store at a visit of the channel the invariant peeks at.
    generate
        if (LIVE_WR_REG != 0) begin : f_wr_reg_cover
            always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
                cover (live_w_en && primed_reg[live_w_addr] && live_w_data[0 +: COUNT_W] != {COUNT_W{1'b0}});
                cover (visit && v_primed && v_count != {COUNT_W{1'b0}} && ch == f_peek_ch);
            end
        end
    endgenerate

`ifdef FORMAL_READBACK
    // What a copy read returns, stated from the spec's rules: a shadow of each copy
    // (ENC_COUNT and ENC_EDGE_TIME taken at the channel's visit at or after a position
    // latch, ENC_INDEX_LATCH at an index event while the latch is armed, ENC_PROBE_LATCH
    // at the visit at or after a probe event; all from the values before the visit's
    // update, the shadow f_count / f_edge) and whether it has been written since reset;
    // the read served in one cycle shows, from the next until the next served read, the
    // addressed copy as of its serving cycle (0 before its first write), and a read of
    // anything else shows 0. The stores are RAMs whose words the
    // induction cannot see, so this is a bounded check from reset (task readback): the
    // free timestamp reaches every bit of an edge time within its depth.
    reg [COUNT_W*N_ENC-1:0] f_lat_count, f_lat_edge, f_idx_count, f_prb_count;
    reg [N_ENC-1:0]    f_lat_w, f_idx_w, f_prb_w;
    integer fg;
    always @(posedge clk) begin
        for (fg = 0; fg < N_ENC; fg = fg + 1) begin
            if (visit && ch_i == fg) begin
                if (latch_pending_reg[fg] || latch_now) begin
                    f_lat_count[COUNT_W*fg +: COUNT_W] <= f_count[fg];
                    f_lat_edge[COUNT_W*fg +: COUNT_W]  <= f_edge[fg];
                    f_lat_w[fg]              <= 1'b1;
                end
                if (index_event && latch_armed_reg[fg]) begin
                    f_idx_count[COUNT_W*fg +: COUNT_W] <= f_count[fg];
                    f_idx_w[fg]              <= 1'b1;
                end
                if (probe_pending_reg[fg] || probe_event) begin
                    f_prb_count[COUNT_W*fg +: COUNT_W] <= f_count[fg];
                    f_prb_w[fg]              <= 1'b1;
                end
            end
        end
        if (rst) begin
            f_lat_w <= {N_ENC{1'b0}};
            f_idx_w <= {N_ENC{1'b0}};
            f_prb_w <= {N_ENC{1'b0}};
        end
    end
    // The read served in this cycle, decoded here from the map's addresses; what it must
    // show from the next cycle until the next served read.
    wire [4:0]  f_base  = read_addr[6:2];
    wire [31:0] f_ch    = {30'd0, read_addr[1:0]};
    wire        f_in    = f_ch < N_ENC;
    // A narrow count reads sign-extended, a narrow edge time zero-extended (stated here
    // by value: the copy as a signed or an unsigned number of COUNT_W bits).
    reg  [31:0] f_now, f_want;
    reg  [COUNT_W-1:0] f_word;
    reg         f_signed;
    integer     fb;
    always @(*) begin
        f_now = 32'd0;
        f_word = {COUNT_W{1'b0}};
        f_signed = 1'b1;
        if (f_in) begin
            if (f_base == FS_ENC_COUNT_ADDR[6:2] && f_lat_w[f_ch])
                f_word = f_lat_count[COUNT_W*f_ch +: COUNT_W];
            if (f_base == FS_ENC_EDGE_TIME_ADDR[6:2] && f_lat_w[f_ch]) begin
                f_word   = f_lat_edge[COUNT_W*f_ch +: COUNT_W];
                f_signed = 1'b0;
            end
            if (f_base == FS_ENC_INDEX_LATCH_ADDR[6:2] && f_idx_w[f_ch])
                f_word = f_idx_count[COUNT_W*f_ch +: COUNT_W];
            if (f_base == FS_ENC_PROBE_LATCH_ADDR[6:2] && f_prb_w[f_ch])
                f_word = f_prb_count[COUNT_W*f_ch +: COUNT_W];
        end
        for (fb = 0; fb < 32; fb = fb + 1)
            f_now[fb] = (fb < COUNT_W) ? f_word[fb] : (f_signed && f_word[COUNT_W-1]);
    end
    localparam F_HIGH_BIT = (COUNT_W >= 30) ? 29 : COUNT_W - 1;   // a high edge-time bit to cover
    always @(posedge clk) begin
        if (read_served) f_want <= f_now;
        if (rst) f_want <= 32'd0;
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (copy_rdata == f_want);
        cover ($past(read_served) && $past(f_base) == FS_ENC_EDGE_TIME_ADDR[6:2] && f_want[F_HIGH_BIT]);
    end
`endif
`endif

endmodule

`default_nettype wire
