`timescale 1ns / 1ps
`default_nettype none
// A simulation model of the ECP5 block RAM DP16KD for the netlist lockstep
// (docs/verification.md), written from Lattice's ECP5 memory usage guide (FPGA-TN-02204):
// Yosys ships DP16KD as a black box only (ecp5/cells_sim.v), so the synthesised ECP5
// netlist cannot be simulated without one. It models the configurations Yosys's
// memory mapping (lattice/brams_map_16kd.v) emits and refuses the others at elaboration:
//   - widths 9, 18 per port (true dual port) or 36 (pseudo dual port: port A writes
//     DI = {DIB, DIA}, port B reads DO = {DOB, DOA}); 1, 2 and 4 are not modelled;
//   - REGMODE "NOREG" (the read data is latched at the clock edge), CSDECODE "0b000",
//     clocks not inverted;
//   - WRITEMODE per port: NORMAL (the writing port's output holds), WRITETHROUGH (shows
//     the new word), READBEFOREWRITE (shows the old one);
//   - byte enables: AD[1:0] at width 18, ADA[3:0] at width 36 (9-bit bytes);
//   - RST clears the output latch, at the edge (RESETMODE "SYNC") or at once ("ASYNC");
//   - INITVAL_00..3F: 16 18-bit words per parameter, word k in bits [20k +: 18].
// Contents are 1024 18-bit words. A read on one port of the word the other port writes
// on the same edge is undefined in the part: the model returns the written word with
// every bit inverted (neither the old nor the new value, so a design that relied on
// either fails lockstep) and prints the first few collisions.
module DP16KD #(
    parameter DATA_WIDTH_A = 18,
    parameter DATA_WIDTH_B = 18,
    parameter REGMODE_A = "NOREG",
    parameter REGMODE_B = "NOREG",
    parameter RESETMODE = "SYNC",
    parameter ASYNC_RESET_RELEASE = "SYNC",
    parameter CSDECODE_A = "0b000",
    parameter CSDECODE_B = "0b000",
    parameter WRITEMODE_A = "NORMAL",
    parameter WRITEMODE_B = "NORMAL",
    parameter DIA17MUX = "DIA17", parameter DIA16MUX = "DIA16", parameter DIA15MUX = "DIA15",
    parameter DIA14MUX = "DIA14", parameter DIA13MUX = "DIA13", parameter DIA12MUX = "DIA12",
    parameter DIA11MUX = "DIA11", parameter DIA10MUX = "DIA10", parameter DIA9MUX = "DIA9",
    parameter DIA8MUX = "DIA8", parameter DIA7MUX = "DIA7", parameter DIA6MUX = "DIA6",
    parameter DIA5MUX = "DIA5", parameter DIA4MUX = "DIA4", parameter DIA3MUX = "DIA3",
    parameter DIA2MUX = "DIA2", parameter DIA1MUX = "DIA1", parameter DIA0MUX = "DIA0",
    parameter ADA13MUX = "ADA13", parameter ADA12MUX = "ADA12", parameter ADA11MUX = "ADA11",
    parameter ADA10MUX = "ADA10", parameter ADA9MUX = "ADA9", parameter ADA8MUX = "ADA8",
    parameter ADA7MUX = "ADA7", parameter ADA6MUX = "ADA6", parameter ADA5MUX = "ADA5",
    parameter ADA4MUX = "ADA4", parameter ADA3MUX = "ADA3", parameter ADA2MUX = "ADA2",
    parameter ADA1MUX = "ADA1", parameter ADA0MUX = "ADA0",
    parameter CEAMUX = "CEA", parameter OCEAMUX = "OCEA", parameter CLKAMUX = "CLKA",
    parameter WEAMUX = "WEA", parameter RSTAMUX = "RSTA",
    parameter CSA2MUX = "CSA2", parameter CSA1MUX = "CSA1", parameter CSA0MUX = "CSA0",
    parameter DOA17MUX = "DOA17", parameter DOA16MUX = "DOA16", parameter DOA15MUX = "DOA15",
    parameter DOA14MUX = "DOA14", parameter DOA13MUX = "DOA13", parameter DOA12MUX = "DOA12",
    parameter DOA11MUX = "DOA11", parameter DOA10MUX = "DOA10", parameter DOA9MUX = "DOA9",
    parameter DOA8MUX = "DOA8", parameter DOA7MUX = "DOA7", parameter DOA6MUX = "DOA6",
    parameter DOA5MUX = "DOA5", parameter DOA4MUX = "DOA4", parameter DOA3MUX = "DOA3",
    parameter DOA2MUX = "DOA2", parameter DOA1MUX = "DOA1", parameter DOA0MUX = "DOA0",
    parameter DIB17MUX = "DIB17", parameter DIB16MUX = "DIB16", parameter DIB15MUX = "DIB15",
    parameter DIB14MUX = "DIB14", parameter DIB13MUX = "DIB13", parameter DIB12MUX = "DIB12",
    parameter DIB11MUX = "DIB11", parameter DIB10MUX = "DIB10", parameter DIB9MUX = "DIB9",
    parameter DIB8MUX = "DIB8", parameter DIB7MUX = "DIB7", parameter DIB6MUX = "DIB6",
    parameter DIB5MUX = "DIB5", parameter DIB4MUX = "DIB4", parameter DIB3MUX = "DIB3",
    parameter DIB2MUX = "DIB2", parameter DIB1MUX = "DIB1", parameter DIB0MUX = "DIB0",
    parameter ADB13MUX = "ADB13", parameter ADB12MUX = "ADB12", parameter ADB11MUX = "ADB11",
    parameter ADB10MUX = "ADB10", parameter ADB9MUX = "ADB9", parameter ADB8MUX = "ADB8",
    parameter ADB7MUX = "ADB7", parameter ADB6MUX = "ADB6", parameter ADB5MUX = "ADB5",
    parameter ADB4MUX = "ADB4", parameter ADB3MUX = "ADB3", parameter ADB2MUX = "ADB2",
    parameter ADB1MUX = "ADB1", parameter ADB0MUX = "ADB0",
    parameter CEBMUX = "CEB", parameter OCEBMUX = "OCEB", parameter CLKBMUX = "CLKB",
    parameter WEBMUX = "WEB", parameter RSTBMUX = "RSTB",
    parameter CSB2MUX = "CSB2", parameter CSB1MUX = "CSB1", parameter CSB0MUX = "CSB0",
    parameter DOB17MUX = "DOB17", parameter DOB16MUX = "DOB16", parameter DOB15MUX = "DOB15",
    parameter DOB14MUX = "DOB14", parameter DOB13MUX = "DOB13", parameter DOB12MUX = "DOB12",
    parameter DOB11MUX = "DOB11", parameter DOB10MUX = "DOB10", parameter DOB9MUX = "DOB9",
    parameter DOB8MUX = "DOB8", parameter DOB7MUX = "DOB7", parameter DOB6MUX = "DOB6",
    parameter DOB5MUX = "DOB5", parameter DOB4MUX = "DOB4", parameter DOB3MUX = "DOB3",
    parameter DOB2MUX = "DOB2", parameter DOB1MUX = "DOB1", parameter DOB0MUX = "DOB0",
    parameter WID = 0,
    parameter GSR = "ENABLED",
    parameter INIT_DATA = "STATIC",
    parameter [319:0] INITVAL_00 = 320'h0, parameter [319:0] INITVAL_01 = 320'h0,
    parameter [319:0] INITVAL_02 = 320'h0, parameter [319:0] INITVAL_03 = 320'h0,
    parameter [319:0] INITVAL_04 = 320'h0, parameter [319:0] INITVAL_05 = 320'h0,
    parameter [319:0] INITVAL_06 = 320'h0, parameter [319:0] INITVAL_07 = 320'h0,
    parameter [319:0] INITVAL_08 = 320'h0, parameter [319:0] INITVAL_09 = 320'h0,
    parameter [319:0] INITVAL_0A = 320'h0, parameter [319:0] INITVAL_0B = 320'h0,
    parameter [319:0] INITVAL_0C = 320'h0, parameter [319:0] INITVAL_0D = 320'h0,
    parameter [319:0] INITVAL_0E = 320'h0, parameter [319:0] INITVAL_0F = 320'h0,
    parameter [319:0] INITVAL_10 = 320'h0, parameter [319:0] INITVAL_11 = 320'h0,
    parameter [319:0] INITVAL_12 = 320'h0, parameter [319:0] INITVAL_13 = 320'h0,
    parameter [319:0] INITVAL_14 = 320'h0, parameter [319:0] INITVAL_15 = 320'h0,
    parameter [319:0] INITVAL_16 = 320'h0, parameter [319:0] INITVAL_17 = 320'h0,
    parameter [319:0] INITVAL_18 = 320'h0, parameter [319:0] INITVAL_19 = 320'h0,
    parameter [319:0] INITVAL_1A = 320'h0, parameter [319:0] INITVAL_1B = 320'h0,
    parameter [319:0] INITVAL_1C = 320'h0, parameter [319:0] INITVAL_1D = 320'h0,
    parameter [319:0] INITVAL_1E = 320'h0, parameter [319:0] INITVAL_1F = 320'h0,
    parameter [319:0] INITVAL_20 = 320'h0, parameter [319:0] INITVAL_21 = 320'h0,
    parameter [319:0] INITVAL_22 = 320'h0, parameter [319:0] INITVAL_23 = 320'h0,
    parameter [319:0] INITVAL_24 = 320'h0, parameter [319:0] INITVAL_25 = 320'h0,
    parameter [319:0] INITVAL_26 = 320'h0, parameter [319:0] INITVAL_27 = 320'h0,
    parameter [319:0] INITVAL_28 = 320'h0, parameter [319:0] INITVAL_29 = 320'h0,
    parameter [319:0] INITVAL_2A = 320'h0, parameter [319:0] INITVAL_2B = 320'h0,
    parameter [319:0] INITVAL_2C = 320'h0, parameter [319:0] INITVAL_2D = 320'h0,
    parameter [319:0] INITVAL_2E = 320'h0, parameter [319:0] INITVAL_2F = 320'h0,
    parameter [319:0] INITVAL_30 = 320'h0, parameter [319:0] INITVAL_31 = 320'h0,
    parameter [319:0] INITVAL_32 = 320'h0, parameter [319:0] INITVAL_33 = 320'h0,
    parameter [319:0] INITVAL_34 = 320'h0, parameter [319:0] INITVAL_35 = 320'h0,
    parameter [319:0] INITVAL_36 = 320'h0, parameter [319:0] INITVAL_37 = 320'h0,
    parameter [319:0] INITVAL_38 = 320'h0, parameter [319:0] INITVAL_39 = 320'h0,
    parameter [319:0] INITVAL_3A = 320'h0, parameter [319:0] INITVAL_3B = 320'h0,
    parameter [319:0] INITVAL_3C = 320'h0, parameter [319:0] INITVAL_3D = 320'h0,
    parameter [319:0] INITVAL_3E = 320'h0, parameter [319:0] INITVAL_3F = 320'h0
) (
    input  wire DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6,
                DIA5, DIA4, DIA3, DIA2, DIA1, DIA0,
    input  wire ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2,
                ADA1, ADA0,
    input  wire CEA, OCEA, CLKA, WEA, RSTA,
    input  wire CSA2, CSA1, CSA0,
    output wire DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6,
                DOA5, DOA4, DOA3, DOA2, DOA1, DOA0,
    input  wire DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6,
                DIB5, DIB4, DIB3, DIB2, DIB1, DIB0,
    input  wire ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2,
                ADB1, ADB0,
    input  wire CEB, OCEB, CLKB, WEB, RSTB,
    input  wire CSB2, CSB1, CSB0,
    output wire DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6,
                DOB5, DOB4, DOB3, DOB2, DOB1, DOB0
);

    localparam WORDS = 1024;         // 18-bit words
    localparam MAX_COLLISIONS_SHOWN = 8;

    // Configurations outside the model stop the elaboration (no silent approximation).
    localparam PDP = (DATA_WIDTH_A == 36) || (DATA_WIDTH_B == 36);
    localparam SUPPORTED =
        (PDP ? (DATA_WIDTH_A == 36 && DATA_WIDTH_B == 36)
             : ((DATA_WIDTH_A == 9 || DATA_WIDTH_A == 18) && (DATA_WIDTH_B == 9 || DATA_WIDTH_B == 18)))
        && REGMODE_A == "NOREG" && REGMODE_B == "NOREG"
        && CSDECODE_A == "0b000" && CSDECODE_B == "0b000"
        && CLKAMUX == "CLKA" && CLKBMUX == "CLKB"
        && (RESETMODE == "SYNC" || RESETMODE == "ASYNC");
    generate
        if (!SUPPORTED) begin : unsupported
            initial $fatal(1, "DP16KD model: configuration not modelled (widths %0d/%0d, see sim/netlist/ecp5_dp16kd.v)",
                           DATA_WIDTH_A, DATA_WIDTH_B);
        end
    endgenerate

    wire [13:0] ada = {ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0};
    wire [13:0] adb = {ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0};
    wire [17:0] dia = {DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6,
                       DIA5, DIA4, DIA3, DIA2, DIA1, DIA0};
    wire [17:0] dib = {DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6,
                       DIB5, DIB4, DIB3, DIB2, DIB1, DIB0};
    wire sel_a = CEA && ({CSA2, CSA1, CSA0} == 3'b000);
    wire sel_b = CEB && ({CSB2, CSB1, CSB0} == 3'b000);

    reg [17:0] mem [0:WORDS-1];
    reg [17:0] doa_reg, dob_reg;
    integer collisions;

    // INITVAL_nn holds words 16*nn .. 16*nn + 15.
    function [319:0] initval;
        input integer n;
        begin
            case (n)
                'h00: initval = INITVAL_00; 'h01: initval = INITVAL_01; 'h02: initval = INITVAL_02; 'h03: initval = INITVAL_03;
                'h04: initval = INITVAL_04; 'h05: initval = INITVAL_05; 'h06: initval = INITVAL_06; 'h07: initval = INITVAL_07;
                'h08: initval = INITVAL_08; 'h09: initval = INITVAL_09; 'h0A: initval = INITVAL_0A; 'h0B: initval = INITVAL_0B;
                'h0C: initval = INITVAL_0C; 'h0D: initval = INITVAL_0D; 'h0E: initval = INITVAL_0E; 'h0F: initval = INITVAL_0F;
                'h10: initval = INITVAL_10; 'h11: initval = INITVAL_11; 'h12: initval = INITVAL_12; 'h13: initval = INITVAL_13;
                'h14: initval = INITVAL_14; 'h15: initval = INITVAL_15; 'h16: initval = INITVAL_16; 'h17: initval = INITVAL_17;
                'h18: initval = INITVAL_18; 'h19: initval = INITVAL_19; 'h1A: initval = INITVAL_1A; 'h1B: initval = INITVAL_1B;
                'h1C: initval = INITVAL_1C; 'h1D: initval = INITVAL_1D; 'h1E: initval = INITVAL_1E; 'h1F: initval = INITVAL_1F;
                'h20: initval = INITVAL_20; 'h21: initval = INITVAL_21; 'h22: initval = INITVAL_22; 'h23: initval = INITVAL_23;
                'h24: initval = INITVAL_24; 'h25: initval = INITVAL_25; 'h26: initval = INITVAL_26; 'h27: initval = INITVAL_27;
                'h28: initval = INITVAL_28; 'h29: initval = INITVAL_29; 'h2A: initval = INITVAL_2A; 'h2B: initval = INITVAL_2B;
                'h2C: initval = INITVAL_2C; 'h2D: initval = INITVAL_2D; 'h2E: initval = INITVAL_2E; 'h2F: initval = INITVAL_2F;
                'h30: initval = INITVAL_30; 'h31: initval = INITVAL_31; 'h32: initval = INITVAL_32; 'h33: initval = INITVAL_33;
                'h34: initval = INITVAL_34; 'h35: initval = INITVAL_35; 'h36: initval = INITVAL_36; 'h37: initval = INITVAL_37;
                'h38: initval = INITVAL_38; 'h39: initval = INITVAL_39; 'h3A: initval = INITVAL_3A; 'h3B: initval = INITVAL_3B;
                'h3C: initval = INITVAL_3C; 'h3D: initval = INITVAL_3D; 'h3E: initval = INITVAL_3E; default: initval = INITVAL_3F;
            endcase
        end
    endfunction

    integer i;
    reg [319:0] init_row;
    initial begin
        for (i = 0; i < WORDS; i = i + 1) begin
            init_row = initval(i / 16);
            mem[i] = init_row[(i % 16) * 20 +: 18];
        end
        doa_reg = 18'd0;
        dob_reg = 18'd0;
        collisions = 0;
    end

    // Port addresses as 18-bit words: width 18 and 9 address AD[13:4] (AD[3] picks the
    // byte at width 9), width 36 addresses word pairs AD[13:5] (low half at the even word).
    wire [9:0] word_a  = PDP ? {ada[13:5], 1'b0} : ada[13:4];
    wire [9:0] word_b  = PDP ? {adb[13:5], 1'b0} : adb[13:4];
    wire       byte_a  = ada[3];
    wire       byte_b  = adb[3];
    // Byte enables {high word high, high word low, low word high, low word low}.
    wire [3:0] be_a = PDP ? ada[3:0]
                    : (DATA_WIDTH_A == 18) ? {2'b00, ada[1:0]}
                    : {2'b00, byte_a, !byte_a};
    wire [1:0] be_b = (DATA_WIDTH_B == 18) ? adb[1:0] : {byte_b, !byte_b};
    wire write_a = sel_a && WEA && (be_a != 4'd0);
    wire write_b = !PDP && sel_b && WEB && (be_b != 2'd0);
    wire read_b  = sel_b && (PDP || !WEB);
    wire read_a  = !PDP && sel_a && !WEA;

    // The new contents of one 18-bit word under byte enables.
    function [17:0] merge;
        input [17:0] old_word, new_word;
        input [1:0]  be;
        begin
            merge = {be[1] ? new_word[17:9] : old_word[17:9], be[0] ? new_word[8:0] : old_word[8:0]};
        end
    endfunction

    // Port A's write data as 18-bit words, with width 9 on both bytes.
    wire [17:0] wa_lo = (DATA_WIDTH_A == 9) ? {dia[8:0], dia[8:0]} : dia;
    wire [17:0] wb_lo = (DATA_WIDTH_B == 9) ? {dib[8:0], dib[8:0]} : dib;

    // Output at width 9: the addressed byte on DO[8:0].
    function [17:0] narrow;
        input [17:0] word;
        input        hi;
        input integer width;
        begin
            narrow = (width == 9) ? {9'd0, hi ? word[17:9] : word[8:0]} : word;
        end
    endfunction

    wire collide_b = write_a && read_b && (word_a == word_b);
    wire collide_a = write_b && read_a && (word_a == word_b);

    // RESETMODE "ASYNC": RST clears the output latch at once; "SYNC": at the edge.
    wire reset_now = (RESETMODE == "ASYNC") && (RSTA || RSTB);
    wire reset_a   = (RESETMODE == "SYNC") && RSTA;
    wire reset_b   = (RESETMODE == "SYNC") && RSTB;

    // Both ports on one clock: the model runs port B on CLKA's edges and stops if CLKB
    // rises without CLKA (a netlist with two clocks on one block RAM is not modelled).
    always @(posedge CLKB)
        if (!CLKA) $fatal(1, "DP16KD model %m: CLKB is not CLKA (two clocks are not modelled)");

    generate
        if (SUPPORTED) begin : model
            always @(posedge CLKA or posedge reset_now) begin
                if (reset_now) begin
                    if (RSTA) doa_reg <= 18'd0;
                    if (RSTB) dob_reg <= 18'd0;
                end else begin
                    if (PDP) begin
                        if (write_a) begin
                            mem[word_a]     <= merge(mem[word_a], dia, be_a[1:0]);
                            mem[word_a + 1] <= merge(mem[word_a + 1], dib, be_a[3:2]);
                        end
                        if (reset_b) begin
                            doa_reg <= 18'd0;
                            dob_reg <= 18'd0;
                        end else if (read_b) begin
                            doa_reg <= collide_b ? ~dia : mem[word_b];
                            dob_reg <= collide_b ? ~dib : mem[word_b + 1];
                        end
                    end else begin
                        if (write_a) mem[word_a] <= merge(mem[word_a], wa_lo, be_a[1:0]);
                        if (write_b) mem[word_b] <= merge(mem[word_b], wb_lo, be_b);
                        if (reset_a) doa_reg <= 18'd0;
                        else if (read_a) doa_reg <= collide_a ? ~wb_lo : narrow(mem[word_a], byte_a, DATA_WIDTH_A);
                        else if (write_a && WRITEMODE_A == "WRITETHROUGH")
                            doa_reg <= narrow(merge(mem[word_a], wa_lo, be_a[1:0]), byte_a, DATA_WIDTH_A);
                        else if (write_a && WRITEMODE_A == "READBEFOREWRITE")
                            doa_reg <= narrow(mem[word_a], byte_a, DATA_WIDTH_A);
                        if (reset_b) dob_reg <= 18'd0;
                        else if (read_b) dob_reg <= collide_b ? ~wa_lo : narrow(mem[word_b], byte_b, DATA_WIDTH_B);
                        else if (write_b && WRITEMODE_B == "WRITETHROUGH")
                            dob_reg <= narrow(merge(mem[word_b], wb_lo, be_b), byte_b, DATA_WIDTH_B);
                        else if (write_b && WRITEMODE_B == "READBEFOREWRITE")
                            dob_reg <= narrow(mem[word_b], byte_b, DATA_WIDTH_B);
                    end
                    if ((collide_a || collide_b) && collisions < MAX_COLLISIONS_SHOWN) begin
                        collisions <= collisions + 1;
                        $display("DP16KD %m: read and write of word %0d on one edge (undefined in the part)", word_a);
                    end
                end
            end
        end
    endgenerate

    assign {DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6,
            DOA5, DOA4, DOA3, DOA2, DOA1, DOA0} = doa_reg;
    assign {DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6,
            DOB5, DOB4, DOB3, DOB2, DOB1, DOB0} = dob_reg;

endmodule

`default_nettype wire
