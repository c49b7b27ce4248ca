"""The shapes of a pulse train's rate (wavecheck.roles.periodic, wavecheck.roles.features): a step
train against clocks, PWM, periodic lines, bursts at one rate and coded pulses."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pytest

from wavecheck.roles.features import look_at
from wavecheck.roles.periodic import timing

from ..waves import capture

I64 = npt.NDArray[np.int64]


def _edges(starts: I64 | list[int], widths: I64 | list[int] | int) -> list[int]:
    s = np.asarray(starts, dtype=np.int64)
    w = np.broadcast_to(np.asarray(widths, dtype=np.int64), s.shape)
    out = np.empty(2 * len(s), np.int64)
    out[0::2], out[1::2] = s, s + w
    return out.tolist()


def _trapezoid(n: int, top: float, accel: float, t0: int = 1000) -> I64:
    """Pulse starts (ns) of a move of ``n`` steps from rest to rest: the rate grows as the square
    root of the steps taken up to ``top`` steps/s, as under constant acceleration."""
    k = np.arange(n)
    v = np.minimum(np.sqrt(2 * accel * (k + 1)), np.sqrt(2 * accel * (n - k)))
    return t0 + np.cumsum(1e9 / np.minimum(v, top)).astype(np.int64)


def _tach(periods: I64) -> list[int]:
    """A line high for half of each period (a tachometer, a Hall sensor)."""
    return _edges(1000 + np.cumsum(periods), periods // 2)


def _moves(*moves: tuple[int, float], pause: int = 20_000_000, accel: float = 4e5) -> I64:
    out: list[int] = []
    t = 1000
    for n, top in moves:
        starts = _trapezoid(n, top, accel, t)
        out += starts.tolist()
        t = int(starts[-1]) + pause
    return np.asarray(out, dtype=np.int64)


def _kind(edges: list[int], resolution: int = 0, end: int | None = None) -> str:
    cap = capture({"x": (0, edges)}, resolution_ticks=resolution, end=end)
    return look_at(cap.channels[0], cap).kind


RNG = np.random.default_rng(26)
_CLOCK = np.arange(100) * 20
_IR_PERIODS = np.where(RNG.random(64) < 0.5, 1125, 2250) * 1000  # NEC: 0 and 1 bits, in ns


@pytest.mark.parametrize(
    ("what", "edges", "kind"),
    [
        # issue 26: a free-running clock (constant period, 50 % duty, no pauses) is no STEP
        ("clock, 50 MHz", _edges(_CLOCK, 10), "clock"),
        ("clock with a 40 % duty", _edges(_CLOCK, 8), "clock"),
        # a PWM line has a fixed period and a varying duty
        ("PWM, duty sweeping", _edges(np.arange(200) * 50_000, 5000 + 200 * np.arange(200)), "pwm"),
        # one period, one width, no pause: a frame sync, or steps at one speed: by name only
        ("frame sync", _edges(np.arange(300) * 125_000, 1000), "periodic"),
        # runs at one rate without speeding up or slowing down: a gated clock
        (
            "SPI clock, bytes apart",
            _edges((np.arange(8)[None, :] * 200 + np.arange(40)[:, None] * 7000).ravel(), 100),
            "bursts",
        ),
        # pulse-distance coding (an IR remote): the period jumps 2x between neighbours
        ("NEC remote", _edges(np.cumsum(_IR_PERIODS), 562_000), "coded"),
        # Miller coding: two periods 1.5x apart, there and back
        (
            "Miller code",
            _edges(np.cumsum(np.tile([9440, 14157, 9440, 9440, 14157, 14157, 9440], 6)), 2753),
            "coded",
        ),
        # a step train: fixed pulse width, a rate that ramps up and down around its pauses
        ("trapezoid moves", _edges(_moves((200, 5000), (120, 8000), (300, 3000)), 2000), "pulses"),
        ("one short move", _edges(_trapezoid(12, 5000, 4e5), 2000), "pulses"),
        ("three pulses", _edges([1000, 600_000, 1_200_000], 4000), "few"),
        # issue 33: a tachometer (or a Hall sensor) spinning up: one duty, its widths follow
        # the period; a step generator keeps its width
        (
            "tachometer spinning up",
            _tach(np.linspace(2e6, 1.2e6, 60).astype(np.int64)),
            "duty",
        ),
    ],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_shapes(what: str, edges: list[int], kind: str) -> None:
    assert _kind(edges) == kind, what


def test_a_quantised_step_generator_at_its_top_rate_is_steps() -> None:
    """LinuxCNC's stepgen at steplen = stepspace = 1 base period P runs its top rates with periods
    of 2P and 3P in turn (a jump of 1.5x each time), its pulses P long: a jump of one tick of the
    generator is no jump (../shared/reference/stepgen.md: the period is a whole number of base
    periods)."""
    p = 25_000
    starts = _moves((300, 16_000), (300, 13_000), accel=4e6)
    quantised = (np.round(starts / p) * p).astype(np.int64)
    assert set(np.unique(np.diff(quantised))[:2] // p) == {2, 3}
    assert _kind(_edges(quantised, p)) == "pulses"


def test_jitter_in_the_periods_only_is_the_rate_jumping() -> None:
    """Periods 25 % apart from pulse to pulse at the line's top rate: with exact widths (a timer
    making the pulses) that is the rate itself, not timing jitter."""
    periods = np.tile([4769, 5962, 4769, 5664, 6559, 4174, 4473, 6561], 12) * 10
    edges = _edges(np.cumsum(periods), 19_230)
    assert _kind(edges) == "coded"
    jitter = RNG.integers(-1500, 1500, len(periods))  # the same periods, the widths jittering
    assert timing(np.cumsum(periods), 19_230 + jitter, 0).width_spread > 0.02


def test_a_step_reversing_at_its_top_rate_is_no_free_running_clock() -> None:
    """Issue 33: a STEP reversing 20 times, periods 4.08 us to 7.89 us, was described as "a
    free-running clock". A clock never slows down; this line is periodic pulses (a STEP when
    named so), and its description says how far it slows."""
    periods = np.full(2400, 4080)
    for k in range(20):  # the 20 reversals: slowing down to 7.89 us and back
        periods[k * 119 + 50 : k * 119 + 57] = [4900, 5900, 7000, 7890, 7000, 5900, 4900]
    starts = np.cumsum(periods)
    t = timing(starts, np.full(len(starts), 2040), 0)
    assert t.one_rate and t.shape(0) == "periodic" and t.slowest > 1.9, t
    clock = timing(np.cumsum(np.full(600, 4080)), np.full(600, 2040), 0)
    assert clock.shape(0) == "clock"
