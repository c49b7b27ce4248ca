// A parallel-port FPGA step generator and its testbench, for the role-inference tests
// (tests/wavecheck/roles/test_hdl.py). After the idea of LinuxCNC's Pluto-P: the host writes each
// axis's velocity over an EPP port (nAddrStr / nDataStr strobes, nWait handshake, 8-bit data
// pd); per axis a DDS accumulator makes STEP pulses of a fixed width, DIR follows the sign with a
// setup time; an LED blinks from a free-running counter. The testbench dumps its whole hierarchy
// (`$dumpvars(0, tb)`): the EPP lines, the data bus, the host's loop variables, the design's
// registers and its outputs. Only tb.dut.step0/dir0 and tb.dut.step1/dir1 are step signals.
// With -DEPP_DATA_ONLY the host writes the address once, then only data: nDataStr and nWait then
// walk quadrature in bursts (a four-phase handshake is a Gray-code walk).
`timescale 1ns/1ps

module pport_stepgen (
    input clk,
    input nWrite,
    input nDataStr,
    input nAddrStr,
    output reg nWait,
    input [7:0] pd,
    output reg step0,
    output reg dir0,
    output reg step1,
    output reg dir1,
    output led
);
  reg [1:0] ds_sync = 2'b11, as_sync = 2'b11;
  reg [2:0] addr = 0;
  reg signed [15:0] vel0 = 0, vel1 = 0;
  reg [20:0] acc0 = 0, acc1 = 0;
  reg [7:0] hold0 = 0, hold1 = 0;  // step width, then DIR setup/hold counters
  reg [19:0] blink = 0;
  wire [15:0] mag0 = vel0[15] ? -vel0 : vel0;  // |velocity|, in 16 bits
  wire [15:0] mag1 = vel1[15] ? -vel1 : vel1;
  assign led = blink[17];
  initial begin
    nWait = 0; step0 = 0; dir0 = 0; step1 = 0; dir1 = 0;
  end
  always @(posedge clk) begin
    blink <= blink + 1;
    ds_sync <= {ds_sync[0], nDataStr};
    as_sync <= {as_sync[0], nAddrStr};
    // EPP: answer a strobe with nWait high, drop it when the strobe ends
    if (!nWrite && as_sync == 2'b00 && !nWait) begin
      addr <= pd[2:0];
      nWait <= 1;
    end else if (!nWrite && ds_sync == 2'b00 && !nWait) begin
      case (addr[1:0])
        0: vel0[7:0] <= pd;
        1: vel0[15:8] <= pd;
        2: vel1[7:0] <= pd;
        3: vel1[15:8] <= pd;
      endcase
      addr <= addr + 1;
      nWait <= 1;
    end else if (ds_sync == 2'b11 && as_sync == 2'b11) nWait <= 0;
  end
  // one DDS per axis: a step when the accumulator carries, 160 clocks wide (8 us); DIR changes
  // only after a pulse has ended, and the next step waits 80 clocks (4 us of DIR setup)
  always @(posedge clk) begin
    if (hold0 != 0) begin
      hold0 <= hold0 - 1;
      if (hold0 == 1) step0 <= 0;
    end else if (dir0 != vel0[15] && vel0 != 0) begin
      dir0 <= vel0[15];
      hold0 <= 80;
    end else begin
      {step0, acc0} <= {1'b0, acc0} + mag0;
      if (({1'b0, acc0} + mag0) >> 21) hold0 <= 160;
    end
  end
  always @(posedge clk) begin
    if (hold1 != 0) begin
      hold1 <= hold1 - 1;
      if (hold1 == 1) step1 <= 0;
    end else if (dir1 != vel1[15] && vel1 != 0) begin
      dir1 <= vel1[15];
      hold1 <= 80;
    end else begin
      {step1, acc1} <= {1'b0, acc1} + mag1;
      if (({1'b0, acc1} + mag1) >> 21) hold1 <= 160;
    end
  end
endmodule

module tb;
  reg clk = 0;
  always #25 clk = ~clk;  // 20 MHz
  reg nWrite = 1, nDataStr = 1, nAddrStr = 1;
  reg [7:0] pd = 8'hzz;
  wire nWait, step0, dir0, step1, dir1, led;
  pport_stepgen dut (clk, nWrite, nDataStr, nAddrStr, nWait, pd, step0, dir0, step1, dir1, led);
  integer period, k;
  integer v0, v1;
  task epp(input is_addr, input [7:0] value);
    begin
      nWrite = 0;
      pd = value;
      #150;
      if (is_addr) nAddrStr = 0; else nDataStr = 0;
      wait (nWait);
      #200;
      if (is_addr) nAddrStr = 1; else nDataStr = 1;
      wait (!nWait);
      #100;
      nWrite = 1;
      pd = 8'hzz;
      #300;
    end
  endtask
  initial begin
    $dumpfile(`DUMPFILE);
    $dumpvars(0, tb);
    #2000;
    // a servo period of 125 us: the host writes both velocities; axis 0 speeds up, runs,
    // reverses and stops, axis 1 moves one way and back more slowly
    for (period = 0; period < 72; period = period + 1) begin
      v0 = period < 16 ? period * 120 : period < 30 ? 1920 : period < 46 ? 1920 - (period - 30) * 220
           : period < 60 ? -1600 : period < 68 ? -1600 + (period - 60) * 200 : 0;
      v1 = period < 10 ? 0 : period < 30 ? (period - 10) * 60 : period < 40 ? 1200
           : period < 60 ? 1200 - (period - 40) * 110 : period < 66 ? -1000 : 0;
`ifdef EPP_DATA_ONLY
      if (period == 0) epp(1, 0);  // the address once: it then runs round the four registers
`else
      epp(1, 0);
`endif
      epp(0, v0[7:0]);
      epp(0, v0[15:8]);
      epp(0, v1[7:0]);
      epp(0, v1[15:8]);
      #(125000 - 5 * 1600);
    end
    $finish;
  end
endmodule
