"""How the suite bounds a run without asserting wall-clock time (issue 37).

A hostile input is bounded by the work it causes, counted (:func:`lines_run`: lines of Python
executed; bytes scanned, edges, calls where a test can see them), or by memory
(:func:`peak_bytes`, or ``RLIMIT_AS`` on a child). Seconds appear once: :data:`HANG_GUARD_S`,
after which a run that never ends fails its test instead of stopping the CI job. It is a guard
against a hang, far above any honest run on a loaded machine, never a claim about speed (those
live in ``bench/``, as ratios against named peers).
"""

from __future__ import annotations

import signal
import sys
import tracemalloc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any, TypeVar

T = TypeVar("T")

#: Seconds after which a run is taken to hang (a guard, not a bound on speed).
HANG_GUARD_S = 600.0


class Hung(AssertionError):
    """A call ran past the hang guard."""


@contextmanager
def hang_guard() -> Iterator[None]:
    """Fail with :class:`Hung` when the block is still running after :data:`HANG_GUARD_S`
    (SIGALRM: the main thread of a process)."""

    def alarm(signum: int, frame: object) -> None:
        raise Hung(f"still running after {HANG_GUARD_S:g} s: a hang")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, HANG_GUARD_S)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def bounded(call: Callable[[], T]) -> T:
    """``call()``, failing the test if it hangs (see :func:`hang_guard`)."""
    with hang_guard():
        return call()


def lines_run(call: Callable[[], T]) -> tuple[T, int]:
    """``call()``'s result and how many lines of Python it executed (every frame, any depth):
    work counted, the same on a quiet machine and a loaded one."""
    count = 0

    def local(frame: FrameType, event: str, arg: Any) -> Any:
        nonlocal count
        if event == "line":
            count += 1
        return local

    def tracer(frame: FrameType, event: str, arg: Any) -> Any:
        return local

    old = sys.gettrace()
    sys.settrace(tracer)
    try:
        result = call()
    finally:
        sys.settrace(old)
    return result, count


def peak_bytes(call: Callable[[], T]) -> tuple[T, int]:
    """``call()``'s result and the peak of Python-allocated memory during it (tracemalloc;
    numpy's buffers included)."""
    started = not tracemalloc.is_tracing()
    if started:
        tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    try:
        result = call()
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        if started:
            tracemalloc.stop()
    return result, peak
