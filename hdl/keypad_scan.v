`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/keypad_scan.md
// 4x4 matrix keypad scan with per-key debounce (seed 001's gantry card). One column is
// driven at a time (col_drive one-hot: the board top drives that column low, the others
// released, open drain); the rows are pulled up and read through a two-flip-flop
// synchroniser. A scan step lasts P = max(scan_div, 3) + 1 clocks; at its last clock the
// four keys of the driven column are sampled (a key is closed when its row reads low)
// and the column moves on, so each key is sampled once every F = 4 * P clocks. The step's
// end is decided from scan_div as it was one clock earlier (the spec's register sd), so
// it is a register here: the divider's compare is not in series with the debounce and
// the event logic (it limited the gantry card's clock).
//
// Debounce, per key: the debounced state takes a sample's value after deb_scans + 1
// consecutive samples of that key with that value (a counter of consecutive samples that
// differ from the state; a sample equal to the state clears it). So a contact whose
// edges all lie within deb_scans * F clocks of each other changes the state at most once
// (docs/spec/keypad_scan.md gives the exact bound): bounce never makes two presses.
//
// Events: key_valid pulses for one clock with key_code = 4 * row + column when a key's
// debounced state rises and it is then the only key down (two-key lockout: a matrix
// without diodes shows a ghost key only with three keys down, so a ghost never makes an
// event; key_down, the debounced bitmap, shows ghosts as the matrix reads them).
// Every output is a register: no combinational path from an input to an output.
module keypad_scan #(
    parameter PRE_W = 16,   // scan_div (>= 2)
    parameter DEB_W = 4     // deb_scans and the per-key counters
) (
    input  wire             clk,
    input  wire             rst,
    input  wire [PRE_W-1:0] scan_div,    // a scan step every max(scan_div, 3) + 1 clocks
    input  wire [DEB_W-1:0] deb_scans,   // consecutive samples - 1 to change a key's state
    input  wire [3:0]       row_n,       // row pins, pulled up: low = key to the driven column closed
    output wire [3:0]       col_drive,   // one-hot: the column driven low
    output wire             key_valid,   // one clock per debounced press (lockout above)
    output wire [3:0]       key_code,    // 4 * row + column of the last press event
    output wire [15:0]      key_down     // debounced state, bit 4 * row + column
);

    localparam [PRE_W-1:0] PRE_ONE = {{(PRE_W-1){1'b0}}, 1'b1};
    localparam [PRE_W-1:0] MIN_DIV = PRE_ONE + PRE_ONE + PRE_ONE;   // 3
    localparam [DEB_W-1:0] DEB_ONE = {{(DEB_W-1){1'b0}}, 1'b1};

    reg [3:0]          sync1_reg;
    reg [3:0]          sync2_reg;
    reg [PRE_W-1:0]    div_reg;
    reg                step_end_reg;
    reg [1:0]          col_reg;
    reg [3:0]          col_drive_reg;
    reg [15:0]         down_reg;
    reg [16*DEB_W-1:0] cnt_reg;
    reg                valid_reg;
    reg [3:0]          code_reg;

    // The step's last clock: the sample and the column change. The spec's step_end is
    // div >= sd && div >= 3 with sd the scan_div of the clock before; it is computed a
    // clock ahead from the divider's next value and this clock's scan_div (after a step's
    // end the divider is 0, below the floor of 3).
    wire             step_end = step_end_reg;
    wire [PRE_W-1:0] div_inc  = div_reg + PRE_ONE;
    wire             step_end_next = !step_end_reg && (div_inc >= scan_div) && (div_inc >= MIN_DIV);

    // Per key: the sample (closed = row low) when its column is sampled, the new state
    // and counter.
    reg [15:0]         down_next;
    reg [16*DEB_W-1:0] cnt_next;
    integer k;
    always @(*) begin
        down_next = down_reg;
        cnt_next  = cnt_reg;
        for (k = 0; k < 16; k = k + 1) begin
            if (step_end && col_reg == k[1:0]) begin
                if (!sync2_reg[k / 4] != down_reg[k]) begin
                    if (cnt_reg[k*DEB_W +: DEB_W] >= deb_scans) begin
                        down_next[k]              = !sync2_reg[k / 4];
                        cnt_next[k*DEB_W +: DEB_W] = {DEB_W{1'b0}};
                    end else begin
                        cnt_next[k*DEB_W +: DEB_W] = cnt_reg[k*DEB_W +: DEB_W] + DEB_ONE;
                    end
                end else begin
                    cnt_next[k*DEB_W +: DEB_W] = {DEB_W{1'b0}};
                end
            end
        end
    end

    // An event: a key rose and is the only key down after the update.
    wire [15:0] rise       = down_next & ~down_reg;
    wire        only_one   = (down_next != 16'h0000) && ((down_next & (down_next - 16'h0001)) == 16'h0000);
    wire        event_now  = (rise != 16'h0000) && only_one;
    reg  [3:0]  rise_code;
    integer j;
    always @(*) begin
        rise_code = 4'h0;
        for (j = 0; j < 16; j = j + 1)
            if (down_next[j]) rise_code = j[3:0];
    end

    always @(posedge clk) begin
        sync1_reg <= row_n;
        sync2_reg <= sync1_reg;
        down_reg  <= down_next;
        cnt_reg   <= cnt_next;
        valid_reg <= event_now;
        if (event_now) code_reg <= rise_code;
        step_end_reg <= step_end_next;
        if (step_end) begin
            div_reg       <= {PRE_W{1'b0}};
            col_reg       <= col_reg + 2'd1;
            col_drive_reg <= {col_drive_reg[2:0], col_drive_reg[3]};
        end else begin
            div_reg <= div_inc;
        end
        if (rst) begin
            sync1_reg     <= 4'hf;
            sync2_reg     <= 4'hf;
            div_reg       <= {PRE_W{1'b0}};
            step_end_reg  <= 1'b0;
            col_reg       <= 2'd0;
            col_drive_reg <= 4'b0001;
            down_reg      <= 16'h0000;
            cnt_reg       <= {(16*DEB_W){1'b0}};
            valid_reg     <= 1'b0;
            code_reg      <= 4'h0;
        end
    end

    assign col_drive = col_drive_reg;
    assign key_valid = valid_reg;
    assign key_code  = code_reg;
    assign key_down  = down_reg;

`ifdef FORMAL
    // Port properties, with DEB_W and PRE_W small: one column driven at a time; an event
    // only where a key's debounced state rises and it is the only key down (so a key
    // makes a second event only after its state fell); and the debounce rule itself for
    // one key chosen by the solver, against a ghost history of that key's samples: its
    // state changes to v only after deb_scans + 1 consecutive samples v, and whenever
    // the last deb_scans + 1 samples are all v the state is v. deb_scans is held
    // constant (the spec asks the host to change it only with the keypad idle).
    localparam HIST = 1 << DEB_W;
    reg              f_past_valid;
    reg [HIST-1:0]   f_hist;       // the chosen key's samples, newest in bit 0
    reg [DEB_W:0]    f_seen;       // samples since reset, saturating at HIST
    (* anyconst *) reg [3:0] f_key;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid) assume (deb_scans == $past(deb_scans));

    wire f_sample_now = step_end && col_reg == f_key[1:0];
    wire f_sample     = !sync2_reg[f_key[3:2]];
    wire [DEB_W-1:0] f_cnt = cnt_reg[f_key*DEB_W +: DEB_W];
    wire [DEB_W:0]   f_need = {1'b0, deb_scans} + 1'b1;
    // The last n samples all equal v (n <= f_seen).
    function f_last_all;
        input [HIST-1:0] hist;
        input [DEB_W:0]  n;
        input            v;
        integer i;
        begin
            f_last_all = 1'b1;
            for (i = 0; i < HIST; i = i + 1)
                if (i < n && hist[i] != v) f_last_all = 1'b0;
        end
    endfunction

    // The spec's sd: scan_div one clock late (reset 0); step_end is stated on it.
    reg [PRE_W-1:0] f_sd;
    always @(posedge clk) f_sd <= rst ? {PRE_W{1'b0}} : scan_div;

    always @(posedge clk) begin
        if (f_sample_now) begin
            f_hist <= {f_hist[HIST-2:0], f_sample};
            if (f_seen != HIST) f_seen <= f_seen + 1'b1;
        end
        if (rst) f_seen <= {(DEB_W+1){1'b0}};
    end

    always @(*) if (f_past_valid && !rst) begin
        assert (col_drive == (4'b0001 << col_reg));
        assert (step_end == ((div_reg >= f_sd) && (div_reg >= MIN_DIV)));
        // The counter is the run of trailing samples that differ from the state.
        assert (f_seen <= HIST);
        assert (f_cnt <= f_seen && f_cnt < f_need);
        assert (f_last_all(f_hist, {1'b0, f_cnt}, !down_reg[f_key]));
        if (f_cnt < f_seen) assert (f_hist[f_cnt] == down_reg[f_key]);
        // Whenever the last deb_scans + 1 samples agree, the state is theirs.
        if (f_seen >= f_need && f_last_all(f_hist, f_need, 1'b1)) assert (down_reg[f_key]);
        if (f_seen >= f_need && f_last_all(f_hist, f_need, 1'b0)) assert (!down_reg[f_key]);
        if (f_seen < f_need) assert (!down_reg[f_key]);
        if (key_valid) assert (key_down == (16'h0001 << key_code));
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // A state changes only at its sample, to a value seen deb_scans + 1 times running.
        if (down_reg[f_key] != $past(down_reg[f_key])) begin
            assert ($past(f_sample_now));
            assert (f_seen >= f_need && f_last_all(f_hist, f_need, down_reg[f_key]));
        end
        // An event is a rise of that key's state.
        if (key_valid && key_code == f_key) assert (down_reg[f_key] && !$past(down_reg[f_key]));
        if (down_reg[f_key] && !$past(down_reg[f_key]) && key_down == (16'h0001 << f_key))
            assert (key_valid && key_code == f_key);
        cover (key_valid && key_code == f_key && deb_scans != {DEB_W{1'b0}} && !$past(down_reg[f_key]));
        cover (!down_reg[f_key] && $past(down_reg[f_key]) && deb_scans != {DEB_W{1'b0}});
    end
`endif

endmodule

`default_nettype wire
