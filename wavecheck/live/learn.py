"""Roles told from the first samples of a live watch (``wavecheck watch`` without ``--map``).

A machine's analyzer channels are often unlabelled. Before the check can start, the samples are
kept (:class:`RoleLearner`) and, at 0.5 s, 1 s, 2 s … of them, read as a capture and given to the
same role inference as ``check`` (:mod:`wavecheck.roles`, through ``decide``). When it is
unambiguous the check starts on the kept samples and goes on live; when the samples reach the
limit (``--learn``) undecided, the watch ends with the candidates and the ``--map`` to give.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from fractions import Fraction

from wavecheck.capture.binary import SampleBlocks, read_binary
from wavecheck.capture.edges import Capture
from wavecheck.engine import MachineCheck

__all__ = ["FIRST_TRY_S", "RoleLearner"]

#: Seconds of samples at the first attempt (then twice as many each time).
FIRST_TRY_S = Fraction(1, 2)


class RoleLearner:
    """Samples kept until ``decide(capture, final)`` gives the check to run (None: not yet;
    with ``final`` it raises instead), at most ``limit`` samples."""

    def __init__(
        self,
        scanner: SampleBlocks,
        decide: Callable[[Capture, bool], MachineCheck | None],
        limit: int,
    ) -> None:
        self.scanner = scanner
        self.decide = decide
        self.limit = max(1, limit)
        self.kept = bytearray()
        self.next_try = min(self.limit, max(1, int(FIRST_TRY_S * scanner.rate)))

    @property
    def samples(self) -> int:
        """Whole samples kept."""
        return len(self.kept) // self.scanner.unitsize

    def add(self, data: bytes) -> None:
        """Keep the next bytes of the stream."""
        self.kept += data

    def attempt(self, final: bool = False) -> MachineCheck | None:
        """Try the inference when enough samples came since the last try (``final``: now, and
        raise if it cannot decide)."""
        n = self.samples
        final = final or n >= self.limit
        if not final and n < self.next_try:
            return None
        self.next_try = min(self.limit, 2 * max(n, 1))
        whole = n * self.scanner.unitsize
        capture = read_binary(
            io.BytesIO(bytes(self.kept[:whole])),
            f"binary:numchannels={len(self.scanner.bits)}",
            name=self.scanner.label,
            samplerate=self.scanner.rate,
            channel_names=self.scanner.names,
        )
        return self.decide(capture, final)

    def replay(self, machine: MachineCheck) -> None:
        """Check the kept samples with ``machine`` (what :meth:`attempt` gave) and let them go."""
        data, self.kept = bytes(self.kept), bytearray()
        machine.feed(self.scanner.scan(data))
