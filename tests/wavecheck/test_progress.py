"""The stderr progress bar: off unless a terminal, drawn after a delay, erased at the end."""

from __future__ import annotations

import io

from wavecheck.progress import ProgressBar, activate, current, no_progress


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_off_when_not_a_terminal() -> None:
    stream = io.StringIO()
    bar = ProgressBar("reading", stream=stream, delay_s=0)
    bar(5, 10)
    bar.close()
    assert stream.getvalue() == ""


def test_drawn_on_a_terminal_and_erased() -> None:
    stream = _Tty()
    bar = ProgressBar("reading x.sr", unit="bytes", stream=stream, delay_s=0)
    bar(2_500_000, 10_000_000)
    text = stream.getvalue()
    assert "reading x.sr [#######-----------------------]  25% 2.5 MB / 10.0 MB" in text
    bar.close()
    assert stream.getvalue().endswith("\r\x1b[2K")


def test_unknown_total_and_delay() -> None:
    assert ProgressBar("sim", unit="periods").line(1234, None) == "sim … 1,234 periods"
    stream = _Tty()
    bar = ProgressBar("slow", stream=stream, delay_s=60)
    bar(1, 2)  # within the delay: nothing drawn
    assert stream.getvalue() == ""


def test_activate_sets_the_current_callback_and_quiet_disables_it() -> None:
    assert current() is no_progress
    stream = _Tty()
    with activate("reading", stream=stream) as bar:
        assert current() is bar
        assert bar.enabled
    assert current() is no_progress
    with activate("reading", quiet=True, stream=stream) as bar:
        assert not bar.enabled
