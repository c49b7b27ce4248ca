// A small step generator for the cocotb tests (tests/wavecheck/cocotb/). Times in ns.
//
// STEP: STEPS pulses, HIGH_NS high and LOW_NS low each, the first rising edge at START_NS.
// DIR: unknown (x) until START_NS/2, then 0; it changes after every REVERSE_EVERY-th step,
// DIR_HOLD_NS after that step's rising edge (the knob: below a drive's DIR hold time the check
// fails), so the DIR setup before the next step is HIGH_NS + LOW_NS - DIR_HOLD_NS.
// With XZ_AT_NS > 0, DIR is x for XZ_NS from XZ_AT_NS (then back to its value).
// DONE rises one period after the last step (the test waits for it).
`timescale 1ns/1ps
module stepgen_dut #(
    parameter integer STEPS = 40,
    parameter integer REVERSE_EVERY = 10,
    parameter integer START_NS = 1000,
    parameter integer HIGH_NS = 2000,
    parameter integer LOW_NS = 2000,
    parameter integer DIR_HOLD_NS = 1000,
    parameter integer XZ_AT_NS = 0,
    parameter integer XZ_NS = 0
) (
    output reg step,
    output reg dir,
    output reg done
);
  localparam integer PERIOD_NS = HIGH_NS + LOW_NS;
  reg saved;
  integer k;

  initial begin : pulses
    step = 0;
    done = 0;
    #(START_NS);
    repeat (STEPS) begin
      step = 1;
      #(HIGH_NS) step = 0;
      #(LOW_NS);
    end
    #(PERIOD_NS) done = 1;
  end

  initial begin : direction
    dir = 1'bx;
    #(START_NS / 2) dir = 0;
    #(START_NS - START_NS / 2);  // the first rising edge
    for (k = REVERSE_EVERY; k < STEPS; k = k + REVERSE_EVERY) begin
      #((REVERSE_EVERY - 1) * PERIOD_NS + DIR_HOLD_NS) dir = ~dir;
      #(PERIOD_NS - DIR_HOLD_NS);  // the next rising edge
    end
  end

  initial begin : unknown
    if (XZ_AT_NS > 0) begin
      #(XZ_AT_NS) saved = dir;
      dir = 1'bx;
      #(XZ_NS) dir = saved;
    end
  end
endmodule
