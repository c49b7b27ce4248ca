"""Each of wavecheck's three simavr fixes (wavecheck/mcu/simavr/fixes.patch), shown by a tiny AVR
program whose pin timing follows from the ATmega328P datasheet alone, run on the patched simavr
and on simavr as it is (which gets each one wrong)."""

from __future__ import annotations

from pathlib import Path

from tests.wavecheck.mcu.helpers import build_avr, high_widths, run_avr, vcd_changes

# Fix 1. Timer1 in CTC mode with OCR1A = 0 at clk/1 matches every cycle (datasheet "Clear Timer
# on Compare Match (CTC) Mode": the counter is cleared when it matches OCR1A; OCF1A is set).
CTC_ZERO = r"""
#include <avr/io.h>
#include <avr/interrupt.h>
ISR(TIMER1_COMPA_vect) { PORTB = 1; TCCR1B = 0; }
int main(void) {
    DDRB = 1; OCR1A = 0; TCCR1A = 0; TIMSK1 = 1 << OCIE1A;
    TCCR1B = (1 << WGM12) | (1 << CS10);
    sei();
    for (;;) {}
}
"""


def _pulse(runner: Path, elf: Path, tmp: Path) -> list[int]:
    vcd = tmp / f"{elf.stem}-{runner.parent.name}.vcd"
    run_avr(runner, elf, vcd, ["PIN=B.0"])
    changes, _ = vcd_changes(vcd)
    return changes["PIN"]


def test_ctc_with_ocr_zero_at_clk1_fires(runner: Path, runner_unpatched: Path, tmp_path: Path):
    elf = build_avr(tmp_path, "ctc0", CTC_ZERO)
    assert [v for _, v in _pulse(runner, elf, tmp_path)][-1:] == [1]  # the interrupt ran
    assert [v for _, v in _pulse(runner_unpatched, elf, tmp_path)][-1:] == [0]  # never armed


# Fix 2. Timer0 stopped, TCNT0 preloaded, started at clk/8: it counts on from the preload, and
# its first count comes on the free-running prescaler's next edge, 1..8 cycles after the start
# (datasheet "Timer/Counter0 and Timer/Counter1 Prescalers"). The pin goes high at OUT PORTB; the
# next instruction starts the timer; the overflow interrupt is taken during a run of NOPs (no
# wait for a longer instruction), 4 cycles of response, a JMP at the vector (3), and the naked
# handler's first instruction clears the pin: width = 1 + d + 8 * (255 - PRELOAD) + 4 + 3.
PRELOADED = r"""
#include <avr/io.h>
#include <avr/interrupt.h>
#define S_(x) #x
#define S(x) S_(x)
ISR(TIMER0_OVF_vect, ISR_NAKED) {
    asm volatile("out %0, __zero_reg__\n\tout %1, __zero_reg__\n\treti"
                 :: "I"(_SFR_IO_ADDR(PORTB)), "I"(_SFR_IO_ADDR(TCCR0B)));
}
int main(void) {
    DDRB = 1; TCCR0A = 0; TCCR0B = 0; TIMSK0 = 1 << TOIE0; TCNT0 = PRELOAD;
    sei();
    asm volatile("ldi r24, 1\n\tldi r25, 2\n\t"
                 ".rept " S(NOPS) "\n\tnop\n\t.endr\n\t"
                 "out %0, r24\n\tout %1, r25\n\t"
                 ".rept 2500\n\tnop\n\t.endr"
                 :: "I"(_SFR_IO_ADDR(PORTB)), "I"(_SFR_IO_ADDR(TCCR0B)) : "r24", "r25");
    for (;;) {}
}
"""


def _preloaded_width(runner: Path, tmp: Path, preload: int, nops: int) -> int:
    elf = build_avr(tmp, f"pre{preload}-{nops}", PRELOADED, PRELOAD=preload, NOPS=nops)
    (width,) = high_widths(_pulse(runner, elf, tmp))
    return width


def test_starting_a_timer_counts_from_the_preloaded_tcnt(runner: Path, tmp_path: Path):
    w250, w200 = (_preloaded_width(runner, tmp_path, p, 0) for p in (250, 200))
    assert w200 - w250 == 50 * 8  # 50 more counts of 8 cycles
    assert 1 + 1 + 8 * 5 + 7 <= w250 <= 1 + 8 + 8 * 5 + 7


def test_the_first_count_comes_on_the_free_running_prescaler(runner: Path, tmp_path: Path):
    widths = {_preloaded_width(runner, tmp_path, 250, k) for k in range(8)}
    assert widths == {1 + d + 8 * 5 + 7 for d in range(1, 9)}


def test_unpatched_simavr_ignores_the_preload(runner_unpatched: Path, tmp_path: Path):
    widths = {_preloaded_width(runner_unpatched, tmp_path, p, 0) for p in (250, 200)}
    assert len(widths) == 1  # the same width whatever was preloaded: the count restarts at 0
    assert widths.pop() > 8 * 200


# Fix 3. The interrupt response takes 4 cycles (datasheet "Interrupt Response Time"). The pin
# goes high; SEI with the overflow flag already pending; the instruction after SEI runs first
# (datasheet "Status Register": SEI), then 4 cycles of response, the vector's JMP (3) and the
# naked handler's OUT: width = 1 (OUT) + 1 (SEI) + 1 (NOP) + 4 + 3 = 10 cycles.
RESPONSE = r"""
#include <avr/io.h>
#include <avr/interrupt.h>
ISR(TIMER0_OVF_vect, ISR_NAKED) {
    asm volatile("out %0, __zero_reg__\n\tout %1, __zero_reg__\n\treti"
                 :: "I"(_SFR_IO_ADDR(PORTB)), "I"(_SFR_IO_ADDR(TCCR0B)));
}
int main(void) {
    DDRB = 1; TIMSK0 = 1 << TOIE0; TCCR0B = 1 << CS00;
    while (!(TIFR0 & (1 << TOV0))) {}
    TCCR0B = 0;
    asm volatile("ldi r24, 1\n\tout %0, r24\n\tsei\n\t.rept 20\n\tnop\n\t.endr"
                 :: "I"(_SFR_IO_ADDR(PORTB)) : "r24");
    for (;;) {}
}
"""


def test_the_interrupt_response_is_four_cycles(
    runner: Path, runner_unpatched: Path, tmp_path: Path
):
    elf = build_avr(tmp_path, "response", RESPONSE)
    assert high_widths(_pulse(runner, elf, tmp_path)) == [10]
    assert high_widths(_pulse(runner_unpatched, elf, tmp_path)) == [6]


# Fix 2, its other half: a stopped timer holds the count it reached (datasheet: TCNT0 keeps its
# value while the clock select is 0). Started at clk/8 from 0, stopped 101 cycles later (the OUT
# that starts it, then 100 NOPs), it has counted 12 or 13 times (the first count 1..8 cycles after
# the start); the program shows TCNT0 on PORTB.
STOPPED = r"""
#include <avr/io.h>
int main(void) {
    DDRB = 0xff; TCCR0A = 0; TCCR0B = 0; TCNT0 = 0;
    asm volatile("ldi r24, 2\n\tout %0, r24\n\t.rept 100\n\tnop\n\t.endr\n\tout %0, __zero_reg__"
                 :: "I"(_SFR_IO_ADDR(TCCR0B)) : "r24");
    PORTB = TCNT0;
    for (;;) {}
}
"""


def _count(runner: Path, elf: Path, tmp: Path) -> int:
    vcd = tmp / f"count-{runner.parent.name}.vcd"
    run_avr(runner, elf, vcd, [f"B{k}=B.{k}" for k in range(8)])
    changes, _ = vcd_changes(vcd)
    return sum(changes[f"B{k}"][-1][1] << k for k in range(8))


def test_a_stopped_timer_keeps_its_count(runner: Path, runner_unpatched: Path, tmp_path: Path):
    elf = build_avr(tmp_path, "stopped", STOPPED)
    assert _count(runner, elf, tmp_path) in (12, 13)
    assert _count(runner_unpatched, elf, tmp_path) == 0  # the count is lost at the stop
