// Simulated lines for the role-inference tests (tests/wavecheck/roles/test_simulated.py): each
// testbench, chosen with -DTB_<NAME>, drives the lines of one kind of design and dumps them to
// `DUMPFILE. Times in ns; a 1 MHz clock `clk` runs in every design, and every line changes on
// one of its rising edges, as in a synchronous design.
`timescale 1ns/1ps

module clocked;
  reg clk = 0;
  always #500 clk = ~clk;
  task cycles(input integer n);
    begin
      repeat (n) @(posedge clk);
    end
  endtask
endmodule

`ifdef TB_BUSES
// Lines of other kinds, none a step signal: a UART at 9600 baud (tx), a bit-banged I2C bus
// (scl, sda) with its lines changing on the clock, a PWM whose duty sweeps (pwm) and one at a
// fixed duty (pwm_fixed), bursts of a clock (gclk) while an enable (gen) is high, and pulses
// at one constant rate through the whole run (q).
module tb;
  clocked c();
  reg tx = 1, scl = 1, sda = 1, pwm = 0, pwm_fixed = 0, gclk = 0, gen = 0, q = 0;
  reg [15:0] lfsr = 16'hBEEF;
  integer i, b;
  task next;
    lfsr = {lfsr[14:0], lfsr[15] ^ lfsr[13] ^ lfsr[12] ^ lfsr[10]};
  endtask
  initial begin : uart
    c.cycles(100);
    forever begin
      next;
      tx = 0;
      c.cycles(104);
      for (b = 0; b < 8; b = b + 1) begin
        tx = lfsr[b];
        c.cycles(104);
      end
      tx = 1;
      c.cycles(104 + 25 * lfsr[3:0]);
    end
  end
  initial begin : i2c
    integer k, j;
    reg [7:0] data;
    c.cycles(300);
    forever begin
      sda = 0;  // START
      c.cycles(10);
      for (k = 0; k < 3; k = k + 1) begin
        data = lfsr[15:8] ^ k;
        for (j = 0; j < 9; j = j + 1) begin
          scl = 0;
          c.cycles(2);
          sda = j < 8 ? data[7 - j] : 0;
          c.cycles(8);
          scl = 1;
          c.cycles(10);
        end
      end
      scl = 0;
      c.cycles(2);
      sda = 0;
      c.cycles(8);
      scl = 1;
      c.cycles(5);
      sda = 1;  // STOP
      c.cycles(2000 + 100 * lfsr[5:0]);
    end
  end
  initial begin : pwms
    integer t;
    t = 0;
    forever begin
      pwm = 1;
      c.cycles(10 + (t % 160) / 2);
      pwm = 0;
      c.cycles(90 - (t % 160) / 2);
      t = t + 1;
    end
  end
  initial forever begin
    pwm_fixed = 1;
    c.cycles(24);
    pwm_fixed = 0;
    c.cycles(56);
  end
  initial begin : bursts
    integer k;
    c.cycles(700);
    forever begin
      gen = 1;
      c.cycles(3);
      for (k = 0; k < 16; k = k + 1) begin
        gclk = 1;
        c.cycles(2);
        gclk = 0;
        c.cycles(2);
      end
      c.cycles(3);
      gen = 0;
      c.cycles(500 + 40 * lfsr[7:2]);
    end
  end
  initial begin
    c.cycles(37);
    forever begin
      q = 1;
      c.cycles(3);
      q = 0;
      c.cycles(397);
    end
  end
  initial begin
    $dumpfile(`DUMPFILE);
    $dumpvars(0, c.clk, tx, scl, sda, pwm, pwm_fixed, gclk, gen, q);
    c.cycles(50000);
    $finish;
  end
endmodule
`else
// A step generator: trapezoid moves (steps/s grows as the square root of the steps taken, up to
// a top rate), 2 us pulses, DIR set 5 us before the first pulse of a move, ENABLE on during the
// moves. The lines have neutral names in a shuffled order: n0 DIR, n1 STEP, n2 ENABLE; with
// -DWITH_SPI an SPI bus (sck, mosi, cs_n) configures a driver between the moves.
module tb;
  clocked c();
  reg n0 = 0, n1 = 0, n2 = 1;
  reg sck = 0, mosi = 0, cs_n = 1;
  reg [15:0] lfsr = 16'hACE1;
  integer k;
  task move(input integer n, input integer d, input real top, input real accel);
    real v, p;
    integer i;
    begin
      n0 = d;
      c.cycles(5);  // DIR setup 5 us
      for (i = 0; i < n; i = i + 1) begin
        v = $sqrt(2.0 * accel * (i + 1));
        if ($sqrt(2.0 * accel * (n - i)) < v) v = $sqrt(2.0 * accel * (n - i));
        if (v > top) v = top;
        p = 1.0e6 / v;
        n1 = 1;
        c.cycles(2);
        n1 = 0;
        c.cycles($rtoi(p) - 2);
      end
    end
  endtask
  task spi_byte;
    integer b;
    begin
      cs_n = 0;
      c.cycles(2);
      for (b = 0; b < 8; b = b + 1) begin
        lfsr = {lfsr[14:0], lfsr[15] ^ lfsr[13] ^ lfsr[12] ^ lfsr[10]};
        mosi = lfsr[0];
        c.cycles(1);
        sck = 1;
        c.cycles(1);
        sck = 0;
      end
      c.cycles(2);
      cs_n = 1;
      c.cycles(10);
    end
  endtask
  initial begin
    $dumpfile(`DUMPFILE);
`ifdef WITH_SPI
    $dumpvars(0, c.clk, n0, n1, n2, sck, mosi, cs_n);
`else
    $dumpvars(0, c.clk, n0, n1, n2);
`endif
    c.cycles(500);
    for (k = 0; k < 4; k = k + 1) begin
`ifdef WITH_SPI
      repeat (12) spi_byte;
`endif
      n2 = 0;  // ENABLE (active low) on
      c.cycles(20);
      move(40 + 37 * k, k % 2, 4000.0 + 1500.0 * k, 2.0e5);
      c.cycles(40);
      n2 = 1;
      c.cycles(400);
    end
    $finish;
  end
endmodule
`endif
