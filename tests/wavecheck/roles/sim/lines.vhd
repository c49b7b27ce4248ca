-- A step generator for the role-inference tests (tests/wavecheck/roles/test_simulated.py), run
-- by GHDL: trapezoid moves (steps/s grows as the square root of the steps taken, up to a top
-- rate) on a 1 MHz clock, 3 us pulses, DIR set 4 us before a move, ENABLE (active high) on
-- during the moves, and a UART at 19200 baud sending between them. Neutral names in a shuffled
-- order: l0 UART, l1 STEP, l2 clock, l3 ENABLE, l4 DIR.
library ieee;
use ieee.math_real.all;

entity tb is
end entity;

architecture sim of tb is
  signal l0 : bit := '1';
  signal l1, l2, l3, l4 : bit := '0';
begin
  l2 <= not l2 after 500 ns;

  steps : process
    variable v, p : real;
    variable n : integer;
  begin
    wait for 20 us;
    for k in 0 to 4 loop
      n := 30 + 25 * k;
      l3 <= '1';
      wait for 50 us;
      if k mod 2 = 1 then l4 <= '1'; else l4 <= '0'; end if;
      wait for 4 us;
      for i in 0 to n - 1 loop
        v := sqrt(2.0 * 1.5e5 * real(i + 1));
        if sqrt(2.0 * 1.5e5 * real(n - i)) < v then v := sqrt(2.0 * 1.5e5 * real(n - i)); end if;
        if v > 3000.0 + 800.0 * real(k) then v := 3000.0 + 800.0 * real(k); end if;
        p := 1.0e6 / v;
        wait until l2 = '1';
        l1 <= '1';
        wait for 3 us;
        l1 <= '0';
        wait for (p - 3.0) * 1 us;
      end loop;
      wait for 100 us;
      l3 <= '0';
      wait for 3 ms;
    end loop;
    report "done" severity note;
    std.env.finish;
  end process;

  uart : process
    variable bits : bit_vector(7 downto 0) := x"5A";
  begin
    wait for 200 us;
    loop
      l0 <= '0';
      wait for 52 us;
      for b in 0 to 7 loop
        l0 <= bits(b);
        wait for 52 us;
      end loop;
      l0 <= '1';
      bits := bits(6 downto 0) & (bits(7) xor bits(5) xor bits(4) xor bits(3));
      wait for 52 us * (1 + (bit'pos(bits(1)) * 7));
    end loop;
  end process;
end architecture;
