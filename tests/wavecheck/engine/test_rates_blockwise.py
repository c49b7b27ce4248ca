"""rates._diff_extreme (block by block) equals argmin/argmax over the full difference array."""

from __future__ import annotations

import numpy as np
import pytest

from wavecheck.engine import rates


@pytest.mark.parametrize("block", [1, 2, 3, 7, 1 << 20])
@pytest.mark.parametrize("n", [1, 2, 6, 7, 8, 50])
def test_diff_extreme_equals_full_arrays(
    monkeypatch: pytest.MonkeyPatch, block: int, n: int
) -> None:
    monkeypatch.setattr(rates, "_BLOCK", block)
    rng = np.random.default_rng(n * 100 + block)
    for _ in range(20):
        ticks = np.cumsum(rng.integers(0, 4, n + 1)).astype(np.int64)  # ties and zero gaps
        start, end = ticks[:-1], ticks[1:]
        d = end - start
        assert rates._diff_extreme(start, end, smallest=True) == (int(d.min()), int(np.argmin(d)))
        assert rates._diff_extreme(start, end, smallest=False) == (int(d.max()), int(np.argmax(d)))
