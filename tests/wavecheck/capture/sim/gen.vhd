-- The same step generator as gen.v in VHDL (GHDL dumps in fs): pulse 5 is 1.8 us high, DIR
-- changes 500 ns before pulse 10, DIR is unknown ('X', then '-') for 1 us from 500 ns after pulse 14 ends.
library ieee;
use ieee.std_logic_1164.all;

entity gen is
  port (step, dir : out std_logic; stout : out std_logic_vector(1 downto 0));
end gen;

architecture sim of gen is
  signal s : std_logic := '0';
  signal d : std_logic := 'U';
begin
  step <= s;
  dir <= d;
  stout <= d & s;
  process
  begin
    wait for 1000 ns;
    d <= '0';
    for i in 0 to 19 loop
      if i = 10 then
        wait for 1500 ns; d <= '1'; wait for 500 ns;
      else
        wait for 2000 ns;
      end if;
      s <= '1';
      if i = 5 then wait for 1800 ns; else wait for 2000 ns; end if;
      s <= '0';
      if i = 14 then
        wait for 500 ns; d <= 'X'; wait for 500 ns; d <= '-'; wait for 500 ns; d <= '1';
      end if;
    end loop;
    wait for 3000 ns;
    wait;
  end process;
end sim;

library ieee;
use ieee.std_logic_1164.all;

entity tb is
end tb;

architecture sim of tb is
  signal step, dir : std_logic;
  signal stout : std_logic_vector(1 downto 0);
  signal spare : std_logic := 'U';
begin
  dut : entity work.gen port map (step => step, dir => dir, stout => stout);
end sim;
