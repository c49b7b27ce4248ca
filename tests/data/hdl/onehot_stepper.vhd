-- A one-hot stepper sequencer and its testbench, for the role-inference tests
-- (tests/wavecheck/roles/test_hdl.py). A 1 MHz clock; a free-running two-stage Johnson
-- divider (div_q0, div_q1: quadrature at one rate, clock / 4) and a prescaler (presc) whose
-- terminal count comes from the speed input; on each prescaler tick, while enabled, a one-hot
-- state A, B, C, D (LinuxCNC's step type 5 table: 1, 2, 4, 8) moves one place, forward or back
-- as dir says. The testbench speeds the motor up, runs, slows down, reverses and pauses.
-- Only A..D are step outputs (one phase group); div_q0/div_q1 are divider nets.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity onehot_stepper is
  port (clk, rst, en, dir : in std_logic;
        speed : in unsigned(7 downto 0);
        a, b, c, d : out std_logic);
end entity;

architecture rtl of onehot_stepper is
  signal div_q0, div_q1 : std_logic := '0';
  signal presc : unsigned(7 downto 0) := (others => '0');
  signal tick : std_logic := '0';
  signal state : std_logic_vector(3 downto 0) := "0001";
begin
  divider : process (clk)
  begin
    if rising_edge(clk) then
      div_q0 <= not div_q1;
      div_q1 <= div_q0;
    end if;
  end process;

  prescaler : process (clk)
  begin
    if rising_edge(clk) then
      tick <= '0';
      if rst = '1' then
        presc <= (others => '0');
      elsif presc >= speed then
        presc <= (others => '0');
        tick <= '1';
      else
        presc <= presc + 1;
      end if;
    end if;
  end process;

  sequencer : process (clk)
  begin
    if rising_edge(clk) then
      if rst = '1' then
        state <= "0001";
      elsif tick = '1' and en = '1' then
        if dir = '1' then
          state <= state(2 downto 0) & state(3);
        else
          state <= state(0) & state(3 downto 1);
        end if;
      end if;
    end if;
  end process;

  a <= state(0);
  b <= state(1);
  c <= state(2);
  d <= state(3);
end architecture;

library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tb is
end entity;

architecture sim of tb is
  signal clk, rst, en, dir : std_logic := '0';
  signal speed : unsigned(7 downto 0) := to_unsigned(200, 8);
  signal a, b, c, d : std_logic;
  signal done : boolean := false;
begin
  dut : entity work.onehot_stepper port map (clk, rst, en, dir, speed, a, b, c, d);
  clk <= not clk after 500 ns when not done else '0';

  stimulus : process
    procedure run (first, last, step_by : integer; each : time) is
      variable v : integer := first;
    begin
      loop
        speed <= to_unsigned(v, 8);
        wait for each;
        exit when v = last;
        v := v + step_by;
      end loop;
    end procedure;
  begin
    rst <= '1';
    wait for 3 us;
    rst <= '0';
    for move in 0 to 3 loop
      dir <= '1' when move mod 2 = 0 else '0';
      wait for 20 us;
      en <= '1';
      run(240, 40, -20, 2 ms);  -- speed up: terminal count 240 down to 40
      wait for 6 ms;
      run(40, 240, 20, 2 ms);  -- slow down
      en <= '0';
      wait for 5 ms;  -- a pause
    end loop;
    done <= true;
    wait;
  end process;
end architecture;
