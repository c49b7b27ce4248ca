"""A guard for the firmware tests: a call that does not return within a bound fails the test
instead of hanging the suite (SIGALRM; the reading itself must be bounded, issue 27)."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

T = TypeVar("T")


class TookTooLong(AssertionError):
    """The call passed its bound."""


@contextmanager
def within(seconds: float) -> Iterator[None]:
    """Fail with :class:`TookTooLong` when the block runs longer than ``seconds``."""

    def alarm(signum: int, frame: object) -> None:
        raise TookTooLong(f"still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def bounded(call: Callable[[], T], seconds: float = 20.0) -> T:
    """``call()`` within ``seconds`` (see :func:`within`)."""
    with within(seconds):
        return call()
