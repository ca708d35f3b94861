`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/parallel_bus_slave.md
// 8080/FSMC parallel bus slave: the STM32 FSMC's asynchronous multiplexed mode of seed
// 003 (chip select, NADV address latch, RD, WR, 16-bit address/data). The strobes and
// the bus are synchronised before use, so the host's timing only has to be slow enough
// (see the spec). Registers are 32 bits: reading the low half latches the high half and
// the high half must be written right after the low half, so 32-bit accesses over the
// 16-bit bus are coherent and a torn write is refused rather than applied.
//
// Latency: read data is driven 7 clocks after RD falls at the pins (5 when the high half
// comes from the latch); a write reaches the register bus 4 clocks after WR rises (and
// takes effect one clock after its grant, from the register file's bus stage).
module parallel_bus_slave #(
    // 1: the register bus's only master (no SPI; the CPLD builds): bus_rdata holds the
    // last word this slave read until its next read, so the latched high half is read
    // there (no copy of it), and a write's low half is sent from its own register (held
    // from the request through the cycle after the grant: busy), not copied
    parameter SOLE_MASTER = 0
) (
    // clock, reset
    input  wire        clk,
    input  wire        rst,
    // pins (asynchronous)
    input  wire        bus_cs_n,
    input  wire        bus_adv_n,
    input  wire        bus_rd_n,
    input  wire        bus_wr_n,
    input  wire [15:0] bus_ad_in,
    output wire [15:0] bus_ad_out,
    output wire        bus_ad_oe,
    // register bus master
    output wire        bus_req,
    output wire        bus_we,
    output wire [6:0]  bus_addr,
    output wire [31:0] bus_wdata,
    input  wire        bus_grant,
    input  wire [31:0] bus_rdata,
    // event, in the cycle that detects it
    output wire        error
);

    // Two synchroniser flops, then one more for edge detection: [1] = now, [2] = before.
    reg [2:0]  cs_n_sync_reg;
    reg [1:0]  adv_n_sync_reg;   // no edge needed: the address is sampled while low
    reg [2:0]  rd_n_sync_reg;
    reg [2:0]  wr_n_sync_reg;
    reg [15:0] ad_meta_reg;
    reg [15:0] ad_sync_reg;

    reg [7:0]  addr_reg;          // halfword address: register [7:1], half [0]
    reg [15:0] wdata_reg;
    reg [15:0] lo_data_reg;       // low half written, waiting for its high half
    reg [6:0]  lo_reg_reg;
    reg        lo_valid_reg;
    reg [15:0] hi_data_reg;       // high half latched by a low-half read (SOLE_MASTER 0)
    reg [6:0]  hi_reg_reg;
    reg        hi_valid_reg;
    reg [15:0] ad_out_reg;
    reg        ad_oe_reg;
    reg        req_reg;
    reg        we_reg;
    reg [6:0]  req_addr_reg;
    reg [31:0] req_wdata_reg;
    reg        wait_serve_reg;    // a read was granted: the register file serves it now
    reg        wait_data_reg;     // a read was served: rdata is valid now
    reg        read_half_reg;

    wire cs_active  = !cs_n_sync_reg[1];
    wire cs_before  = !cs_n_sync_reg[2];
    wire rd_low     = !rd_n_sync_reg[1];
    wire write_end  = wr_n_sync_reg[1] && !wr_n_sync_reg[2] && cs_before;
    wire read_start = rd_low && rd_n_sync_reg[2] && cs_active;
    wire busy       = req_reg || wait_serve_reg || wait_data_reg;
    wire [6:0] reg_addr = addr_reg[7:1];
    wire       half_hi  = addr_reg[0];
    wire lo_matches = lo_valid_reg && (lo_reg_reg == reg_addr);
    // The latched high half: its copy, or with SOLE_MASTER the read word itself, which
    // stays on bus_rdata until this slave's next read is served (and until then the high
    // half is only ever read from the latch, which that read's data replaces).
    wire [15:0] hi_data = (SOLE_MASTER != 0) ? bus_rdata[31:16] : hi_data_reg;
    wire hi_matches = hi_valid_reg && (hi_reg_reg == reg_addr);

    wire torn_write = write_end && !busy && half_hi && !lo_matches;
    wire overrun    = (write_end || read_start) && busy;

    always @(posedge clk) begin
        cs_n_sync_reg  <= {cs_n_sync_reg[1:0], bus_cs_n};
        adv_n_sync_reg <= {adv_n_sync_reg[0], bus_adv_n};
        rd_n_sync_reg  <= {rd_n_sync_reg[1:0], bus_rd_n};
        wr_n_sync_reg  <= {wr_n_sync_reg[1:0], bus_wr_n};
        ad_meta_reg    <= bus_ad_in;
        ad_sync_reg    <= ad_meta_reg;

        if (cs_active && !adv_n_sync_reg[1]) addr_reg <= ad_sync_reg[7:0];
        if (!wr_n_sync_reg[1]) wdata_reg <= ad_sync_reg;
        if (!rd_low) ad_oe_reg <= 1'b0;

        wait_serve_reg <= 1'b0;
        wait_data_reg  <= wait_serve_reg;
        if (bus_grant) begin
            req_reg        <= 1'b0;
            wait_serve_reg <= !we_reg;
        end
        if (wait_data_reg) begin
            ad_out_reg    <= read_half_reg ? bus_rdata[31:16] : bus_rdata[15:0];
            ad_oe_reg     <= rd_low;
            if (!read_half_reg) begin
                hi_data_reg  <= bus_rdata[31:16];
                hi_reg_reg   <= req_addr_reg;
                hi_valid_reg <= 1'b1;
            end else begin
                hi_valid_reg <= 1'b0;
            end
        end

        if (write_end && !busy) begin
            hi_valid_reg <= 1'b0;
            lo_valid_reg <= !half_hi;
            if (!half_hi) begin
                lo_data_reg <= wdata_reg;
                lo_reg_reg  <= reg_addr;
            end else if (lo_matches) begin
                req_reg       <= 1'b1;
                we_reg        <= 1'b1;
                req_addr_reg  <= reg_addr;
                req_wdata_reg <= {wdata_reg, lo_data_reg};
            end
        end else if (read_start && !busy) begin
            lo_valid_reg <= 1'b0;
            if (half_hi && hi_matches) begin
                ad_out_reg   <= hi_data;
                ad_oe_reg    <= 1'b1;
                hi_valid_reg <= 1'b0;
            end else begin
                req_reg       <= 1'b1;
                we_reg        <= 1'b0;
                req_addr_reg  <= reg_addr;
                read_half_reg <= half_hi;
            end
        end

        if (rst) begin
            cs_n_sync_reg  <= 3'b111;
            adv_n_sync_reg <= 2'b11;
            rd_n_sync_reg  <= 3'b111;
            wr_n_sync_reg  <= 3'b111;
            ad_meta_reg    <= 16'd0;
            ad_sync_reg    <= 16'd0;
            addr_reg       <= 8'd0;
            wdata_reg      <= 16'd0;
            lo_data_reg    <= 16'd0;
            lo_reg_reg     <= 7'd0;
            lo_valid_reg   <= 1'b0;
            hi_data_reg    <= 16'd0;
            hi_reg_reg     <= 7'd0;
            hi_valid_reg   <= 1'b0;
            ad_out_reg     <= 16'd0;
            ad_oe_reg      <= 1'b0;
            req_reg        <= 1'b0;
            we_reg         <= 1'b0;
            req_addr_reg   <= 7'd0;
            req_wdata_reg  <= 32'd0;
            wait_serve_reg <= 1'b0;
            wait_data_reg  <= 1'b0;
            read_half_reg  <= 1'b0;
        end
    end

    assign bus_ad_out = ad_out_reg;
    assign bus_ad_oe  = ad_oe_reg;
    assign bus_req    = req_reg;
    assign bus_we     = we_reg;
    assign bus_addr   = req_addr_reg;
    assign bus_wdata  = (SOLE_MASTER != 0) ? {req_wdata_reg[31:16], lo_data_reg} : req_wdata_reg;
    assign error      = torn_write || overrun;

`ifdef FORMAL
    // A register is written only whole: the write request carries the high half just
    // written and the low half written before it to the same register; the bus is driven
    // only while the (synchronised) read strobe is low; one request at a time; and the
    // high half returned from the latch is the one read with its low half.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(*) assume (!bus_grant || bus_req);
    // SOLE_MASTER: the register bus changes its read word only at the edge ending the cycle
    // that serves this slave's read (wait_serve_reg), as the register file does when this
    // slave is its only master.
    always @(posedge clk) if (f_past_valid && SOLE_MASTER != 0 && !$past(wait_serve_reg))
        assume (bus_rdata == $past(bus_rdata));

    // The word most recently read by a low-half read, as the register bus returned it.
    reg [31:0] f_low_read_word;
    reg [6:0]  f_low_read_reg;
    always @(posedge clk) if (wait_data_reg && !read_half_reg) begin
        f_low_read_word <= bus_rdata;
        f_low_read_reg  <= req_addr_reg;
    end

    // The data of the last low-half write, as the spec's `wdata` (the pins through the
    // synchroniser) held it at that write's strobe end: the low half a register write
    // carries is this, not the slave's own copy of it (a slip in `lo_data` kept the
    // property above it, which compares with that copy).
    reg [15:0] f_lo_word;
    always @(posedge clk) if (write_end && !busy && !half_hi) f_lo_word <= wdata_reg;
    always @(*) if (f_past_valid && lo_valid_reg) assert (lo_data_reg == f_lo_word);

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if (req_reg && we_reg && !$past(req_reg)) begin
            assert ($past(write_end && half_hi && lo_matches && !busy));
            assert (bus_wdata == {$past(wdata_reg), $past(lo_data_reg)} && req_addr_reg == $past(reg_addr));
            assert (bus_wdata == {$past(wdata_reg), $past(f_lo_word)});
        end
        if (ad_oe_reg) assert ($past(rd_low));
        // The write word changes only with the write request that carries it (the low
        // half of a sole master's is its held low half, above): between requests it holds
        // (mutant 107 of the list at dd15ecb cleared a bit of it at a low-half write).
        if (bus_wdata[31:16] != $past(bus_wdata[31:16]) ||
            (SOLE_MASTER == 0 && bus_wdata[15:0] != $past(bus_wdata[15:0])))
            assert (req_reg && we_reg && !$past(req_reg));
        assert (!(req_reg && wait_data_reg) && !(req_reg && wait_serve_reg) && !(wait_serve_reg && wait_data_reg));
        if (wait_data_reg) assert ($past(wait_serve_reg));
        // (With SOLE_MASTER a read's word is on bus_rdata in its wait_data cycle, before the
        // latch's flags take it; no read is started in that cycle: busy.)
        if (hi_valid_reg) assert ((hi_data == f_low_read_word[31:16] || (SOLE_MASTER != 0 && wait_data_reg)) &&
                                  hi_reg_reg == f_low_read_reg);
        if ($rose(ad_oe_reg) && $past(read_start && half_hi && hi_matches && !busy))
            assert (bus_ad_out == f_low_read_word[31:16]);
        // A register request stays up, unchanged, until it is granted (the register bus's
        // handshake): the register file may grant it cycles later (the SPI slave first).
        if ($past(bus_req && !bus_grant))
            assert (bus_req && bus_we == $past(bus_we) && bus_addr == $past(bus_addr) &&
                    (!bus_we || bus_wdata == $past(bus_wdata)));
        // ... and through the cycle after its grant, which the register file's bus stage
        // serves (with no other master it reads the request there instead of a copy).
        if ($past(bus_grant))
            assert (bus_we == $past(bus_we) && bus_addr == $past(bus_addr) && bus_wdata == $past(bus_wdata));
        cover (req_reg && we_reg);
        cover ($rose(ad_oe_reg) && $past(hi_matches));
    end
`endif

endmodule

`default_nettype wire
