// A gate-level netlist of a PWM controller and its testbench, for the role-inference tests
// (tests/wavecheck/roles/test_hdl.py): what a synthesis tool writes and a gate-level simulation
// dumps. A 100 MHz clock; a 4-bit counter (flip-flops U1..U4 with their next-state nets); a
// two-bit state machine (IDLE, RAMP_UP, HOLD, RAMP_DOWN: nets st0/st1 and their next-state
// nets) that steps a 4-bit duty register (U9..U12) inc and dec every 16 PWM periods; a
// comparator (counter < duty) drives pwm_out. Gates have 1 ns delays, so nets glitch as in a
// timing simulation. None of these lines is a step signal.
`timescale 1ns/1ps

module dff (output reg q, input d, input clk, input rst);
  always @(posedge clk or posedge rst) q <= rst ? 1'b0 : d;
endmodule

module pwm_gates (input clk, input rst, output pwm_out);
  wire c0, c1, c2, c3, n_c0, n_c1, n_c2, n_c3, t1, t2, t3, wrap;
  // counter: c <= c + 1
  not #1 U5 (n_c0, c0);
  xor #1 U6 (n_c1, c1, c0);
  and #1 U7 (t1, c1, c0);
  xor #1 U8 (n_c2, c2, t1);
  and #1 U13 (t2, c2, t1);
  xor #1 U14 (n_c3, c3, t2);
  and #1 U15 (wrap, c3, t2);
  dff U1 (c0, n_c0, clk, rst);
  dff U2 (c1, n_c1, clk, rst);
  dff U3 (c2, n_c2, clk, rst);
  dff U4 (c3, n_c3, clk, rst);
  // a 4-bit prescaler of PWM periods: tick every 16 wraps
  wire p0, p1, p2, p3, n_p0, n_p1, n_p2, n_p3, u1, u2, u3, tick;
  xor #1 U16 (n_p0, p0, wrap);
  and #1 U17 (u1, p0, wrap);
  xor #1 U18 (n_p1, p1, u1);
  and #1 U19 (u2, p1, u1);
  xor #1 U20 (n_p2, p2, u2);
  and #1 U21 (u3, p2, u2);
  xor #1 U22 (n_p3, p3, u3);
  and #1 U23 (tick, p3, u3);
  dff U24 (p0, n_p0, clk, rst);
  dff U25 (p1, n_p1, clk, rst);
  dff U26 (p2, n_p2, clk, rst);
  dff U27 (p3, n_p3, clk, rst);
  // state machine: 00 IDLE -> 01 RAMP_UP -> 10 HOLD -> 11 RAMP_DOWN -> 00, on tick when the
  // duty reaches its end (all ones going inc, all zeros going dec; HOLD and IDLE: one tick)
  wire st0, st1, n_st0, n_st1, d0, d1, d2, d3, full, empty, adv, inc, dec;
  and #1 U28 (full, d0, d1, d2, d3);
  nor #1 U29 (empty, d0, d1, d2, d3);
  wire is_up, is_down, go_up, go_down, n_st1_a, ns0, ns1;
  and #1 U30 (is_up, st0, ~st1);
  and #1 U31 (is_down, st0, st1);
  and #1 U32 (go_up, is_up, full);
  and #1 U33 (go_down, is_down, empty);
  wire hold_or_idle, fsm_adv;
  xnor #1 U34 (hold_or_idle, st0, 1'b0);
  or #1 U35 (fsm_adv, go_up, go_down, ~st0);
  and #1 U36 (adv, tick, fsm_adv);
  xor #1 U37 (ns0, st0, adv);
  and #1 U38 (n_st1_a, st0, adv);
  xor #1 U39 (ns1, st1, n_st1_a);
  dff U40 (st0, ns0, clk, rst);
  dff U41 (st1, ns1, clk, rst);
  and #1 U42 (inc, tick, is_up, ~full);
  and #1 U43 (dec, tick, is_down, ~empty);
  // duty register: d <= d + inc - dec
  wire [3:0] d = {d3, d2, d1, d0};
  wire [3:0] nd = inc ? d + 4'd1 : dec ? d - 4'd1 : d;
  dff U9 (d0, nd[0], clk, rst);
  dff U10 (d1, nd[1], clk, rst);
  dff U11 (d2, nd[2], clk, rst);
  dff U12 (d3, nd[3], clk, rst);
  // comparator: pwm_out = counter < duty
  wire [3:0] c = {c3, c2, c1, c0};
  wire lt = c < d;
  buf #1 U44 (pwm_out, lt);
endmodule

module tb;
  reg clk = 0, rst = 1;
  always #5 clk = ~clk;  // 100 MHz
  wire pwm_out;
  pwm_gates dut (clk, rst, pwm_out);
  initial begin
    $dumpfile(`DUMPFILE);
    $dumpvars(0, tb);
    #23 rst = 0;
    #400000 $finish;
  end
endmodule
