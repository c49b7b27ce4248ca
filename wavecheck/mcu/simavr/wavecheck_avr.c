/*
 * wavecheck-avr: run an AVR firmware (ELF) on simavr, talk to its UART line by line, and
 * write chosen port pins to a VCD with the exact cycle of every change.
 *
 * Copyright (C) 2026 the wavecheck authors
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * This program links simavr (GPL-3.0) and is therefore GPL-3.0-or-later. wavecheck (MIT) runs it
 * as a separate process and reads its output; it does not link it.
 *
 * Usage:
 *   wavecheck-avr ELF MCU FREQ_HZ VCD BANNER MAX_CYCLES TAIL_CYCLES PIN...
 *   PIN is NAME=PORT.BIT, e.g. X_STEP=D.2
 * Standard input: the lines to send, one per line. Nothing is sent before a UART line that
 * contains BANNER (at once if BANNER is empty); then each line is sent (at the UART's own byte rate, with its fifo's
 * XON/XOFF) and the next one only after a reply line starting "ok" or "error". After the last
 * reply the simulation runs TAIL_CYCLES more and stops. It never runs past MAX_CYCLES, and it
 * stops at a line starting "ALARM" (grbl's alarm: it resets and drops the line in flight).
 * Standard output: "CYCLE LINE" for every line the firmware prints, then one of
 *   "END done CYCLE", "END limit CYCLE", "END nobanner CYCLE", "END alarm CYCLE",
 *   "END crashed CYCLE".
 * Exit status: 0 when it ran (whatever the end), 2 for bad arguments or an unloadable ELF.
 *
 * Block mode (Klipper's binary protocol), chosen by the option --blocks=ADDR among the PINs:
 * each input line is "NEED HEX", one message block and the number of move-queue slots its
 * commands take. Nothing is sent before the cycle --start=N. Block k is sent when the MCU has
 * answered block k-1 (any block whose sequence byte is the one after k-1's) and, if ADDR (the
 * data address of the firmware's free-list head pointer) is not 0, when that list holds at least
 * NEED nodes (walked every 1024 cycles while a block waits). Each block the MCU sends is printed
 * as "CYCLE HEX". After the last answer the simulation runs to the cycle --until=N, then
 * TAIL_CYCLES more. It stops at an MCU block whose payload starts with one of the --stop=HEX
 * prefixes, and at a 5-byte block that repeats the sequence of the block in flight (a nak).
 * Ends: "END done|limit|noanswer|stop|nak|crashed CYCLE".
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_irq.h"
#include "avr_ioport.h"
#include "avr_uart.h"

#define MAX_PINS 32
#define MAX_LINE 512
#define MAX_STOPS 8
#define MAX_BLOCK 64	/* Klipper's MESSAGE_MAX */
#define FREE_LIST_BOUND 65536	/* nodes walked at most (a corrupt list ends the walk) */

typedef struct pin_t {
	char name[64];
	char port;
	int bit;
	char id[4];
	int value;	/* -1 before the first report */
} pin_t;

static avr_t *avr;
static FILE *vcd;
static uint64_t ticks_per_cycle;
static uint64_t last_time = UINT64_MAX;
static pin_t pins[MAX_PINS];
static int npins;

static char **lines;	/* the lines to send */
static size_t nlines, cur_line, cur_pos;
static int xoff;
static avr_irq_t *uart_in;
static const char *banner;

enum { WAIT_BANNER, SENDING, WAIT_REPLY, TAIL, STOP } state = WAIT_BANNER;
static uint64_t stop_at;
static const char *end_reason = "done";
static char rx[MAX_LINE];
static size_t rx_len;

/* block mode */
static int blocks;
static uint16_t free_list_addr;
static uint64_t start_cycle, until_cycle, next_check;
static int *needs;
static uint8_t stops[MAX_STOPS][MAX_BLOCK];
static size_t stop_len[MAX_STOPS];
static int nstops;
static int answered;	/* an answer came to the block in flight */

static void
vcd_change(pin_t *p, int value)
{
	uint64_t t = avr->cycle * ticks_per_cycle;
	if (t != last_time) {
		fprintf(vcd, "#%" PRIu64 "\n", t);
		last_time = t;
	}
	fprintf(vcd, "%d%s\n", value, p->id);
}

static void
pin_changed(struct avr_irq_t *irq, uint32_t value, void *param)
{
	pin_t *p = param;
	int v = value & 1;
	if (v != p->value) {
		p->value = v;
		vcd_change(p, v);
	}
}

static void
got_line(void)
{
	rx[rx_len] = 0;
	if (rx_len && rx[rx_len - 1] == '\r')
		rx[--rx_len] = 0;
	printf("%" PRIu64 " %s\n", avr->cycle, rx);
	if (state == WAIT_BANNER && strstr(rx, banner)) {
		state = nlines ? SENDING : TAIL;
	} else if (state == WAIT_REPLY &&
			(strncmp(rx, "ok", 2) == 0 || strncmp(rx, "error", 5) == 0)) {
		cur_line++;
		cur_pos = 0;
		state = cur_line < nlines ? SENDING : TAIL;
	}
	if (state != WAIT_BANNER && strncmp(rx, "ALARM", 5) == 0) {
		end_reason = "alarm";	/* grbl resets and flushes its input: no reply will come */
		state = STOP;
	}
	if (state == TAIL && !stop_at)
		stop_at = 1;	/* set by the main loop */
	rx_len = 0;
}

/* A whole block from the MCU in rx[0..rx_len): print it, note an answer or a stop. */
static void
got_block(void)
{
	const uint8_t *b = (const uint8_t *)rx;
	printf("%" PRIu64 " ", avr->cycle);
	for (size_t i = 0; i < rx_len; i++)
		printf("%02x", b[i]);
	printf("\n");
	if (rx_len < 5 || b[0] != rx_len)
		return;	/* not a block: the framing is the firmware's to get right */
	for (int k = 0; k < nstops; k++)
		if (rx_len - 2 >= stop_len[k] && !memcmp(b + 2, stops[k], stop_len[k])) {
			end_reason = "stop";
			state = STOP;
			return;
		}
	if (state != WAIT_REPLY)
		return;
	unsigned sent = 0x10 | (cur_line & 0x0f);
	unsigned next = 0x10 | ((cur_line + 1) & 0x0f);
	if (b[1] == next) {
		answered = 1;
		cur_line++;
		state = cur_line < nlines ? SENDING : TAIL;
		if (state == TAIL)
			stop_at = 1;
	} else if (rx_len == 5 && b[1] == sent) {
		end_reason = "nak";
		state = STOP;
	}
}

static void
uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
	char c = value & 0xff;
	if (blocks) {
		if ((uint8_t)c == 0x7e) {
			if (rx_len)
				rx[rx_len++] = c;
			if (rx_len)
				got_block();
			rx_len = 0;
		} else if (rx_len < MAX_BLOCK) {
			rx[rx_len++] = c;
		}
		return;
	}
	if (c == '\n')
		got_line();
	else if (rx_len < MAX_LINE - 1)
		rx[rx_len++] = c;
}

static void
uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
	xoff = value & 1;
}

static void
uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
	if (value & 1)
		xoff = 0;
}

static int
hexval(int c)
{
	if (c >= '0' && c <= '9')
		return c - '0';
	if (c >= 'a' && c <= 'f')
		return c - 'a' + 10;
	if (c >= 'A' && c <= 'F')
		return c - 'A' + 10;
	return -1;
}

/* HEX -> bytes in out (at most max); returns the count, or -1 for a malformed string. */
static int
unhex(const char *hex, uint8_t *out, size_t max)
{
	size_t n = strlen(hex);
	if (n % 2 || n / 2 > max)
		return -1;
	for (size_t i = 0; i < n / 2; i++) {
		int hi = hexval(hex[2 * i]), lo = hexval(hex[2 * i + 1]);
		if (hi < 0 || lo < 0)
			return -1;
		out[i] = hi << 4 | lo;
	}
	return n / 2;
}

/* Block mode: each line "NEED HEX" becomes the bytes of one block (its first byte is its
 * length). */
static int
read_blocks(void)
{
	size_t cap = 64;
	char buf[4096];
	lines = malloc(cap * sizeof(char *));
	needs = malloc(cap * sizeof(int));
	while (fgets(buf, sizeof(buf), stdin)) {
		buf[strcspn(buf, "\r\n")] = 0;
		char *sp = strchr(buf, ' ');
		uint8_t bytes[MAX_BLOCK];
		int n = sp ? unhex(sp + 1, bytes, sizeof(bytes)) : -1;
		if (n < 5 || bytes[0] != n) {
			fprintf(stderr, "input line %zu: expected NEED HEX, a whole message block\n",
					nlines + 1);
			return -1;
		}
		if (nlines == cap) {
			lines = realloc(lines, (cap *= 2) * sizeof(char *));
			needs = realloc(needs, cap * sizeof(int));
		}
		needs[nlines] = atoi(buf);
		lines[nlines] = malloc(n);
		memcpy(lines[nlines], bytes, n);
		nlines++;
	}
	return 0;
}

/* The nodes on the firmware's free list (its head pointer at free_list_addr in data space). */
static int
free_nodes(void)
{
	int n = 0;
	uint16_t p = avr->data[free_list_addr] | avr->data[free_list_addr + 1] << 8;
	while (p && p + 1 <= avr->ramend && n < FREE_LIST_BOUND) {
		n++;
		p = avr->data[p] | avr->data[p + 1] << 8;
	}
	return n;
}

static void
read_lines(void)
{
	size_t cap = 64;
	char buf[4096];
	lines = malloc(cap * sizeof(char *));
	while (fgets(buf, sizeof(buf), stdin)) {
		size_t n = strcspn(buf, "\r\n");
		buf[n] = 0;
		if (nlines == cap)
			lines = realloc(lines, (cap *= 2) * sizeof(char *));
		lines[nlines] = malloc(n + 2);
		memcpy(lines[nlines], buf, n);
		lines[nlines][n] = '\n';
		lines[nlines][n + 1] = 0;
		nlines++;
	}
}

/* The VCD time unit: the largest of 1/10/100 fs..s that divides the cycle period. */
static const char *
timescale(uint64_t period_fs, uint64_t *unit_fs)
{
	static const char *names[] = {
		"1 fs", "10 fs", "100 fs", "1 ps", "10 ps", "100 ps", "1 ns", "10 ns", "100 ns",
		"1 us", "10 us", "100 us", "1 ms", "10 ms", "100 ms", "1 s" };
	uint64_t u = 1;
	int k = 0;
	while (k < 15 && period_fs % (u * 10) == 0) {
		u *= 10;
		k++;
	}
	*unit_fs = u;
	return names[k];
}

int
main(int argc, char *argv[])
{
	if (argc < 8) {
		fprintf(stderr, "usage: %s ELF MCU FREQ_HZ VCD BANNER MAX_CYCLES TAIL_CYCLES PIN...\n", argv[0]);
		return 2;
	}
	const char *elf = argv[1], *mcu = argv[2], *vcd_path = argv[4];
	uint64_t freq = strtoull(argv[3], NULL, 10);
	banner = argv[5];
	uint64_t max_cycles = strtoull(argv[6], NULL, 10);
	uint64_t tail_cycles = strtoull(argv[7], NULL, 10);
	if (!freq || 1000000000000000ULL % freq) {
		fprintf(stderr, "FREQ_HZ %s: the cycle must be a whole number of femtoseconds\n", argv[3]);
		return 2;
	}
	uint64_t period_fs = 1000000000000000ULL / freq, unit_fs;
	const char *ts = timescale(period_fs, &unit_fs);
	ticks_per_cycle = period_fs / unit_fs;

	for (int i = 8; i < argc && npins < MAX_PINS; i++) {
		pin_t *p = &pins[npins];
		if (!strncmp(argv[i], "--", 2)) {
			const char *v = strchr(argv[i], '=');
			v = v ? v + 1 : "";
			if (!strncmp(argv[i], "--blocks=", 9)) {
				blocks = 1;
				free_list_addr = strtoul(v, NULL, 0);
			} else if (!strncmp(argv[i], "--start=", 8)) {
				start_cycle = strtoull(v, NULL, 10);
			} else if (!strncmp(argv[i], "--until=", 8)) {
				until_cycle = strtoull(v, NULL, 10);
			} else if (!strncmp(argv[i], "--stop=", 7) && nstops < MAX_STOPS) {
				int n = unhex(v, stops[nstops], MAX_BLOCK);
				if (n <= 0) {
					fprintf(stderr, "%s: expected --stop=HEX\n", argv[i]);
					return 2;
				}
				stop_len[nstops++] = n;
			} else {
				fprintf(stderr, "%s: not an option of this program\n", argv[i]);
				return 2;
			}
			continue;
		}
		const char *eq = strchr(argv[i], '=');
		if (!eq || eq - argv[i] >= (long)sizeof(p->name) || strlen(eq) != 4 || eq[2] != '.' ||
				eq[3] < '0' || eq[3] > '7') {
			fprintf(stderr, "PIN %s: expected NAME=PORT.BIT, e.g. X_STEP=D.2\n", argv[i]);
			return 2;
		}
		memcpy(p->name, argv[i], eq - argv[i]);
		p->port = eq[1];
		p->bit = eq[3] - '0';
		p->value = -1;
		snprintf(p->id, sizeof(p->id), "%c", '!' + npins);
		npins++;
	}

	elf_firmware_t fw;
	memset(&fw, 0, sizeof(fw));
	if (elf_read_firmware(elf, &fw) != 0) {
		fprintf(stderr, "%s: not a readable AVR ELF\n", elf);
		return 2;
	}
	avr = avr_make_mcu_by_name(mcu);
	if (!avr) {
		fprintf(stderr, "MCU %s: not a simavr core\n", mcu);
		return 2;
	}
	avr_init(avr);
	avr->log = LOG_ERROR;
	avr_load_firmware(avr, &fw);
	avr->frequency = freq;

	vcd = fopen(vcd_path, "w");
	if (!vcd) {
		perror(vcd_path);
		return 2;
	}
	static char vbuf[1 << 16];
	setvbuf(vcd, vbuf, _IOFBF, sizeof(vbuf));
	fprintf(vcd, "$comment wavecheck-avr: %s on simavr, %" PRIu64 " Hz, "
			"times are the cycles of the instructions that write the port $end\n", mcu, freq);
	fprintf(vcd, "$timescale %s $end\n$scope module %s $end\n", ts, mcu);
	for (int i = 0; i < npins; i++)
		fprintf(vcd, "$var wire 1 %s %s $end\n", pins[i].id, pins[i].name);
	fprintf(vcd, "$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
	for (int i = 0; i < npins; i++) {
		fprintf(vcd, "0%s\n", pins[i].id);
		pins[i].value = 0;
	}
	fprintf(vcd, "$end\n");
	last_time = 0;

	for (int i = 0; i < npins; i++) {
		avr_irq_t *irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(pins[i].port), pins[i].bit);
		if (!irq) {
			fprintf(stderr, "PIN %s: %s has no port %c\n", pins[i].name, mcu, pins[i].port);
			return 2;
		}
		avr_irq_register_notify(irq, pin_changed, &pins[i]);
	}
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
			uart_out, NULL);
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF),
			uart_xoff, NULL);
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON),
			uart_xon, NULL);
	uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
	uint32_t flags = 0;	/* the lines go to our stdout, not simavr's console copy */
	avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
	flags &= ~AVR_UART_FLAG_STDIO;
	avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);

	if (blocks) {
		if (read_blocks())
			return 2;
		banner = "";
	} else {
		read_lines();
	}
	if (!*banner)	/* no banner to wait for: send at once */
		state = nlines ? SENDING : TAIL;
	if (state == TAIL)
		stop_at = 1;

	for (;;) {
		int s = avr_run(avr);
		if (s == cpu_Done || s == cpu_Crashed) {
			end_reason = "crashed";
			break;
		}
		if (state == STOP)
			break;
		if (state == TAIL && stop_at == 1)
			stop_at = (until_cycle > avr->cycle ? until_cycle : avr->cycle) + tail_cycles;
		if (state == TAIL && avr->cycle >= stop_at)
			break;
		if (avr->cycle >= max_cycles) {
			end_reason = state == WAIT_BANNER ? "nobanner" :
				blocks && !answered ? "noanswer" : "limit";
			break;
		}
		if (blocks) {
			if (state != SENDING || xoff || avr->cycle < start_cycle)
				continue;
			if (cur_pos == 0 && free_list_addr && needs[cur_line]) {
				if (avr->cycle < next_check)
					continue;
				if (free_nodes() < needs[cur_line]) {
					next_check = avr->cycle + 1024;
					continue;
				}
			}
			const uint8_t *b = (const uint8_t *)lines[cur_line];
			avr_raise_irq(uart_in, b[cur_pos++]);	/* its sequence byte: cur_line's */
			if (cur_pos == b[0]) {
				cur_pos = 0;
				state = WAIT_REPLY;
			}
			continue;
		}
		if (state == SENDING && !xoff) {
			const char *l = lines[cur_line];
			avr_raise_irq(uart_in, (uint8_t)l[cur_pos++]);
			if (!l[cur_pos])
				state = WAIT_REPLY;
		}
	}
	if (fflush(vcd) != 0 || fclose(vcd) != 0) {
		perror(vcd_path);
		return 2;
	}
	printf("END %s %" PRIu64 "\n", end_reason, avr->cycle);
	return 0;
}
