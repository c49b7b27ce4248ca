"""Channels named after their roles (``step``, ``up``, ``down``): a name is a hint, not evidence
(issue 33). A line so named whose waveform makes no step pulses (a free-running clock, a bus's
clock or data, not one whole pulse) is refused with the reason and the lines most like a STEP,
both by :func:`wavecheck.roles.propose` (``info``) and by :func:`wavecheck.engine.planning.auto_map`
(``check``); pulses the waveform cannot tell from steps (a few, at one rate) keep the name."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.engine_probe import run_check
from wavecheck.capture.edges import Capture, Channel
from wavecheck.cli import main
from wavecheck.engine.planning import auto_map
from wavecheck.errors import UsageError
from wavecheck.roles import name_conflicts, propose
from wavecheck.roles.features import ChannelLook, look_at
from wavecheck.steptypes import step_type

from ..waves import capture, drive, pulses
from .moves import US, move


def _clock(n: int, half: int = 5 * US) -> list[int]:
    return [half * (k + 1) for k in range(2 * n)]


def _serial(bits: str, bit: int = 8680) -> list[int]:
    """Edges of a UART line idle high sending ``bits`` (0/1 characters) at ``bit`` ticks a bit."""
    edges, level = [], 1
    for k, b in enumerate(bits):
        if int(b) != level:
            edges.append(1000 + k * bit)
            level = int(b)
    return edges


def _pwm(n: int, period: int = 20 * US) -> list[int]:
    """A PWM line: one period, widths 3..9 µs."""
    return [e for k in range(n) for e in (k * period, k * period + (3 + k % 7) * US)][1:]


_UART = "".join(f"0{v:08b}1" + "1" * (k % 3) for k, v in enumerate(b"step and dir bytes " * 3))
#: a step train beside the named line: the line most like a STEP
_TRAIN = pulses(move(0, 30), 5 * US)

#: (the waveform of the line named ``step``, refused?, words of the reason)
NAMED_STEP = [
    ("clock", (0, _clock(200)), True, "clock"),
    ("never changes", (0, []), True, "never changes"),
    ("one edge", (0, [1003 * US]), True, "not one whole pulse"),
    # a base thread's STEP with latency looks so (stepgen simulate): the name decides
    ("serial line", (1, _serial(_UART)), False, ""),
    ("PWM", (0, _pwm(60)), False, ""),
    ("step train", (0, pulses(move(0, 19), 5 * US)), False, ""),
    ("three pulses", (0, pulses([100 * US, 400 * US, 900 * US], 5 * US)), False, ""),
    ("pulses at one rate", (0, pulses([k * 50 * US for k in range(1, 40)], 5 * US)), False, ""),
]


@pytest.mark.parametrize(("waveform", "refused", "why"), [c[1:] for c in NAMED_STEP],
                         ids=[c[0] for c in NAMED_STEP])  # fmt: skip
def test_a_name_wins_only_where_the_waveform_does_not_contradict_it(
    waveform: tuple[int, list[int]], refused: bool, why: str
) -> None:
    cap = capture({"train": (0, _TRAIN), "STEP": waveform, "DIR": (0, [])})
    p = propose(cap)
    assert p.named
    if not refused:
        assert p.map_args() == "--map step=STEP,dir=DIR" and not p.ambiguous, p.text()
        assert not name_conflicts(cap, {"step": 1})
        return
    assert not p.axes, p.text()
    (conflict,) = p.ambiguous
    assert "1='STEP' is named STEP, but its waveform is no STEP line" in conflict.question
    assert why in conflict.question
    # the named line first, then the line most like a STEP
    assert conflict.candidates[0].startswith("step=STEP: named so; ")
    assert conflict.candidates[1].startswith("step=train: pulse train: 30 high pulses")
    (refusal,) = name_conflicts(cap, {"step": 1})
    assert (refusal.role, refusal.ref, refusal.others) == ("step", "STEP", ("train",))


def _bus() -> Capture:
    """A line named ``step`` that changes in step with the falling edges of a clock, at most
    once a period: the data of that bus."""
    clk = _clock(400, 2 * US)
    data = [clk[k] for k in range(1, len(clk), 2) if (k * 7919) % 5 < 2]
    return capture({"SCK": (0, clk), "step": (0, data)})


def test_a_bus_line_named_step_is_refused() -> None:
    p = propose(_bus())
    assert not p.axes
    (conflict,) = p.ambiguous
    assert "data of bus clock 0='SCK'" in conflict.question, conflict


def test_up_down_named_lines_are_judged_each() -> None:
    """UP a step train, DOWN a clock: the pair is refused for DOWN."""
    cap = capture({"up": (0, _TRAIN), "down": (0, _clock(300))})
    p = propose(cap)
    assert not p.axes
    (conflict,) = p.ambiguous
    assert conflict.question.startswith("1='down' is named DOWN")


# ---------------------------------------------------------------- check: engine.auto_map


def test_check_refuses_a_clock_named_step_with_the_candidates() -> None:
    cap = capture({"train": (0, _TRAIN), "step": (0, _clock(200)), "dir": (0, [])})
    d = drive("rising", step_high=1000)
    with pytest.raises(UsageError) as err:
        run_check(cap, d)
    text = str(err.value)
    assert "1='step' is named STEP, but its waveform is no STEP line (clock" in text
    assert "e.g. --map step=train" in text and "--map step=step to check this line anyway" in text
    assert any(line.startswith("  - step=train: pulse train") for line in err.value.details)
    # the user's word settles it: mapped explicitly, the clock is checked as a STEP
    assert run_check(cap, d, {"step": "step"}).report.steps.count == 200
    # a DIR mapped by the user leaves the STEP to the name: still judged
    with pytest.raises(UsageError):
        run_check(cap, d, {"dir": "dir"})


def test_auto_map_judges_only_with_the_waveforms() -> None:
    """Without edges (a skeleton, ``follow``) the names map as before; with them, refused."""
    cap = capture({"step": (0, _clock(200)), "dir": (0, [])})
    assert auto_map(cap, step_type(0)) == {"step": "step", "dir": "dir"}
    with pytest.raises(UsageError, match="--map step=LINE"):
        auto_map(cap, step_type(0), waveforms=cap)


def test_check_of_a_named_step_train_is_unchanged() -> None:
    cap = capture({"step": (0, pulses(move(0, 19), 5 * US)), "dir": (0, [])})
    r = run_check(cap, drive("rising", step_high=1000)).report
    assert r.steps.count == 19


def test_channels_named_after_their_roles_are_what_check_maps() -> None:
    """Issue 26: a channel called ``step`` is the STEP ``check`` maps without --map
    (engine.auto_map); the proposal is that mapping, with what the waveform says against it (a
    step train named DIR; a STEP whose waveform is none is refused: test_named.py)."""
    step = pulses(move(0, 19), 5 * US)
    p = propose(capture({"DIR": (0, step), "STEP": (0, pulses([1003 * US], 5 * US))}))
    assert p.named and p.map_args() == "--map step=STEP,dir=DIR"
    assert all(r.basis == "name" for r in p.axes[0].roles)
    assert p.axes[0].role("step").evidence == "named 'STEP'; its waveform: changes 2 times"


def test_the_user_sees_the_refusal_and_the_candidates(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``wavecheck check`` of a VCD whose ``step`` is a clock: exit 2, one error line naming
    the line, the reason and both --map choices, the candidates below; ``info`` asks the same."""
    vcd = write_vcd(
        tmp_path / "named.vcd", {"step": (0, _clock(200)), "dir": (0, []), "X": (0, _TRAIN)}
    )
    assert main(["check", str(vcd), "--drive", "gecko-g202"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"wavecheck: error: {vcd}: 0='step' is named STEP, but its wave")
    assert "(e.g. --map step=X), or --map step=step to check this line anyway" in err[0]
    assert err[1:] == [
        "  candidates:",
        "    - step=step: named so; clock: 200 pulses, every period 10 us (100 kHz), 50% duty, "
        "no pause: a free-running clock, not a step signal",
        "    - step=X: pulse train: 30 high pulses of 5 us, gaps 95 us–365 us, rate up to 10 kHz",
    ]
    assert main(["info", str(vcd)]) == 0
    assert "ambiguous: 0='step' is named STEP" in capsys.readouterr().out
    assert main(["check", str(vcd), "--drive", "gecko-g202", "--map", "step=X"]) in (0, 1)


# ---------------------------------------------------------------- the work a name's judgement costs


def _strobed() -> Capture:
    """Bursts of 8 clock cycles with data changing on each falling edge, and after each burst
    a pulse on the line named ``step``, always 3 µs after the clock's last edge: a strobe."""
    clk: list[int] = []
    data: list[int] = []
    strobe: list[int] = []
    for b in range(30):
        t0 = 1000 * US + b * 200 * US
        burst = [t0 + k * 2 * US for k in range(16)]
        clk += burst
        data += [burst[k] for k in range(1, 16, 2) if (b * 16 + k) * 7919 % 5 < 2]
        strobe += [burst[-1] + 3 * US, burst[-1] + 4 * US]
    return capture({"SCK": (0, clk), "MOSI": (0, data), "step": (0, strobe)})


@pytest.mark.parametrize(("cap", "named", "why"), [
    (_bus(), {"step": 1}, "data of bus clock 0='SCK'"),
    (_strobed(), {"step": 2}, "a strobe of bus clock 0='SCK'"),
])  # fmt: skip
def test_a_bus_line_named_step_is_refused_by_check(
    cap: Capture, named: dict[str, int], why: str
) -> None:
    """The question is asked on the named lines' findings first (a strobe looked for beside a
    bus clock only); the refusal is :func:`propose`'s."""
    (refusal,) = name_conflicts(cap, named)
    assert why in refusal.conflict.question
    (conflict,) = propose(cap).ambiguous
    assert conflict == refusal.conflict


@pytest.mark.parametrize(("step", "refused", "looks"), [
    (_TRAIN, False, 0),  # a step train speeds up: no clock, told without its whole look
    (pulses([k * 50 * US for k in range(1, 40)], 5 * US), False, 1),  # one rate: looked at
    (_clock(200), True, 3),  # refused: every line's look, for the lines most like a STEP
])  # fmt: skip
def test_judging_a_name_looks_only_at_what_the_question_needs(
    monkeypatch: pytest.MonkeyPatch, step: list[int], refused: bool, looks: int
) -> None:
    """A named two-line capture (and a line beside it): its lines' whole looks
    (:func:`~wavecheck.roles.features.look_at`, the cost of judging a name on a capture of
    millions of edges) are made only where the question needs them."""
    import wavecheck.roles.state as state

    made: list[str] = []

    def counted(ch: Channel, cap: Capture) -> ChannelLook:
        made.append(ch.name)
        return look_at(ch, cap)

    monkeypatch.setattr(state, "look_at", counted)
    cap = capture({"step": (0, step), "dir": (0, [700 * US, 1400 * US]), "led": (1, [])})
    assert bool(name_conflicts(cap, {"step": 0, "dir": 1})) == refused
    assert len(made) == looks, made
