"""Build captures and drives directly in tests: every interval known by construction."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np

from wavecheck.capture.edges import Capture, Channel
from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.timebase import Timebase


def capture(
    signals: dict[str, tuple[int, list[int]]],
    *,
    tick_ns: Fraction | int = 1,
    resolution_ticks: int = 0,
    end: int | None = None,
) -> Capture:
    """A capture of ``signals`` (name → (initial level, edge ticks)); 1 ns ticks by default."""
    channels = [
        Channel(name=name, index=i, initial=init, edges=np.asarray(edges, dtype=np.int64))
        for i, (name, (init, edges)) in enumerate(signals.items())
    ]
    last = max((int(c.edges[-1]) for c in channels if len(c.edges)), default=0)
    tick = Fraction(tick_ns) / 10**9
    return Capture(
        path="test.vcd",
        format="vcd",
        timebase=Timebase(tick),
        resolution_ticks=resolution_ticks,
        samplerate_hz=(1 / tick) if resolution_ticks else None,
        start=0,
        end=end if end is not None else last + 1,
        channels=channels,
    )


def renamed(cap: Capture, names: list[str]) -> Capture:
    """``cap`` with its channels called ``names`` (in channel order)."""
    chans = [
        Channel(name=n, index=c.index, initial=c.initial, edges=c.edges)
        for n, c in zip(names, cap.channels, strict=True)
    ]
    return Capture(
        cap.path,
        cap.format,
        cap.timebase,
        cap.resolution_ticks,
        cap.samplerate_hz,
        cap.start,
        cap.end,
        chans,
    )


def drive(
    active_edge: str = "rising",
    max_rate_hz: Fraction | int | None = None,
    interface: str = "step-dir",
    **limits_ns: Fraction | int,
) -> Drive:
    """A drive with the given limits in ns (``step_high=4500, dir_hold=20000`` …)."""
    return Drive(
        id="test-drive",
        name="Test drive",
        path=Path("test-drive.toml"),
        kind="user",
        interface=interface,  # type: ignore[arg-type]
        active_edge=active_edge,  # type: ignore[arg-type]
        limits={k: Figure(Fraction(v), "test", "datasheet") for k, v in limits_ns.items()},
        max_rate=Figure(Fraction(max_rate_hz), "test", "datasheet") if max_rate_hz else None,
    )


def g202() -> Drive:
    """The Gecko G202 figures of the design: falling edge, '1' ≥ 4.5 µs, '0' ≥ 0.5 µs, DIR setup
    ≥ 1 µs, hold ≥ 20 µs, ≤ 200 kHz."""
    return drive(
        "falling",
        max_rate_hz=200_000,
        step_high=4500,
        step_low=500,
        dir_setup=1000,
        dir_hold=20000,
    )


def move(t0: int, n: int, period: int, ramp: int = 6) -> list[int]:
    """Pulse starts of a move of ``n`` steps after ``t0``, from rest to rest: the rate grows as the
    square root of the steps taken (as under constant acceleration) over ``ramp`` steps up to one
    step per ``period`` ticks, and falls likewise before the end."""
    k = np.arange(n)
    steps = np.minimum(np.minimum(k + 1, n - k), ramp)
    return (t0 + np.cumsum(period * np.sqrt(ramp / steps))).astype(np.int64).tolist()


def pulses(starts: list[int], width: int) -> list[int]:
    """Edges of high pulses of ``width`` ticks starting at ``starts`` (signal initially low)."""
    out: list[int] = []
    for s in starts:
        out += [s, s + width]
    return out
