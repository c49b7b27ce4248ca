// A small step generator for the simulator-format tests (tests/wavecheck/capture/test_simulators.py).
// Times in ns; `TIMESCALE_PRECISION is substituted by the test. Against a DRV8825 (1.9 us pulses,
// 650 ns DIR setup/hold): pulse 5 is 1.8 us high (step_high fails), DIR changes 500 ns before
// pulse 10 (dir_setup fails), DIR is unknown (x) for 1 us from 500 ns after pulse 14 ends.
`timescale 1ns/TIMESCALE_PRECISION
module gen(output reg step, output reg dir, output [1:0] stout);
  integer i;
  assign stout = {dir, step};
  initial begin
    step = 0;
    dir = 1'bx;
    #1000 dir = 0;
    for (i = 0; i < 20; i = i + 1) begin
      if (i == 10) begin #1500 dir = 1; #500; end else #2000;
      step = 1;
      if (i == 5) #1800; else #2000;
      step = 0;
      if (i == 14) begin #500 dir = 1'bx; #1000 dir = 1; end
    end
    #3000 $finish;
  end
endmodule

module tb;
  wire step, dir;
  wire [1:0] stout;
  reg spare;  // x throughout
  gen dut(.step(step), .dir(dir), .stout(stout));
  initial begin
    spare = 1'bx;
    $dumpfile(`DUMPFILE);
    $dumpvars(0, tb);
  end
endmodule
