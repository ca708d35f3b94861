`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/register_file.md
// Register file: the host-visible registers of hdl/registers.toml (addresses and field
// positions come from the generated finestep_regs.vh), the register-bus arbiter for the
// two host links (SPI first), error counters, the interrupt, the per-period position
// latch and the RECORD_PUSH path into the position FIFO. The feedback blocks' registers
// live in feedback_registers on the same arbitrated bus; their read value, taken by
// finestep_top at the edge ending the serving cycle, comes in with `late_rdata`, or with
// FEEDBACK_REG 0 (the CPLDs: 32 flip-flops fewer) as `early_rdata` into the read register.
//
// Latency: a request granted in cycle n is registered at the edge ending n (the bus
// stage) and served in n+1: a write takes effect at the edge ending n+1 (its command
// pulses, push and watchdog kick are high in n+2); a read returns rdata in n+2, computed
// from the state of cycle n+1. Neither the grant nor the masters' multiplexer sits in
// front of the read multiplexer or the write decode. The encoder bank's copies are read
// from its store at the edge ending n+1 (addressed by the bus stage, so no grant decode
// reaches its schedule) and come in as `late_rdata` in n+2, ORed after rdata's register;
// so do the feedback blocks' words (finestep_top's register of them, loaded at the same
// edge from the same stage), so their multiplexers end at a register of their own.
module register_file #(
    parameter N_AXES          = 4,
    parameter P_WIDTH         = 20,
    parameter TIMING_W        = 12,
    parameter FIFO_DEPTH_LOG2 = 8,
    parameter WD_W            = 24,
    parameter CLOCK_HZ        = 50000000,
    parameter HAS_SPI         = 1,
    parameter HAS_PARALLEL    = 1,
    parameter N_ENC           = 4,
    parameter HAS_MPG         = 1,
    parameter READ_STORE      = 1,    // 1: the per-axis arrays read back from a store (RAM)
    parameter RAM_BLOCK       = 0,    // 1: that store in block RAM
    parameter STEP_ROUND_LOG2 = 0,    // CAPS.STEP_ROUND_LOG2: log2 of the step engine's round (0: none)
    parameter ONE_SNAPSHOT    = 0,    // 1: the position latch is the probe's snapshot too (PROBE_POSITION,
                                      // PROBE_TIME read POSITION, LATCH_TIME)
    parameter INC_WRITE_ONLY  = 0,    // 1: RECORD_INC reads 0 (with READ_STORE 0: no multiplexer inputs)
    parameter AXIS_WRITE_ONLY = 0,    // 1: AXIS_TIMING_A/B, AXIS_MODE read 0 (the same, with READ_STORE 0)
    parameter INC_DIRECT      = 0,    // 1: a RECORD_INC write goes straight into the FIFO's record being
                                      // written, no copy here and no push sequence (needs INC_WRITE_ONLY 1)
    parameter ENC_COUNT_W     = 32,   // the encoder bank's words (VERSION.ENC_COUNT_16 when 16)
    parameter TIMING_ROUND_L  = 0     // L > 0 (write-only timings, the digit-serial engine of round
                                      // 2^L): each timing X held as the engine reads it, X's bits
                                      // from L up and bit 0 = (X mod 2^L != 0), bits 1 .. L-1 0
) (
    // clock, reset
    input  wire                         clk,
    input  wire                         rst,
    // register bus: SPI master
    input  wire                         spi_req,
    input  wire                         spi_we,
    input  wire [6:0]                   spi_addr,
    input  wire [31:0]                  spi_wdata,
    output wire                         spi_grant,
    // register bus: parallel master
    input  wire                         par_req,
    input  wire                         par_we,
    input  wire [6:0]                   par_addr,
    input  wire [31:0]                  par_wdata,
    output wire                         par_grant,
    output wire [31:0]                  rdata,
    // the arbitrated bus, for feedback_registers
    output wire                         bus_write,
    output wire [6:0]                   bus_address,
    output wire [31:0]                  bus_write_data,
    output wire                         bus_read,       // a read served in this cycle (at bus_address)
    input  wire [31:0]                  late_rdata,     // a served read's word from the cycle after, held
    input  wire [31:0]                  early_rdata,    // a served read's word from its serving cycle (0: none)
    // configuration out
    output wire                         run,
    output wire                         watchdog_enable,
    output wire                         estop_active_high,
    output wire [P_WIDTH-1:0]           period_clocks,
    output wire [WD_W-1:0]              watchdog_timeout,
    output wire [7:0]                   estop_filter,
    output wire [15:0]                  start_level,
    output wire [N_AXES-1:0]            axis_enable,
    output wire [TIMING_W*N_AXES-1:0]   step_len,
    output wire [TIMING_W*N_AXES-1:0]   step_space,
    output wire [TIMING_W*N_AXES-1:0]   dir_setup,
    output wire [TIMING_W*N_AXES-1:0]   dir_hold,
    output wire [2*N_AXES-1:0]          out_mode,
    output wire [3*N_AXES-1:0]          invert,
    // command pulses and the watchdog kick
    output wire                         clear_errors,
    output wire                         clear_faults,
    output wire                         clear_counters,
    output wire                         run_write_one,   // a write of CONTROL with RUN = 1 is served
    output wire                         flush_cmd,
    output wire                         kick,
    // machine state in
    input  wire                         core_run,
    input  wire                         gate,
    input  wire                         halt,
    input  wire                         fault_estop,
    input  wire                         fault_watchdog,
    input  wire                         estop_active,
    input  wire                         underrun,
    input  wire                         underrun_event,
    input  wire                         record_error,
    input  wire [N_AXES-1:0]            rate_error,
    input  wire [N_AXES-1:0]            step_lost,
    input  wire                         boundary,
    input  wire                         block_end,
    input  wire [32*N_AXES-1:0]         position,
    input  wire [FIFO_DEPTH_LOG2:0]     fifo_level,
    input  wire [FIFO_DEPTH_LOG2:0]     fifo_staged,
    input  wire                         fifo_full,
    // SPI frame layer events and FIFO port use
    input  wire                         latch_hold,
    // the probe (ONE_SNAPSHOT): its event in this clock, PROBE_STATUS.SEEN
    input  wire                         probe_event,
    input  wire                         probe_seen,
    input  wire                         spi_crc_error,
    input  wire                         spi_frame_error,
    input  wire                         spi_refused,
    input  wire [7:0]                   spi_refused_count,
    input  wire                         spi_fifo_in_use,
    input  wire                         spi_fifo_commit,
    input  wire                         par_error,
    // feedback state
    input  wire                         feedback_error,
    input  wire                         jog_engaged,
    input  wire                         jog_refused,
    output wire [31:0]                  timestamp,
    output wire                         latch_now,
    // RECORD_PUSH into the FIFO: its record's lanes written one a cycle (RECORD_INC[k]
    // from the store in lane k, then the flags with wr_en), committed in the next cycle
    input  wire                         fifo_flush,
    output wire [N_AXES:0]              push_lane,
    output wire [31:0]                  push_word,      // every increment lane's data
    output wire [7:0]                   push_flags,     // the flags lane's
    output wire                         push_wr_en,
    output wire                         push_commit,
    output wire                         push_in_flight, // a push writes the FIFO's record now
    // out
    output wire [7:0]                   status_byte,
    output wire                         irq
);

`include "finestep_regs.vh"
`include "finestep_interface.vh"

    localparam FIFO_DEPTH = 1 << FIFO_DEPTH_LOG2;
    localparam WORD_W     = 32;                                  // every register
    localparam ADDR_W     = FS_ADDR_WIDTH;
    localparam INC_W      = FS_REC_INC_WIDTH;                    // RECORD_INC, one axis
    localparam POS_W      = FS_POSITION_STEPS_WIDTH;             // POSITION, one axis
    localparam WATERMARK_W = FS_FIFO_WATERMARK_WATERMARK_WIDTH;
    localparam START_W    = FS_START_LEVEL_LEVEL_WIDTH;
    localparam FILTER_W   = FS_ESTOP_FILTER_SAMPLES_WIDTH;
    localparam COUNT_W    = FS_UNDERRUN_COUNT_COUNT_WIDTH;       // every error counter
    localparam LEVEL_W    = FS_FIFO_LEVEL_LEVEL_WIDTH;
    localparam IRQ_W = FS_IRQ_MASK_MASK_WIDTH;
    // VERSION: the map's version and, in bits CAPS has no room for, the register
    // behaviours a build changes to save logic (default: none)
    localparam [31:0] VERSION_WORD = (FS_MAP_VERSION_MAJOR << FS_VERSION_MAJOR_LSB) |
                                     (FS_MAP_VERSION_MINOR << FS_VERSION_MINOR_LSB) |
                                     (FS_MAP_VERSION_PATCH << FS_VERSION_PATCH_LSB) |
                                     ((ONE_SNAPSHOT != 0 ? 1 : 0) << FS_VERSION_ONE_SNAPSHOT_LSB) |
                                     ((INC_WRITE_ONLY != 0 ? 1 : 0) << FS_VERSION_INC_WRITE_ONLY_LSB) |
                                     ((AXIS_WRITE_ONLY != 0 ? 1 : 0) << FS_VERSION_AXIS_WRITE_ONLY_LSB) |
                                     ((INC_DIRECT != 0 ? 1 : 0) << FS_VERSION_INC_DIRECT_LSB) |
                                     ((ENC_COUNT_W == 16 ? 1 : 0) << FS_VERSION_ENC_COUNT_16_LSB);
    localparam [31:0] CAPS_WORD = (N_AXES << FS_CAPS_N_AXES_LSB) |
                                  (N_ENC << FS_CAPS_N_ENC_LSB) |
                                  ((HAS_MPG != 0 ? 1 : 0) << FS_CAPS_HAS_MPG_LSB) |
                                  (FIFO_DEPTH_LOG2 << FS_CAPS_FIFO_DEPTH_LOG2_LSB) |
                                  (P_WIDTH << FS_CAPS_P_WIDTH_LSB) |
                                  (TIMING_W << FS_CAPS_TIMING_W_LSB) |
                                  ((HAS_SPI != 0 ? 1 : 0) << FS_CAPS_HAS_SPI_LSB) |
                                  ((HAS_PARALLEL != 0 ? 1 : 0) << FS_CAPS_HAS_PARALLEL_LSB) |
                                  (STEP_ROUND_LOG2 << FS_CAPS_STEP_ROUND_LOG2_LSB);

    // Host registers
    reg                        run_reg;
    reg                        watchdog_enable_reg;
    reg                        estop_active_high_reg;
    reg [P_WIDTH-1:0]          period_reg;
    reg [WD_W-1:0]             watchdog_timeout_reg;
    reg [FILTER_W-1:0]         estop_filter_reg;
    reg [WATERMARK_W-1:0]      watermark_reg;
    reg [START_W-1:0]          start_level_reg;
    reg [IRQ_W-1:0]            irq_mask_reg;
    reg [N_AXES-1:0]           axis_enable_reg;
    reg [TIMING_W*N_AXES-1:0]  step_len_reg;
    reg [TIMING_W*N_AXES-1:0]  step_space_reg;
    reg [TIMING_W*N_AXES-1:0]  dir_setup_reg;
    reg [TIMING_W*N_AXES-1:0]  dir_hold_reg;
    // The timings as held (TIMING_ROUND_L): the digit-serial engine compares a counter of
    // rounds with X >> L and X mod 2^L != 0 only (docs/spec/step_serial.md), so with
    // write-only timings nothing else of X is ever seen: bits 1 .. L-1 are not kept.
    localparam [TIMING_W-1:0] ROUND_LOW = (1 << TIMING_ROUND_L) - 1;
    function [TIMING_W-1:0] held_timing;
        input [TIMING_W-1:0] x;
        begin
            held_timing = (x & ~ROUND_LOW) | {{(TIMING_W-1){1'b0}}, |(x & ROUND_LOW)};
        end
    endfunction
    reg [FS_OUT_MODE_WIDTH*N_AXES-1:0] out_mode_reg;
    reg [FS_INVERT_WIDTH*N_AXES-1:0]   invert_reg;
    reg [INC_W*N_AXES-1:0]     record_inc_reg;
    // Hardware state
    reg [WORD_W-1:0]           timestamp_reg;
    reg [WORD_W-1:0]           latch_time_reg;
    reg [WORD_W-1:0]           period_count_reg;
    reg [POS_W*N_AXES-1:0]     position_latch_reg;
    reg                        irq_period_reg;
    reg                        irq_block_end_reg;
    reg                        overflow_reg;
    reg                        bus_error_reg;
    reg [COUNT_W-1:0]          underrun_count_reg;
    reg [COUNT_W-1:0]          crc_error_count_reg;
    reg [COUNT_W-1:0]          frame_error_count_reg;
    reg [COUNT_W-1:0]          parallel_error_count_reg;
    reg [COUNT_W-1:0]          refused_count_reg;
    reg                        irq_reg;
    reg [WORD_W-1:0]           rdata_reg;
    // One-cycle pulses after a write
    reg                        clear_errors_reg;
    reg                        clear_faults_reg;
    reg                        flush_reg;
    reg                        clear_counters_reg;
    reg                        kick_reg;
    reg                        push_reg;
    reg                        push_commit_reg;   // the record push_wr_en staged last cycle
    reg                        push_active_reg;   // the push accepted in cycle 1 goes on
    reg [FS_REC_FLAGS_WIDTH-1:0] push_flags_reg;

    // Arbiter: SPI first. The granted request goes into the bus stage; the stage is
    // what is served, in the next cycle. While a push reads RECORD_INC from the store
    // (bus_hold, below) a request that touches the push is not granted (its master holds
    // it) and the others pass: see push_touch.
    reg               stage_valid_reg;
    reg               stage_we_reg;
    reg  [ADDR_W-1:0] stage_addr_reg;
    reg  [WORD_W-1:0] stage_wdata_reg;
    reg  [5:0]        stage_map_reg;    // store_map of the stage's address, taken with it
    // The push sequence: push_seq = k in the k-th cycle after the cycle serving a
    // RECORD_PUSH write (1..N_AXES), 0 when idle. The store is read for RECORD_INC[k] in
    // cycle k (0..N_AXES-1: bus_hold), and that word goes into the FIFO record's
    // lane k in cycle k + 1; the flags and wr_en come in cycle N_AXES, the commit in the
    // next. The push is decided (accepted or refused) in cycle 1.
    // The hold comes from flip-flops (the stage's decode would put the address compare in
    // front of the grant, and the grant in front of the store's address):
    // push_served_reg = the stage serves a RECORD_PUSH write, set with the stage;
    // seq_hold_reg = push_seq is 1 .. N_AXES - 1.
    localparam SEQ_W = 4;
    reg  [SEQ_W-1:0]  push_seq_reg;
    reg               push_served_reg;
    reg               seq_hold_reg;
    // INC_DIRECT: no push sequence, so no hold (its flip-flops stay 0 and go).
    localparam        DIRECT      = (INC_DIRECT != 0);
    wire              bus_hold    = !DIRECT && (push_served_reg || seq_hold_reg);
    localparam [ADDR_W-6:0] BLOCK_HIGH = FS_AXIS_TIMING_A_ADDR[ADDR_W-1:5];   // the axis block's 32 words
    localparam [ADDR_W-4:0] INC_HIGH   = FS_RECORD_INC_ADDR[ADDR_W-1:3];      // RECORD_INC's 8
    // A request that touches the push: a read of the axis block (AXIS_TIMING_A/B,
    // AXIS_MODE) or of RECORD_INC, whose words the store answers through the port the
    // push reads, and a write of RECORD_INC or RECORD_PUSH (the record is RECORD_INC as
    // written before the push; one push at a time). Whole address blocks, so that a few
    // address bits decide it.
    function push_touch(input we, input [ADDR_W-1:0] addr);
        push_touch = we ? (addr[ADDR_W-1:3] == INC_HIGH || addr == FS_RECORD_PUSH_ADDR)
                        : (addr[ADDR_W-1:5] == BLOCK_HIGH || addr[ADDR_W-1:3] == INC_HIGH);
    endfunction
    wire        spi_held  = bus_hold && push_touch(spi_we, spi_addr);
    wire        par_held  = bus_hold && push_touch(par_we, par_addr);
    // A link that is not built never requests (the top ties its request low; said here
    // too, so that a hierarchical build keeps no arbiter or request multiplexer for it).
    wire        spi_req_on = (HAS_SPI != 0) && spi_req;
    wire        par_req_on = (HAS_PARALLEL != 0) && par_req;
    wire        grant_spi = spi_req_on && !spi_held;
    wire        grant_par = par_req_on && !par_held && !grant_spi;
    wire        granted   = grant_spi || grant_par;
    wire [ADDR_W-1:0] granted_addr = grant_spi ? spi_addr : par_addr;
    wire [WORD_W-1:0] granted_wdata = grant_spi ? spi_wdata : par_wdata;
    wire              granted_we = grant_spi ? spi_we : par_we;
    always @(posedge clk) begin
        if (rst) begin
            stage_valid_reg <= 1'b0;
            stage_we_reg    <= 1'b0;
            stage_addr_reg  <= {ADDR_W{1'b0}};
            stage_wdata_reg <= {WORD_W{1'b0}};
            stage_map_reg   <= store_map({ADDR_W{1'b0}});
            push_served_reg <= 1'b0;
        end else begin
            stage_valid_reg <= granted;
            push_served_reg <= granted && granted_we && (granted_addr == FS_RECORD_PUSH_ADDR);
            if (granted) begin
                stage_we_reg    <= granted_we;
                stage_addr_reg  <= granted_addr;
                stage_wdata_reg <= granted_wdata;
                stage_map_reg   <= store_map(granted_addr);
            end
        end
    end
    // With the parallel slave the only master (no SPI), the stage's request is the
    // slave's own request registers: the slave holds them unchanged from its request
    // through the cycle after its grant (busy until then: parallel_bus_slave's proof),
    // so they are read there instead of copied (40 flip-flops fewer).
    localparam PAR_ONLY = (HAS_SPI == 0 && HAS_PARALLEL != 0);
    wire              bus_we    = PAR_ONLY ? par_we : stage_we_reg;
    wire [ADDR_W-1:0] bus_addr  = PAR_ONLY ? par_addr : stage_addr_reg;
    wire [WORD_W-1:0] bus_wdata = PAR_ONLY ? par_wdata : stage_wdata_reg;
    // The readback store (READ_STORE = 1): what a read of AXIS_TIMING_A/B[i],
    // AXIS_MODE[i] or RECORD_INC[i] (i < N_AXES) returns comes from a RAM of 32 words,
    // word {i, k} with k = 0, 1, 2 for the axis block (address 0x20 + 4i + k) and 3 for
    // RECORD_INC[i], instead of a multiplexer over their flip-flops (which stay: they feed
    // the core). The store is written with the readable fields of the word at the edge
    // ending the write's grant cycle and read at the edge ending a read's grant cycle, so
    // a read granted after a write sees it, as the registers do (they take a write at the
    // end of its serving cycle, the grant cycle + 1, and a read returns the state of its
    // serving cycle); one grant a cycle, so the store never reads and writes one word on
    // one clock for a read. `written` marks the words written since reset (the others
    // read their reset values).
    function [5:0] store_map;   // {shadowed, word}
        input [ADDR_W-1:0] addr;
        begin
            store_map = 6'd0;
            if (addr[ADDR_W-1:5] == BLOCK_HIGH && {29'd0, addr[4:2]} < N_AXES && addr[1:0] != 2'd3)
                store_map = {1'b1, addr[4:0]};
            if (addr[ADDR_W-1:3] == INC_HIGH && {29'd0, addr[2:0]} < N_AXES)
                store_map = {1'b1, addr[2:0], 2'd3};
        end
    endfunction
    // The readable fields of a word written to a stored register (k = word[1:0]).
    function [WORD_W-1:0] store_fields;
        input [1:0]        k;
        input [WORD_W-1:0] w;
        begin
            store_fields = {WORD_W{1'b0}};
            case (k)
                2'd0: begin
                    store_fields[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]   = w[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W];
                    store_fields[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W] = w[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W];
                end
                2'd1: begin
                    store_fields[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W] = w[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W];
                    store_fields[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]  = w[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W];
                end
                2'd2: begin
                    store_fields[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH] = w[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH];
                    store_fields[FS_AXIS_MODE_INVERT_A_LSB]  = w[FS_AXIS_MODE_INVERT_A_LSB];
                    store_fields[FS_AXIS_MODE_INVERT_B_LSB]  = w[FS_AXIS_MODE_INVERT_B_LSB];
                    store_fields[FS_AXIS_MODE_INVERT_EN_LSB] = w[FS_AXIS_MODE_INVERT_EN_LSB];
                end
                default: store_fields[INC_W-1:0] = w[INC_W-1:0];
            endcase
        end
    endfunction
    // The reset value of a stored register, as the register file's reset sets it.
    function [WORD_W-1:0] store_reset;
        input [1:0] k;
        reg   [WORD_W-1:0] r;
        begin
            r = {WORD_W{1'b0}};
            case (k)
                2'd0: begin
                    r[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]   = FS_AXIS_TIMING_A_STEP_LEN_RESET[TIMING_W-1:0];
                    r[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W] = FS_AXIS_TIMING_A_STEP_SPACE_RESET[TIMING_W-1:0];
                end
                2'd1: begin
                    r[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W] = FS_AXIS_TIMING_B_DIR_SETUP_RESET[TIMING_W-1:0];
                    r[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]  = FS_AXIS_TIMING_B_DIR_HOLD_RESET[TIMING_W-1:0];
                end
                2'd2: begin
                    r[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH] = FS_AXIS_MODE_OUT_MODE_RESET;
                    r[FS_AXIS_MODE_INVERT_A_LSB]  = FS_AXIS_MODE_INVERT_A_RESET;
                    r[FS_AXIS_MODE_INVERT_B_LSB]  = FS_AXIS_MODE_INVERT_B_RESET;
                    r[FS_AXIS_MODE_INVERT_EN_LSB] = FS_AXIS_MODE_INVERT_EN_RESET;
                end
                default: r[INC_W-1:0] = FS_RECORD_INC_INC_RESET;
            endcase
            store_reset = r;
        end
    endfunction
    localparam STORED = (READ_STORE != 0);
    // The word numbering above relies on the map's layout of the axis block and RECORD_INC.
    generate
        if (FS_AXIS_TIMING_A_ADDR % 32 != 0 || FS_AXIS_TIMING_A_STRIDE != 4 || FS_AXIS_TIMING_B_STRIDE != 4 ||
                FS_AXIS_MODE_STRIDE != 4 || FS_AXIS_TIMING_B_ADDR != FS_AXIS_TIMING_A_ADDR + 1 ||
                FS_AXIS_MODE_ADDR != FS_AXIS_TIMING_A_ADDR + 2 || FS_RECORD_INC_ADDR % 8 != 0 ||
                FS_RECORD_INC_STRIDE != 1) begin : fs_check_store_layout
            register_file_readback_store_needs_the_axis_block_layout out_of_range ();
        end
    endgenerate
    wire [5:0]        grant_map  = store_map(granted_addr);
    // The store's ports take the address with no grant decode in front of them (the ECP5
    // board build's critical path ran from the SPI address through the push-hold decode
    // and the grant into the store's read address). The read address matters only at a
    // read's grant while no push holds the bus (during a hold the port reads the push's
    // words, and a read granted then is of no stored word); then nothing is held, so the
    // granted master is the requesting one, SPI first. The write address and data matter
    // only at a granted write: with one master that is its own.
    wire [ADDR_W-1:0] rd_src_addr = (HAS_PARALLEL == 0) ? spi_addr : (HAS_SPI == 0) ? par_addr :
                                    (spi_req ? spi_addr : par_addr);
    wire [ADDR_W-1:0] wr_src_addr = (HAS_PARALLEL == 0) ? spi_addr : (HAS_SPI == 0) ? par_addr : granted_addr;
    wire [WORD_W-1:0] wr_src_data = (HAS_PARALLEL == 0) ? spi_wdata : (HAS_SPI == 0) ? par_wdata : granted_wdata;
    wire [5:0]        rd_map     = store_map(rd_src_addr);
    wire [5:0]        wr_map     = store_map(wr_src_addr);
    wire unused_maps = &{1'b0, grant_map[4:0], rd_map[5], wr_map[5]};   // grant_map's word: the proof's
    // RECORD_INC[k]'s store word, k = the push sequence's cycle (0 while serving the write).
    wire [4:0]        push_read_word = {push_seq_reg[2:0], 2'd3};
    wire [5:0]        stage_map  = PAR_ONLY ? store_map(bus_addr) : stage_map_reg;
    wire              store_write = STORED && granted && granted_we && grant_map[5];
    wire [WORD_W-1:0] store_rd;
    reg  [31:0]       written_reg;
`ifdef FORMAL
    (* anyconst *) reg [4:0] f_word;      // the store word the invariants look at
    wire [WORD_W-1:0] f_word_data;
`endif
    generate
        if (STORED) begin : readback
            store_ram #(.WIDTH(WORD_W), .DEPTH(32), .ADDR_W(5), .BLOCK(RAM_BLOCK)) store (
                .clk(clk), .wr_en(store_write), .wr_addr(wr_map[4:0]),
                .wr_data(store_fields(wr_map[1:0], wr_src_data)),
                .rd_en(1'b1), .rd_addr(bus_hold ? push_read_word : rd_map[4:0]), .rd_data(store_rd)
`ifdef FORMAL
                , .f_peek_addr(f_word), .f_peek_data(f_word_data)
`endif
            );
        end else begin : no_readback
            assign store_rd = {WORD_W{1'b0}};
`ifdef FORMAL
            assign f_word_data = {WORD_W{1'b0}};
`endif
        end
    endgenerate
    always @(posedge clk) begin
        if (rst || !STORED) written_reg <= 32'd0;
        else if (store_write) written_reg[wr_map[4:0]] <= 1'b1;
    end
    wire              stage_stored = STORED && stage_map[5];
    wire [WORD_W-1:0] stored_word  = written_reg[stage_map[4:0]] ? store_rd : store_reset(stage_map[1:0]);

    wire              write     = stage_valid_reg && bus_we;
    wire              read      = stage_valid_reg && !bus_we;

    wire any_rate_error = |rate_error;
    wire any_step_lost  = |step_lost;
    wire any_error = underrun || overflow_reg || record_error || any_rate_error || any_step_lost || bus_error_reg ||
                     feedback_error || jog_refused;
    wire fifo_low  = ({{(LEVEL_W-1-FIFO_DEPTH_LOG2){1'b0}}, fifo_level} < watermark_reg);
    wire [IRQ_W-1:0] irq_status;
    assign irq_status[FS_IRQ_STATUS_FIFO_LOW_LSB]  = fifo_low;
    assign irq_status[FS_IRQ_STATUS_PERIOD_LSB]    = irq_period_reg;
    assign irq_status[FS_IRQ_STATUS_BLOCK_END_LSB] = irq_block_end_reg;
    assign irq_status[FS_IRQ_STATUS_FAULT_LSB]     = halt;
    assign irq_status[FS_IRQ_STATUS_ERROR_LSB]     = any_error;

    wire [FIFO_DEPTH_LOG2:0] fifo_free = FIFO_DEPTH[FIFO_DEPTH_LOG2:0] - fifo_level - fifo_staged;

    reg [WORD_W-1:0] status_word;
    always @* begin
        status_word = {WORD_W{1'b0}};
        status_word[FS_STATUS_RUNNING_LSB]        = core_run;
        status_word[FS_STATUS_STREAMING_LSB]      = gate;
        status_word[FS_STATUS_HALT_LSB]           = halt;
        status_word[FS_STATUS_FAULT_ESTOP_LSB]    = fault_estop;
        status_word[FS_STATUS_FAULT_WATCHDOG_LSB] = fault_watchdog;
        status_word[FS_STATUS_ESTOP_ACTIVE_LSB]   = estop_active;
        status_word[FS_STATUS_UNDERRUN_LSB]       = underrun;
        status_word[FS_STATUS_OVERFLOW_LSB]       = overflow_reg;
        status_word[FS_STATUS_RECORD_ERROR_LSB]   = record_error;
        status_word[FS_STATUS_RATE_ERROR_LSB]     = any_rate_error;
        status_word[FS_STATUS_STEP_LOST_LSB]      = any_step_lost;
        status_word[FS_STATUS_BUS_ERROR_LSB]      = bus_error_reg;
        status_word[FS_STATUS_IRQ_LSB]            = irq_reg;
        status_word[FS_STATUS_FEEDBACK_ERROR_LSB] = feedback_error;
        status_word[FS_STATUS_JOG_ENGAGED_LSB]    = jog_engaged;
        status_word[FS_STATUS_JOG_REFUSED_LSB]    = jog_refused;
    end

    // A link's error counters count only its own errors: without the link they stay 0,
    // so they read as the constant (a hierarchical build keeps no flip-flops for them).
    wire [COUNT_W-1:0] crc_error_count      = (HAS_SPI != 0) ? crc_error_count_reg : {COUNT_W{1'b0}};
    wire [COUNT_W-1:0] frame_error_count    = (HAS_SPI != 0) ? frame_error_count_reg : {COUNT_W{1'b0}};
    wire [COUNT_W-1:0] parallel_error_count = (HAS_PARALLEL != 0) ? parallel_error_count_reg : {COUNT_W{1'b0}};

    // The read value of an address, from the state of this cycle. A function called only
    // on a read, so a simulator evaluates this wide mux only when a read is served.
    // The read multiplexer in two halves: read_sel decodes an address into one select
    // per readable word (at most one set: the map keeps addresses distinct), read_mux ORs
    // the selected words. With a bus stage the selects are decoded from the granted
    // address into rsel_reg as the stage takes it, so the multiplexer of the serving
    // cycle starts from flip-flops instead of after the address compares (the ECP5
    // board build's critical path on one seed or another: the stage's address -> seven
    // LUTs -> rdata_reg).
    localparam R_ID = 0, R_VERSION = 1, R_CAPS = 2, R_CLOCK_HZ = 3, R_CONTROL = 4, R_STATUS = 5,
               R_FIFO_LEVEL = 6, R_WATERMARK = 7, R_START_LEVEL = 8, R_PERIOD = 9, R_WATCHDOG = 10,
               R_ESTOP_FILTER = 11, R_IRQ_STATUS = 12, R_IRQ_MASK = 13, R_TIMESTAMP = 14,
               R_LATCH_TIME = 15, R_PROBE_TIME = 16, R_PERIOD_COUNT = 17, R_UNDERRUN = 18,
               R_CRC_ERRORS = 19, R_FRAME_ERRORS = 20, R_PAR_ERRORS = 21, R_REFUSED = 22,
               R_AXIS_STATUS = 23, R_AXIS_ENABLE = 24, R_SCALARS = 25;
    localparam R_POSITION = R_SCALARS, R_TIMING_A = R_SCALARS + N_AXES, R_TIMING_B = R_SCALARS + 2 * N_AXES,
               R_MODE = R_SCALARS + 3 * N_AXES, R_INC = R_SCALARS + 4 * N_AXES, N_SEL = R_SCALARS + 5 * N_AXES;
    function [N_SEL-1:0] read_sel(input [ADDR_W-1:0] addr);
        integer index;
        reg [WORD_W-1:0] a;
        begin
            read_sel = {N_SEL{1'b0}};
            a = {{(WORD_W-ADDR_W){1'b0}}, addr};
            case (addr)
                FS_ID_ADDR:                   read_sel[R_ID] = 1'b1;
                FS_VERSION_ADDR:              read_sel[R_VERSION] = 1'b1;
                FS_CAPS_ADDR:                 read_sel[R_CAPS] = 1'b1;
                FS_CLOCK_HZ_ADDR:             read_sel[R_CLOCK_HZ] = 1'b1;
                FS_CONTROL_ADDR:              read_sel[R_CONTROL] = 1'b1;
                FS_STATUS_ADDR:               read_sel[R_STATUS] = 1'b1;
                FS_FIFO_LEVEL_ADDR:           read_sel[R_FIFO_LEVEL] = 1'b1;
                FS_FIFO_WATERMARK_ADDR:       read_sel[R_WATERMARK] = 1'b1;
                FS_START_LEVEL_ADDR:          read_sel[R_START_LEVEL] = 1'b1;
                FS_PERIOD_CLOCKS_ADDR:        read_sel[R_PERIOD] = 1'b1;
                FS_WATCHDOG_TIMEOUT_ADDR:     read_sel[R_WATCHDOG] = 1'b1;
                FS_ESTOP_FILTER_ADDR:         read_sel[R_ESTOP_FILTER] = 1'b1;
                FS_IRQ_STATUS_ADDR:           read_sel[R_IRQ_STATUS] = 1'b1;
                FS_IRQ_MASK_ADDR:             read_sel[R_IRQ_MASK] = 1'b1;
                FS_TIMESTAMP_ADDR:            read_sel[R_TIMESTAMP] = 1'b1;
                FS_LATCH_TIME_ADDR:           read_sel[R_LATCH_TIME] = 1'b1;
                FS_PROBE_TIME_ADDR:           read_sel[R_PROBE_TIME] = (ONE_SNAPSHOT != 0);
                FS_PERIOD_COUNT_ADDR:         read_sel[R_PERIOD_COUNT] = 1'b1;
                FS_UNDERRUN_COUNT_ADDR:       read_sel[R_UNDERRUN] = 1'b1;
                FS_CRC_ERROR_COUNT_ADDR:      read_sel[R_CRC_ERRORS] = 1'b1;
                FS_FRAME_ERROR_COUNT_ADDR:    read_sel[R_FRAME_ERRORS] = 1'b1;
                FS_PARALLEL_ERROR_COUNT_ADDR: read_sel[R_PAR_ERRORS] = 1'b1;
                FS_REFUSED_RECORD_COUNT_ADDR: read_sel[R_REFUSED] = 1'b1;
                FS_AXIS_STATUS_ADDR:          read_sel[R_AXIS_STATUS] = 1'b1;
                FS_AXIS_ENABLE_ADDR:          read_sel[R_AXIS_ENABLE] = 1'b1;
                default: ;
            endcase
            for (index = 0; index < N_AXES; index = index + 1) begin
                read_sel[R_POSITION + index] =
                    a == {{(WORD_W-ADDR_W){1'b0}}, FS_POSITION_ADDR} + index * FS_POSITION_STRIDE ||
                    (ONE_SNAPSHOT != 0 && a == {{(WORD_W-ADDR_W){1'b0}}, FS_PROBE_POSITION_ADDR} + index * FS_PROBE_POSITION_STRIDE);
                // Without the readback store the per-axis arrays from their flip-flops,
                // unless write-only (AXIS_WRITE_ONLY: they read 0).
                read_sel[R_TIMING_A + index] = !STORED && AXIS_WRITE_ONLY == 0 &&
                    a == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_A_ADDR} + index * FS_AXIS_TIMING_A_STRIDE;
                read_sel[R_TIMING_B + index] = !STORED && AXIS_WRITE_ONLY == 0 &&
                    a == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_B_ADDR} + index * FS_AXIS_TIMING_B_STRIDE;
                read_sel[R_MODE + index] = !STORED && AXIS_WRITE_ONLY == 0 &&
                    a == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_MODE_ADDR} + index * FS_AXIS_MODE_STRIDE;
                // RECORD_INC, unless write-only (INC_WRITE_ONLY: it reads 0).
                read_sel[R_INC + index] = !STORED && INC_WRITE_ONLY == 0 &&
                    a == {{(WORD_W-ADDR_W){1'b0}}, FS_RECORD_INC_ADDR} + index * FS_RECORD_INC_STRIDE;
            end
        end
    endfunction
    // An OR of masked words, a shallow tree where overriding ifs would put a multiplexer
    // per register in series.
    function [WORD_W-1:0] read_mux(input [N_SEL-1:0] sel);
        integer index;
        reg [WORD_W-1:0] read_value;
        reg [WORD_W-1:0] control_word, fifo_level_word;
        reg [WORD_W-1:0] watermark_word, start_word, period_word, watchdog_word, estop_word, irq_status_word, irq_mask_word, underrun_word, crc_word, frame_word, par_word, refused_word, axis_enable_word;
        reg [WORD_W-1:0] timing_a_word, timing_b_word, mode_word, axis_status_word;   // one axis's
        begin
            control_word = {WORD_W{1'b0}};
            control_word[FS_CONTROL_RUN_LSB]               = run_reg;
            control_word[FS_CONTROL_WATCHDOG_ENABLE_LSB]   = watchdog_enable_reg;
            control_word[FS_CONTROL_ESTOP_ACTIVE_HIGH_LSB] = estop_active_high_reg;
            fifo_level_word = {WORD_W{1'b0}};
            fifo_level_word[FS_FIFO_LEVEL_LEVEL_LSB +: FIFO_DEPTH_LOG2 + 1] = fifo_level;
            fifo_level_word[FS_FIFO_LEVEL_FREE_LSB +: FIFO_DEPTH_LOG2 + 1]  = fifo_free;
            watermark_word = {WORD_W{1'b0}};
            watermark_word[WATERMARK_W-1:0] = watermark_reg;
            start_word = {WORD_W{1'b0}};
            start_word[START_W-1:0] = start_level_reg;
            period_word = {WORD_W{1'b0}};
            period_word[P_WIDTH-1:0] = period_reg;
            watchdog_word = {WORD_W{1'b0}};
            watchdog_word[WD_W-1:0] = watchdog_timeout_reg;
            estop_word = {WORD_W{1'b0}};
            estop_word[FILTER_W-1:0] = estop_filter_reg;
            irq_status_word = {WORD_W{1'b0}};
            irq_status_word[IRQ_W-1:0] = irq_status;
            irq_mask_word = {WORD_W{1'b0}};
            irq_mask_word[IRQ_W-1:0] = irq_mask_reg;
            underrun_word = {WORD_W{1'b0}};
            underrun_word[COUNT_W-1:0] = underrun_count_reg;
            crc_word = {WORD_W{1'b0}};
            crc_word[COUNT_W-1:0] = crc_error_count;
            frame_word = {WORD_W{1'b0}};
            frame_word[COUNT_W-1:0] = frame_error_count;
            par_word = {WORD_W{1'b0}};
            par_word[COUNT_W-1:0] = parallel_error_count;
            refused_word = {WORD_W{1'b0}};
            refused_word[COUNT_W-1:0] = refused_count_reg;
            axis_enable_word = {WORD_W{1'b0}};
            axis_enable_word[N_AXES-1:0] = axis_enable_reg;
            axis_status_word = {WORD_W{1'b0}};
            axis_status_word[FS_AXIS_STATUS_RATE_ERROR_LSB +: N_AXES] = rate_error;
            axis_status_word[FS_AXIS_STATUS_STEP_LOST_LSB +: N_AXES]  = step_lost;
            read_value = ({WORD_W{sel[R_ID]}} & FS_ID_MAGIC_VALUE)
                | ({WORD_W{sel[R_VERSION]}} & VERSION_WORD)
                | ({WORD_W{sel[R_CAPS]}} & CAPS_WORD)
                | ({WORD_W{sel[R_CLOCK_HZ]}} & CLOCK_HZ)
                | ({WORD_W{sel[R_CONTROL]}} & control_word)
                | ({WORD_W{sel[R_STATUS]}} & status_word)
                | ({WORD_W{sel[R_FIFO_LEVEL]}} & fifo_level_word)
                | ({WORD_W{sel[R_WATERMARK]}} & watermark_word)
                | ({WORD_W{sel[R_START_LEVEL]}} & start_word)
                | ({WORD_W{sel[R_PERIOD]}} & period_word)
                | ({WORD_W{sel[R_WATCHDOG]}} & watchdog_word)
                | ({WORD_W{sel[R_ESTOP_FILTER]}} & estop_word)
                | ({WORD_W{sel[R_IRQ_STATUS]}} & irq_status_word)
                | ({WORD_W{sel[R_IRQ_MASK]}} & irq_mask_word)
                | ({WORD_W{sel[R_TIMESTAMP]}} & timestamp_reg)
                | ({WORD_W{sel[R_LATCH_TIME] || sel[R_PROBE_TIME]}} & latch_time_reg)
                | ({WORD_W{sel[R_PERIOD_COUNT]}} & period_count_reg)
                | ({WORD_W{sel[R_UNDERRUN]}} & underrun_word)
                | ({WORD_W{sel[R_CRC_ERRORS]}} & crc_word)
                | ({WORD_W{sel[R_FRAME_ERRORS]}} & frame_word)
                | ({WORD_W{sel[R_PAR_ERRORS]}} & par_word)
                | ({WORD_W{sel[R_REFUSED]}} & refused_word)
                | ({WORD_W{sel[R_AXIS_STATUS]}} & axis_status_word)
                | ({WORD_W{sel[R_AXIS_ENABLE]}} & axis_enable_word);
            for (index = 0; index < N_AXES; index = index + 1) begin
                timing_a_word = {WORD_W{1'b0}};
                timing_a_word[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]   = step_len_reg[TIMING_W*index +: TIMING_W];
                timing_a_word[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W] = step_space_reg[TIMING_W*index +: TIMING_W];
                timing_b_word = {WORD_W{1'b0}};
                timing_b_word[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W] = dir_setup_reg[TIMING_W*index +: TIMING_W];
                timing_b_word[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]  = dir_hold_reg[TIMING_W*index +: TIMING_W];
                mode_word = {WORD_W{1'b0}};
                mode_word[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH] =
                    out_mode_reg[FS_OUT_MODE_WIDTH*index +: FS_OUT_MODE_WIDTH];
                mode_word[FS_AXIS_MODE_INVERT_A_LSB]  = invert_reg[FS_INVERT_WIDTH*index + FS_INVERT_PIN_A_BIT];
                mode_word[FS_AXIS_MODE_INVERT_B_LSB]  = invert_reg[FS_INVERT_WIDTH*index + FS_INVERT_PIN_B_BIT];
                mode_word[FS_AXIS_MODE_INVERT_EN_LSB] = invert_reg[FS_INVERT_WIDTH*index + FS_INVERT_PIN_EN_BIT];
                read_value = read_value
                    | ({WORD_W{sel[R_POSITION + index]}} & position_latch_reg[POS_W*index +: POS_W])
                    | ({WORD_W{sel[R_TIMING_A + index]}} & timing_a_word)
                    | ({WORD_W{sel[R_TIMING_B + index]}} & timing_b_word)
                    | ({WORD_W{sel[R_MODE + index]}} & mode_word)
                    | ({WORD_W{sel[R_INC + index]}} & record_inc_reg[INC_W*index +: INC_W]);
            end
            read_mux = read_value;
        end
    endfunction
    // The selects of the word the stage serves, taken with the stage (PAR_ONLY: the
    // slave's own address, decoded in the serving cycle).
    reg  [N_SEL-1:0] rsel_reg;
    always @(posedge clk) begin
        if (rst) rsel_reg <= read_sel({ADDR_W{1'b0}});
        else if (granted) rsel_reg <= read_sel(granted_addr);
    end
    wire [N_SEL-1:0] bus_sel = PAR_ONLY ? read_sel(bus_addr) : rsel_reg;

    integer axis;

    // INC_DIRECT: a write of RECORD_INC[k] (k < N_AXES) in its serving cycle writes lane k
    // of the FIFO's record being written, unless the FIFO is full, the SPI frame layer
    // uses its port or a push stages the record in this cycle (the lane is lost: nothing
    // is written, so it cannot slip into the record staged); inc_written marks the lanes
    // written since the last push, flush or use of the port by the SPI frame layer (whose
    // records take the slot), and a push is accepted only when all are (else refused as
    // a push to a full FIFO is), so a queued record never holds a lane of another one.
    reg  [N_AXES-1:0] inc_written_reg;
    wire [N_AXES-1:0] inc_lane_write;
    genvar inc_lane;
    generate
        for (inc_lane = 0; inc_lane < N_AXES; inc_lane = inc_lane + 1) begin : direct_lanes
            assign inc_lane_write[inc_lane] = DIRECT && write && !fifo_full && !spi_fifo_in_use && !push_reg &&
                ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_RECORD_INC_ADDR} + inc_lane * FS_RECORD_INC_STRIDE);
        end
    endgenerate
    always @(posedge clk) begin
        if (rst || !DIRECT || push_reg || fifo_flush || spi_fifo_in_use) inc_written_reg <= {N_AXES{1'b0}};
        else inc_written_reg <= inc_written_reg | inc_lane_write;
    end
    wire push_refused = push_reg && (fifo_full || spi_fifo_in_use || (DIRECT && !(&inc_written_reg)));
    wire push_accept  = push_reg && !push_refused;
    // The push sequence's FIFO writes: lane k - 1 in cycle k, the flags and wr_en in
    // cycle N_AXES, while the push is accepted (cycle 1) or goes on (no flush since).
    wire push_go   = push_reg ? push_accept : push_active_reg;
    wire push_last = ({28'd0, push_seq_reg} == N_AXES);
    genvar lane;
    generate
        for (lane = 0; lane < N_AXES; lane = lane + 1) begin : push_lanes
            assign push_lane[lane] = DIRECT ? inc_lane_write[lane] : push_go && ({28'd0, push_seq_reg} == lane + 1);
        end
    endgenerate
    wire push_stage = DIRECT ? push_accept : push_go && push_last;   // the flags lane and wr_en
    assign push_lane[N_AXES] = push_stage;
    // RECORD_INC[k - 1]: the store word read in the cycle before (its reset value until
    // written), or its flip-flops in a build without the store.
    wire [2:0]        push_axis      = push_seq_reg[2:0] - 3'd1;
    wire [4:0]        push_word_addr = {push_axis, 2'd3};
    wire [WORD_W-1:0] push_stored    = written_reg[push_word_addr] ? store_rd : store_reset(2'd3);
    wire [INC_W-1:0]  push_ff_word   = record_inc_reg[INC_W*push_axis +: INC_W];
    wire [INC_W-1:0]  push_inc       = STORED ? push_stored[INC_W-1:0] : push_ff_word;
    // REFUSED_RECORD_COUNT counts a refused push (1) and the records of a refused SPI
    // commit (spi_refused_count) of this cycle, as one carry chain: the SPI count is the
    // addend and the push's refusal, which decides late (on the FIFO's fill), the carry
    // in ({count, 1} + {addend, carry}), so the counter's sum waits for no sum before it
    // (the ECP5 board build's critical path at 100 MHz, seed 2, with a sum of the two).
    wire [COUNT_W-1:0] spi_refused_add = (HAS_SPI != 0 && spi_refused) ? {{(COUNT_W-8){1'b0}}, spi_refused_count} :
                                                                       {COUNT_W{1'b0}};
    wire [COUNT_W:0]   refused_sum     = {refused_count_reg, 1'b1} + {spi_refused_add, push_refused};
    wire unused_refused_sum = &{1'b0, refused_sum[0]};

    // Time and the position latch. With ONE_SNAPSHOT it is the probe's snapshot too: a
    // probe event takes it (whatever latch_hold says), and while PROBE_STATUS.SEEN the
    // period latch leaves it alone (the encoder bank's copies still follow latch_now).
    wire snapshot_now = ONE_SNAPSHOT != 0 ? (probe_event || (latch_now && !probe_seen)) : latch_now;
    always @(posedge clk) begin
        if (rst) begin
            timestamp_reg      <= {WORD_W{1'b0}};
            latch_time_reg     <= {WORD_W{1'b0}};
            period_count_reg   <= {WORD_W{1'b0}};
            position_latch_reg <= {POS_W*N_AXES{1'b0}};
        end else begin
            timestamp_reg <= timestamp_reg + 1'b1;
            if (boundary) period_count_reg <= period_count_reg + 1'b1;
            if (snapshot_now) begin
                position_latch_reg <= position;
                latch_time_reg     <= timestamp_reg;
            end
        end
    end

    // The read port (the stage's read answers at the edge ending its serving cycle) and
    // the interrupt pin.
    always @(posedge clk) begin
        if (rst) begin
            irq_reg   <= 1'b0;
            rdata_reg <= {WORD_W{1'b0}};
        end else begin
            irq_reg <= |(irq_status & irq_mask_reg);
            if (read) rdata_reg <= (stage_stored ? stored_word : read_mux(bus_sel)) | early_rdata;
        end
    end

    // Host registers: what a served write puts there. A halt wins over a write of RUN;
    // so does the jog while it drives the core.
    always @(posedge clk) begin
        if (rst) begin
            run_reg               <= FS_CONTROL_RUN_RESET;
            watchdog_enable_reg   <= FS_CONTROL_WATCHDOG_ENABLE_RESET;
            estop_active_high_reg <= FS_CONTROL_ESTOP_ACTIVE_HIGH_RESET;
            period_reg            <= FS_PERIOD_CLOCKS_CLOCKS_RESET[P_WIDTH-1:0];
            watchdog_timeout_reg  <= FS_WATCHDOG_TIMEOUT_CLOCKS_RESET[WD_W-1:0];
            estop_filter_reg      <= FS_ESTOP_FILTER_SAMPLES_RESET;
            watermark_reg         <= FS_FIFO_WATERMARK_WATERMARK_RESET;
            start_level_reg       <= FS_START_LEVEL_LEVEL_RESET;
            irq_mask_reg          <= FS_IRQ_MASK_MASK_RESET;
            axis_enable_reg       <= FS_AXIS_ENABLE_ENABLE_RESET[N_AXES-1:0];
            step_len_reg          <= {N_AXES{held_timing(FS_AXIS_TIMING_A_STEP_LEN_RESET[TIMING_W-1:0])}};
            step_space_reg        <= {N_AXES{held_timing(FS_AXIS_TIMING_A_STEP_SPACE_RESET[TIMING_W-1:0])}};
            dir_setup_reg         <= {N_AXES{held_timing(FS_AXIS_TIMING_B_DIR_SETUP_RESET[TIMING_W-1:0])}};
            dir_hold_reg          <= {N_AXES{held_timing(FS_AXIS_TIMING_B_DIR_HOLD_RESET[TIMING_W-1:0])}};
            out_mode_reg          <= {N_AXES{FS_AXIS_MODE_OUT_MODE_RESET}};
            for (axis = 0; axis < N_AXES; axis = axis + 1) begin
                invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_A_BIT]  <= FS_AXIS_MODE_INVERT_A_RESET;
                invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_B_BIT]  <= FS_AXIS_MODE_INVERT_B_RESET;
                invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_EN_BIT] <= FS_AXIS_MODE_INVERT_EN_RESET;
            end
            record_inc_reg        <= {N_AXES{FS_RECORD_INC_INC_RESET}};
        end else begin
            if (write) begin
                case (bus_addr)
                    FS_CONTROL_ADDR: begin
                        run_reg               <= bus_wdata[FS_CONTROL_RUN_LSB];
                        watchdog_enable_reg   <= bus_wdata[FS_CONTROL_WATCHDOG_ENABLE_LSB];
                        estop_active_high_reg <= bus_wdata[FS_CONTROL_ESTOP_ACTIVE_HIGH_LSB];
                    end
                    FS_FIFO_WATERMARK_ADDR:   watermark_reg        <= bus_wdata[WATERMARK_W-1:0];
                    FS_START_LEVEL_ADDR:      start_level_reg      <= bus_wdata[START_W-1:0];
                    FS_PERIOD_CLOCKS_ADDR:    period_reg           <= bus_wdata[P_WIDTH-1:0];
                    FS_WATCHDOG_TIMEOUT_ADDR: watchdog_timeout_reg <= bus_wdata[WD_W-1:0];
                    FS_ESTOP_FILTER_ADDR:     estop_filter_reg     <= bus_wdata[FILTER_W-1:0];
                    FS_IRQ_MASK_ADDR:         irq_mask_reg         <= bus_wdata[IRQ_W-1:0];
                    FS_AXIS_ENABLE_ADDR:      axis_enable_reg      <= bus_wdata[N_AXES-1:0];
                    default: ;
                endcase
                for (axis = 0; axis < N_AXES; axis = axis + 1) begin
                    if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_A_ADDR} + axis * FS_AXIS_TIMING_A_STRIDE) begin
                        step_len_reg[TIMING_W*axis +: TIMING_W] <=
                            held_timing(bus_wdata[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]);
                        step_space_reg[TIMING_W*axis +: TIMING_W] <=
                            held_timing(bus_wdata[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W]);
                    end
                    if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_B_ADDR} + axis * FS_AXIS_TIMING_B_STRIDE) begin
                        dir_setup_reg[TIMING_W*axis +: TIMING_W] <=
                            held_timing(bus_wdata[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W]);
                        dir_hold_reg[TIMING_W*axis +: TIMING_W] <=
                            held_timing(bus_wdata[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]);
                    end
                    if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_MODE_ADDR} + axis * FS_AXIS_MODE_STRIDE) begin
                        out_mode_reg[FS_OUT_MODE_WIDTH*axis +: FS_OUT_MODE_WIDTH] <=
                            bus_wdata[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH];
                        invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_A_BIT]  <= bus_wdata[FS_AXIS_MODE_INVERT_A_LSB];
                        invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_B_BIT]  <= bus_wdata[FS_AXIS_MODE_INVERT_B_LSB];
                        invert_reg[FS_INVERT_WIDTH*axis + FS_INVERT_PIN_EN_BIT] <= bus_wdata[FS_AXIS_MODE_INVERT_EN_LSB];
                    end
                    if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_RECORD_INC_ADDR} + axis * FS_RECORD_INC_STRIDE)
                        record_inc_reg[INC_W*axis +: INC_W] <= bus_wdata[INC_W-1:0];
                end
            end
            if (halt || jog_engaged) run_reg <= 1'b0;
        end
    end

    // One-clock pulses after a write: the commands, RECORD_PUSH and the watchdog kick
    // (every served write and every SPI commit).
    always @(posedge clk) begin
        if (rst) begin
            clear_errors_reg   <= 1'b0;
            clear_faults_reg   <= 1'b0;
            flush_reg          <= 1'b0;
            clear_counters_reg <= 1'b0;
            kick_reg           <= 1'b0;
            push_reg           <= 1'b0;
            push_commit_reg    <= 1'b0;
            push_active_reg    <= 1'b0;
            push_seq_reg       <= {SEQ_W{1'b0}};
            seq_hold_reg       <= 1'b0;
            push_flags_reg     <= {FS_REC_FLAGS_WIDTH{1'b0}};
        end else begin
            push_commit_reg    <= push_stage;
            push_active_reg    <= !DIRECT && push_go && !push_last && !fifo_flush;
            push_seq_reg       <= (bus_hold && !push_last) ? push_seq_reg + 1'b1 : {SEQ_W{1'b0}};
            // push_seq after this edge is 1 .. N_AXES - 1
            seq_hold_reg       <= bus_hold && ({28'd0, push_seq_reg} + 1 < N_AXES);
            clear_errors_reg   <= write && bus_addr == FS_COMMAND_ADDR && bus_wdata[FS_COMMAND_CLEAR_ERRORS_LSB];
            clear_faults_reg   <= write && bus_addr == FS_COMMAND_ADDR && bus_wdata[FS_COMMAND_CLEAR_FAULTS_LSB];
            flush_reg          <= write && bus_addr == FS_COMMAND_ADDR && bus_wdata[FS_COMMAND_FLUSH_FIFO_LSB];
            clear_counters_reg <= write && bus_addr == FS_COMMAND_ADDR && bus_wdata[FS_COMMAND_CLEAR_COUNTERS_LSB];
            push_reg           <= write && bus_addr == FS_RECORD_PUSH_ADDR;
            if (write && bus_addr == FS_RECORD_PUSH_ADDR)
                push_flags_reg <= bus_wdata[FS_RECORD_PUSH_FLAGS_LSB +: FS_REC_FLAGS_WIDTH];
            kick_reg           <= write || spi_fifo_commit;
        end
    end

    // Sticky flags: a set wins over a clear in the same clock (write-1-to-clear for the
    // interrupt sources, CLEAR_ERRORS for the others).
    always @(posedge clk) begin
        if (rst) begin
            irq_period_reg    <= 1'b0;
            irq_block_end_reg <= 1'b0;
            overflow_reg      <= 1'b0;
            bus_error_reg     <= 1'b0;
        end else begin
            if (boundary) irq_period_reg <= 1'b1;
            else if (write && bus_addr == FS_IRQ_STATUS_ADDR && bus_wdata[FS_IRQ_STATUS_PERIOD_LSB])
                irq_period_reg <= 1'b0;
            if (block_end) irq_block_end_reg <= 1'b1;
            else if (write && bus_addr == FS_IRQ_STATUS_ADDR && bus_wdata[FS_IRQ_STATUS_BLOCK_END_LSB])
                irq_block_end_reg <= 1'b0;
            if (push_refused || spi_refused) overflow_reg <= 1'b1;
            else if (clear_errors_reg) overflow_reg <= 1'b0;
            if (spi_crc_error || spi_frame_error || par_error) bus_error_reg <= 1'b1;
            else if (clear_errors_reg) bus_error_reg <= 1'b0;
        end
    end

    // Error counters (wrap at 16 bits); CLEAR_COUNTERS zeroes them all and wins.
`ifdef F_FREE_COUNTERS
    // The formal task counters: any value at reset, so that the counting properties meet
    // every counter value a few clocks after it (from 0 a 16-bit counter's bit 15 takes
    // 2^15 events: a base case never gets there).
    (* anyconst *) reg [5*COUNT_W-1:0] f_count_start;
`endif
    always @(posedge clk) begin
        if (rst || clear_counters_reg) begin
            underrun_count_reg       <= {COUNT_W{1'b0}};
            crc_error_count_reg      <= {COUNT_W{1'b0}};
            frame_error_count_reg    <= {COUNT_W{1'b0}};
            parallel_error_count_reg <= {COUNT_W{1'b0}};
            refused_count_reg        <= {COUNT_W{1'b0}};
`ifdef F_FREE_COUNTERS
            if (rst) {underrun_count_reg, crc_error_count_reg, frame_error_count_reg,
                      parallel_error_count_reg, refused_count_reg} <= f_count_start;
`endif
        end else begin
            if (underrun_event) underrun_count_reg <= underrun_count_reg + 1'b1;
            if (spi_crc_error) crc_error_count_reg <= crc_error_count_reg + 1'b1;
            if (spi_frame_error) frame_error_count_reg <= frame_error_count_reg + 1'b1;
            if (par_error) parallel_error_count_reg <= parallel_error_count_reg + 1'b1;
            refused_count_reg <= refused_sum[COUNT_W:1];
        end
    end

    assign latch_now         = !latch_hold && (boundary || !core_run);
    assign clear_counters    = clear_counters_reg;
    assign run_write_one     = write && (bus_addr == FS_CONTROL_ADDR) && bus_wdata[FS_CONTROL_RUN_LSB];
    assign timestamp         = timestamp_reg;
    assign bus_write         = write;
    assign bus_address       = bus_addr;
    assign bus_write_data    = bus_wdata;
    assign spi_grant         = grant_spi;
    assign par_grant         = grant_par;
    assign bus_read          = read;
    assign rdata             = rdata_reg | late_rdata;
    assign run               = run_reg;
    assign watchdog_enable   = watchdog_enable_reg;
    assign estop_active_high = estop_active_high_reg;
    assign period_clocks     = period_reg;
    assign watchdog_timeout  = watchdog_timeout_reg;
    assign estop_filter      = estop_filter_reg;
    assign start_level       = start_level_reg;
    assign axis_enable       = axis_enable_reg;
    assign step_len          = step_len_reg;
    assign step_space        = step_space_reg;
    assign dir_setup         = dir_setup_reg;
    assign dir_hold          = dir_hold_reg;
    assign out_mode          = out_mode_reg;
    assign invert            = invert_reg;
    assign clear_errors      = clear_errors_reg;
    assign clear_faults      = clear_faults_reg;
    assign flush_cmd         = flush_reg;
    assign kick              = kick_reg;
    assign push_word         = DIRECT ? bus_wdata[INC_W-1:0] : push_inc;
    assign push_flags        = push_flags_reg;
    assign push_wr_en        = push_stage;
    assign push_commit       = push_commit_reg;
    assign push_in_flight    = DIRECT ? push_accept : push_go;
    assign status_byte       = status_word[7:0];
    assign irq               = irq_reg;

`ifdef FORMAL
    // One master served at a time and only on request; a record is pushed only when
    // the FIFO has room and the SPI frame layer is not using its port, else refused
    // and flagged, and committed exactly in the next cycle; a halt always clears RUN; every served write and every SPI commit
    // kicks the watchdog, and nothing else does; sticky flags hold until cleared.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    // A link that is not built never requests (finestep_top ties its master's request
    // low); its error inputs stay free, so the proof covers them doing anything.
    always @(*) begin
        if (HAS_SPI == 0) assume (!spi_req);
        if (HAS_PARALLEL == 0) assume (!par_req);
    end
    // The parallel slave holds its request through the cycle after its grant (its own
    // proof): with it the only master the bus stage reads it there (PAR_ONLY).
    always @(posedge clk) if (f_past_valid && PAR_ONLY && $past(grant_par))
        assume (par_we == $past(par_we) && par_addr == $past(par_addr) && par_wdata == $past(par_wdata));
    always @(*) begin
        assert (!(grant_spi && grant_par));
        if (grant_spi) assert (spi_req);
        if (grant_par) assert (par_req);
        if (push_accept) assert (push_reg && !fifo_full && !spi_fifo_in_use);
        // No request that touches the push is granted while it reads the store; the
        // others are (SPI first).
        if (bus_hold && granted) assert (!push_touch(granted_we, granted_addr));
        if (spi_req && !spi_held) assert (grant_spi);
        if (par_req && !par_held && !spi_req) assert (grant_par);
        // The store's port the push reads is not written on the word it reads.
        if (bus_hold && store_write) assert (grant_map[4:0] != push_read_word);
        // The store's grant-free addresses are the granted ones where they matter.
        if (store_write) assert (wr_map == grant_map && wr_src_data == granted_wdata);
        if (granted && !bus_hold) assert (rd_map == grant_map);
    end
    always @(*) if (f_past_valid && !rst) begin
        // The sequence counts 1..N_AXES after the cycle serving the write; the hold's
        // flip-flops say what the stage and the sequence say.
        assert (push_served_reg == (stage_valid_reg && bus_we && bus_addr == FS_RECORD_PUSH_ADDR));
        // The stage's decoded selects and store word are its address's.
        if (!PAR_ONLY) assert (rsel_reg == read_sel(stage_addr_reg) && stage_map_reg == store_map(stage_addr_reg));
        assert (seq_hold_reg == (push_seq_reg != {SEQ_W{1'b0}} && {28'd0, push_seq_reg} < N_AXES));
        assert ({28'd0, push_seq_reg} <= N_AXES);
        if (!DIRECT) assert (push_reg == (push_seq_reg == {{(SEQ_W-1){1'b0}}, 1'b1}));
        if (push_active_reg) assert (push_seq_reg > {{(SEQ_W-1){1'b0}}, 1'b1});
        // The word a push writes is RECORD_INC[k - 1] (its register).
        if (!DIRECT && push_go && (!STORED || push_word_addr == f_word))
            assert (push_word == record_inc_reg[INC_W*push_axis +: INC_W]);
        // INC_DIRECT: no sequence; a lane is written only by a served write of its
        // RECORD_INC while the FIFO has room, with that write's word, and a record is
        // staged only with every lane written since the last push or flush.
        if (DIRECT) begin
            assert (push_seq_reg == {SEQ_W{1'b0}} && !push_active_reg && !bus_hold);
            if (|push_lane[N_AXES-1:0]) assert (write && !fifo_full && !spi_fifo_in_use && !push_reg && push_word == bus_wdata);
            if (push_wr_en) assert (push_reg && &inc_written_reg && !fifo_full && push_lane[N_AXES]);
            if (push_reg && !(&inc_written_reg)) assert (push_refused && !push_wr_en);
        end
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(halt) || $past(jog_engaged)) assert (!run_reg);
        assert (kick_reg == $past(write || spi_fifo_commit));
        if ($past(push_refused)) assert (overflow_reg);
        if ($past(overflow_reg) && !$past(clear_errors_reg)) assert (overflow_reg);
        if ($past(clear_counters_reg)) assert (underrun_count_reg == 16'd0 && crc_error_count_reg == 16'd0 &&
                                              refused_count_reg == 16'd0);
        // Otherwise each error counter counts its own events, one each (wrapping at 16 bits).
        if (!$past(clear_counters_reg))
            assert (underrun_count_reg == $past(underrun_count_reg) + {15'd0, $past(underrun_event)} &&
                    crc_error_count_reg == $past(crc_error_count_reg) + {15'd0, $past(spi_crc_error)} &&
                    frame_error_count_reg == $past(frame_error_count_reg) + {15'd0, $past(spi_frame_error)} &&
                    parallel_error_count_reg == $past(parallel_error_count_reg) + {15'd0, $past(par_error)} &&
                    refused_count_reg == $past(refused_count_reg) + {15'd0, $past(push_refused)} +
                                         ((HAS_SPI != 0 && $past(spi_refused)) ? {8'd0, $past(spi_refused_count)} : 16'd0));
        if ($past(write && bus_addr == FS_RECORD_PUSH_ADDR)) assert (push_reg);
        assert (push_commit == $past(push_stage));
        if (!DIRECT && $past(push_go) && !$past(push_last) && !$past(fifo_flush)) assert (push_go);
        // INC_DIRECT: a lane written stays marked until the next push or flush.
        if (DIRECT && !$past(push_reg) && !$past(fifo_flush) && !$past(spi_fifo_in_use))
            assert (inc_written_reg == ($past(inc_written_reg) | $past(push_lane[N_AXES-1:0])));
        if (DIRECT && ($past(push_reg) || $past(fifo_flush) || $past(spi_fifo_in_use)))
            assert (inc_written_reg == {N_AXES{1'b0}});
        // The bus stage serves exactly the request granted in the cycle before.
        assert (stage_valid_reg == $past(granted));
        if ($past(grant_spi)) assert (bus_we == $past(spi_we) && bus_addr == $past(spi_addr) &&
                                      bus_wdata == $past(spi_wdata));
        if ($past(grant_par)) assert (bus_we == $past(par_we) && bus_addr == $past(par_addr) &&
                                      bus_wdata == $past(par_wdata));
        cover (push_accept);
        cover (push_commit);
        cover ($past(push_refused));
        cover (read && stage_stored && written_reg[stage_map[4:0]] && stored_word != 32'd0);
        // The store's read register holds the word read at the grant.
        if (STORED && $past(granted && grant_map[5] && grant_map[4:0] == f_word && !store_write))
            assert (store_rd == $past(f_word_data));
    end

    // The readback store answers what the registers hold: a served read of a stored
    // register gets the word its flip-flops make (the multiplexer it replaces).
    reg [WORD_W-1:0] f_ff_word;
    integer f_axis;
    always @(*) begin
        f_ff_word = {WORD_W{1'b0}};
        for (f_axis = 0; f_axis < N_AXES; f_axis = f_axis + 1) if (AXIS_WRITE_ONLY == 0) begin
            if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_A_ADDR} + f_axis * FS_AXIS_TIMING_A_STRIDE) begin
                f_ff_word[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]   = step_len_reg[TIMING_W*f_axis +: TIMING_W];
                f_ff_word[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W] = step_space_reg[TIMING_W*f_axis +: TIMING_W];
            end
            if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_B_ADDR} + f_axis * FS_AXIS_TIMING_B_STRIDE) begin
                f_ff_word[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W] = dir_setup_reg[TIMING_W*f_axis +: TIMING_W];
                f_ff_word[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]  = dir_hold_reg[TIMING_W*f_axis +: TIMING_W];
            end
            if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_MODE_ADDR} + f_axis * FS_AXIS_MODE_STRIDE) begin
                f_ff_word[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH] = out_mode_reg[FS_OUT_MODE_WIDTH*f_axis +: FS_OUT_MODE_WIDTH];
                f_ff_word[FS_AXIS_MODE_INVERT_A_LSB]  = invert_reg[FS_INVERT_WIDTH*f_axis + FS_INVERT_PIN_A_BIT];
                f_ff_word[FS_AXIS_MODE_INVERT_B_LSB]  = invert_reg[FS_INVERT_WIDTH*f_axis + FS_INVERT_PIN_B_BIT];
                f_ff_word[FS_AXIS_MODE_INVERT_EN_LSB] = invert_reg[FS_INVERT_WIDTH*f_axis + FS_INVERT_PIN_EN_BIT];
            end
            // RECORD_INC reads as written, or 0 when write-only (INC_WRITE_ONLY).
            if ({{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_RECORD_INC_ADDR} + f_axis * FS_RECORD_INC_STRIDE &&
                INC_WRITE_ONLY == 0)
                f_ff_word[INC_W-1:0] = record_inc_reg[INC_W*f_axis +: INC_W];
        end
    end
    // The timings: a write of an axis's timing word lands in its registers as
    // held_timing says (as written when TIMING_ROUND_L = 0), and every timing is always
    // in that form (bits 1 .. L-1 clear).
    integer f_t;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        for (f_t = 0; f_t < N_AXES; f_t = f_t + 1) begin
            assert (step_len_reg[TIMING_W*f_t +: TIMING_W] == held_timing(step_len_reg[TIMING_W*f_t +: TIMING_W]));
            assert (step_space_reg[TIMING_W*f_t +: TIMING_W] == held_timing(step_space_reg[TIMING_W*f_t +: TIMING_W]));
            assert (dir_setup_reg[TIMING_W*f_t +: TIMING_W] == held_timing(dir_setup_reg[TIMING_W*f_t +: TIMING_W]));
            assert (dir_hold_reg[TIMING_W*f_t +: TIMING_W] == held_timing(dir_hold_reg[TIMING_W*f_t +: TIMING_W]));
            if ($past(write) && {{(WORD_W-ADDR_W){1'b0}}, $past(bus_addr)} ==
                    {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_A_ADDR} + f_t * FS_AXIS_TIMING_A_STRIDE) begin
                assert (step_len_reg[TIMING_W*f_t +: TIMING_W] ==
                        held_timing($past(bus_wdata[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W])));
                assert (step_space_reg[TIMING_W*f_t +: TIMING_W] ==
                        held_timing($past(bus_wdata[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W])));
            end
            if ($past(write) && {{(WORD_W-ADDR_W){1'b0}}, $past(bus_addr)} ==
                    {{(WORD_W-ADDR_W){1'b0}}, FS_AXIS_TIMING_B_ADDR} + f_t * FS_AXIS_TIMING_B_STRIDE) begin
                assert (dir_setup_reg[TIMING_W*f_t +: TIMING_W] ==
                        held_timing($past(bus_wdata[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W])));
                assert (dir_hold_reg[TIMING_W*f_t +: TIMING_W] ==
                        held_timing($past(bus_wdata[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W])));
            end
        end
    end

    // The word f_word of the store, once written, holds its register's readable fields
    // (the invariant that makes the read property inductive): the register behind f_word
    // is the one a write granted now would land in, decoded by f_word_reg below.
    reg [WORD_W-1:0] f_word_reg;
    integer f_a;
    always @(*) begin
        f_word_reg = {WORD_W{1'b0}};
        for (f_a = 0; f_a < N_AXES; f_a = f_a + 1) begin
            if ({29'd0, f_word[4:2]} == f_a) begin
                case (f_word[1:0])
                    2'd0: begin
                        f_word_reg[FS_AXIS_TIMING_A_STEP_LEN_LSB +: TIMING_W]   = step_len_reg[TIMING_W*f_a +: TIMING_W];
                        f_word_reg[FS_AXIS_TIMING_A_STEP_SPACE_LSB +: TIMING_W] = step_space_reg[TIMING_W*f_a +: TIMING_W];
                    end
                    2'd1: begin
                        f_word_reg[FS_AXIS_TIMING_B_DIR_SETUP_LSB +: TIMING_W] = dir_setup_reg[TIMING_W*f_a +: TIMING_W];
                        f_word_reg[FS_AXIS_TIMING_B_DIR_HOLD_LSB +: TIMING_W]  = dir_hold_reg[TIMING_W*f_a +: TIMING_W];
                    end
                    2'd2: begin
                        f_word_reg[FS_AXIS_MODE_OUT_MODE_LSB +: FS_OUT_MODE_WIDTH] = out_mode_reg[FS_OUT_MODE_WIDTH*f_a +: FS_OUT_MODE_WIDTH];
                        f_word_reg[FS_AXIS_MODE_INVERT_A_LSB]  = invert_reg[FS_INVERT_WIDTH*f_a + FS_INVERT_PIN_A_BIT];
                        f_word_reg[FS_AXIS_MODE_INVERT_B_LSB]  = invert_reg[FS_INVERT_WIDTH*f_a + FS_INVERT_PIN_B_BIT];
                        f_word_reg[FS_AXIS_MODE_INVERT_EN_LSB] = invert_reg[FS_INVERT_WIDTH*f_a + FS_INVERT_PIN_EN_BIT];
                    end
                    default: f_word_reg[INC_W-1:0] = record_inc_reg[INC_W*f_a +: INC_W];
                endcase
            end
        end
    end
    // A write granted in the last cycle is in the store but not yet in its register.
    wire f_word_pending = stage_valid_reg && bus_we && stage_map[5] && stage_map[4:0] == f_word;
    always @(*) if (f_past_valid && !rst && STORED) begin
        if ({29'd0, f_word[4:2]} < N_AXES && written_reg[f_word] && !f_word_pending)
            assert (f_word_data == f_word_reg);
        if (!({29'd0, f_word[4:2]} < N_AXES)) assert (!written_reg[f_word]);
        else if (!written_reg[f_word]) assert (f_word_reg == store_reset(f_word[1:0]));
        if (f_word_pending) assert (f_word_data == store_fields(f_word[1:0], bus_wdata));
        if (read && stage_stored && stage_map[4:0] == f_word) assert (stored_word == f_ff_word);
        // The store never reads and writes one word for a read in one clock.
        if (store_write) assert (!(granted && !granted_we));
    end

    // IRQ_MASK (spec): reset value from the map, then the value of the last served write
    // to it, read back as written; the irq pin is |(IRQ_STATUS & IRQ_MASK) a clock later.
    reg [IRQ_W-1:0] f_irq_mask;
    always @(posedge clk) begin
        if (write && bus_addr == FS_IRQ_MASK_ADDR) f_irq_mask <= bus_wdata[IRQ_W-1:0];
        if (rst) f_irq_mask <= FS_IRQ_MASK_MASK_RESET;
    end
    always @(*) if (f_past_valid && !rst) assert (irq_mask_reg == f_irq_mask);
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (irq == $past(|(irq_status & f_irq_mask)));
        // early_rdata's bits reach the read register with the served read's word.
        if ($past(read)) assert ((rdata_reg & $past(early_rdata)) == $past(early_rdata));
        if ($past(read && bus_addr == FS_IRQ_MASK_ADDR && !stage_stored && early_rdata == 32'd0))
            assert (rdata_reg[IRQ_W-1:0] == $past(f_irq_mask));
        // Without a link its error counters read 0, whatever its (absent) error inputs do.
        if (HAS_SPI == 0 && $past(read && early_rdata == 32'd0 &&
                (bus_addr == FS_CRC_ERROR_COUNT_ADDR || bus_addr == FS_FRAME_ERROR_COUNT_ADDR)))
            assert (rdata_reg == 32'd0);
        if (HAS_PARALLEL == 0 && $past(read && early_rdata == 32'd0 && bus_addr == FS_PARALLEL_ERROR_COUNT_ADDR))
            assert (rdata_reg == 32'd0);
        // The position latch (spec): the core's positions and TIMESTAMP of the cycle of a
        // period latch (latch_now) or, with ONE_SNAPSHOT, of a probe event, the period
        // latch left alone while SEEN; else held. With ONE_SNAPSHOT, PROBE_POSITION and
        // PROBE_TIME read it, from the register file's own flip-flops.
        if (ONE_SNAPSHOT != 0 ? $past(probe_event || (latch_now && !probe_seen)) : $past(latch_now))
            assert (position_latch_reg == $past(position) && latch_time_reg == $past(timestamp_reg));
        else
            assert (position_latch_reg == $past(position_latch_reg) && latch_time_reg == $past(latch_time_reg));
        if (ONE_SNAPSHOT != 0 && $past(read && !stage_stored && early_rdata == 32'd0 &&
                {{(WORD_W-ADDR_W){1'b0}}, bus_addr} == {{(WORD_W-ADDR_W){1'b0}}, FS_PROBE_POSITION_ADDR}))
            assert (rdata_reg == $past(position_latch_reg[POS_W-1:0]));
        if (ONE_SNAPSHOT != 0 && $past(read && !stage_stored && early_rdata == 32'd0 && bus_addr == FS_PROBE_TIME_ADDR))
            assert (rdata_reg == $past(latch_time_reg));
    end
`endif

endmodule

`default_nettype wire
