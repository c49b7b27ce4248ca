// The testbench of issue 26 (tests/wavecheck/roles/test_which_line.py): a 50 MHz clock `clk`
// and a step generator clocked by it, whose outputs `step` and `dir` change on its rising edge;
// with -DNEUTRAL the outputs are called `s` and `d`. Two moves, one each way: the step period
// shrinks by an eighth a step from 100 us to 10 us, runs, and grows back; 2 us pulses; DIR
// changes 10 us before the second move.
`timescale 1ns/1ps
module tb;
  reg clk = 0, rst = 1;
`ifdef NEUTRAL
  reg s = 0, d = 0;
`define STEP s
`define DIR d
`else
  reg step = 0, dir = 0;
`define STEP step
`define DIR dir
`endif
  integer per, k, move, i;
  always #10 clk = ~clk;
  initial begin
    $dumpfile(`DUMPFILE);
    $dumpvars(0, tb);
    repeat (5) @(posedge clk);
    rst = 0;
    for (move = 0; move < 2; move = move + 1) begin
      per = 5000;
      for (k = 0; k < 60; k = k + 1) begin
        `STEP = 1;
        repeat (100) @(posedge clk);
        `STEP = 0;
        repeat (per - 100) @(posedge clk);
        if (k < 25 && per > 500) per = per - per / 8;
        if (k >= 40) per = per + per / 8;
      end
      repeat (5000) @(posedge clk);
      `DIR = ~`DIR;
      repeat (500) @(posedge clk);
    end
    $finish;
  end
endmodule
