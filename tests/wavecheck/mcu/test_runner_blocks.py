"""wavecheck-avr's block mode (Klipper's protocol) against a tiny ATmega644P program of known
behaviour: it answers each block at once (an empty block with the next sequence number, as
src/command.c:363-372 does), and links 3 nodes into its ``move_free_list`` only after a delay,
raising PB0 as it does. A block that needs 3 slots must wait for PB0; one that needs none must
not."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import CLOCK_HZ, build_avr, rising, vcd_changes
from wavecheck.mcu.klipper import free_list_address
from wavecheck.mcu.klipper_msg import block_crc

#: The program: USART0 at 250000 baud (U2X, UBRR 7 at 16 MHz), answers each block; 20,000
#: turns of its loop after the first block it links 3 nodes into move_free_list and raises PB0.
ANSWERER = r"""
#include <avr/io.h>
struct node { struct node *next; };
struct node nodes[3];
struct node *volatile move_free_list;
static void put(unsigned char c) { while (!(UCSR0A & (1 << UDRE0))) {} UDR0 = c; }
int main(void) {
    DDRB = 1;
    UCSR0A = 1 << U2X0; UBRR0 = 7;
    UCSR0B = (1 << RXEN0) | (1 << TXEN0);
    unsigned char len = 0, seq = 0, blocks = 0;
    unsigned long wait = 0;
    for (;;) {
        if (blocks && !move_free_list && ++wait == 20000UL) {
            nodes[0].next = &nodes[1]; nodes[1].next = &nodes[2]; nodes[2].next = 0;
            move_free_list = &nodes[0];
            PORTB = 1;
        }
        if (!(UCSR0A & (1 << RXC0)))
            continue;
        unsigned char c = UDR0;
        if (++len == 2)
            seq = c;
        if (c == 0x7e) {
            blocks++;
            len = 0;
            put(5); put(0x10 | ((seq + 1) & 0x0f)); put(0); put(0); put(0x7e);
        }
    }
}
"""


def block(number: int, payload: bytes) -> str:
    head = bytes([len(payload) + 5, 0x10 | number]) + payload
    return (head + block_crc(head) + b"\x7e").hex()


def run(runner: Path, elf: Path, vcd: Path, need: int) -> tuple[list[int], int]:
    """The cycles of the program's answers, and the cycle PB0 rose."""
    first, second = block(0, bytes([1])), block(1, bytes([2]))
    lines = f"0 {first}\n{need} {second}\n"
    cmd = [str(runner), str(elf), "atmega644p", str(CLOCK_HZ), str(vcd), "", "20000000", "1000000"]
    cmd += ["READY=B.0", f"--blocks={free_list_address(elf)}", "--start=1000"]
    out = subprocess.run(cmd, input=lines, capture_output=True, text=True, check=True).stdout
    answers = [int(ln.split()[0]) for ln in out.splitlines() if ln.split()[1].startswith("05")]
    assert out.splitlines()[-1].startswith("END done")
    changes, _ = vcd_changes(vcd)
    return answers, rising(changes["READY"])[0] if rising(changes["READY"]) else -1


@pytest.fixture(scope="module")
def answerer(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_avr(tmp_path_factory.mktemp("answerer"), "answerer", ANSWERER, mcu="atmega644p")


def test_a_block_waits_for_its_slots(runner, answerer, tmp_path):
    answers, ready = run(runner, answerer, tmp_path / "paced.vcd", need=3)
    assert len(answers) == 2 and ready > answers[0]
    assert answers[1] > ready  # sent only after the free list held 3 nodes


def test_a_block_that_needs_no_slot_goes_at_once(runner, answerer, tmp_path):
    answers, ready = run(runner, answerer, tmp_path / "free.vcd", need=0)
    assert len(answers) == 2 and answers[1] < ready
