"""stepgen.plan: the seed's worked numbers, the datasheet → LinuxCNC mapping, and properties."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stepgen.plan import PARAMS, latency_guidance, min_base_period_ns, plan, simple_base_period_ns
from stepgen.plan_render import plan_to_dict
from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.timing import evaluate, periods_needed, step_rate_hz

US = 1000


def make_drive(
    edge: str = "rising",
    high: Fraction | int | None = 2000,
    low: Fraction | int | None = 1000,
    setup: Fraction | int | None = 200,
    hold: Fraction | int | None = 200,
    max_rate_hz: Fraction | int | None = None,
    *,
    interface: str = "step-dir",
    drive_id: str = "test-drive",
) -> Drive:
    """A drive built in the test (figures in ns), independent of the rule files."""
    limits = {
        rule: Figure(Fraction(v), "T", "datasheet")
        for rule, v in (
            ("step_high", high),
            ("step_low", low),
            ("dir_setup", setup),
            ("dir_hold", hold),
        )
        if v is not None
    }
    rate = Figure(Fraction(max_rate_hz), "T", "datasheet") if max_rate_hz is not None else None
    return Drive(
        id=drive_id,
        name=drive_id,
        path=Path(f"{drive_id}.toml"),
        kind="user",
        interface=interface,  # type: ignore[arg-type]
        active_edge=edge,  # type: ignore[arg-type]
        limits=limits,
        max_rate=rate,
    )


#: The seed's drives, with the figures the seed quotes (seed 000 "Figure out what your drives expect").
G202 = make_drive("falling", 4500, 500, 1000, 20000, 200_000, drive_id="g202")
XYLOTEX = make_drive("rising", 2000, 1000, 200, 200, drive_id="xylotex")


# --------------------------------------------------------------------------- the seed's numbers


def test_simple_base_period_g202_seed() -> None:
    """Seed 000 "Choose your BASE_PERIOD": 20 us hold + 11 us latency = 31 us → 16,129 steps/s."""
    p = plan(G202, 11 * US)
    assert p.simple_base_period_ns == 31 * US
    assert plan_to_dict(p)["simple_base_period_step_rate_hz"] == 16_129


def test_minimum_base_period_xylotex_seed() -> None:
    """Seed 000: Xylotex 2 us + 11 us = 13 us minimum → 38,461 steps/s; also the default P."""
    p = plan(XYLOTEX, 11 * US)
    assert p.min_base_period_ns == 13 * US
    assert p.base_period_ns == 13 * US
    assert plan_to_dict(p)["min_base_period_step_rate_hz"] == 38_461
    assert plan_to_dict(p)["max_step_rate_hz"] == 38_461


def test_minimum_base_period_g202_seed() -> None:
    """Seed 000 "Use steplen...": 4.5 us high + 11 us = 15.5 us; the default rounds up to 16 us."""
    p = plan(G202, 11 * US)
    assert p.min_base_period_ns == Fraction(31, 2) * US
    assert p.base_period_ns == 16 * US


@pytest.mark.parametrize(
    ("source", "drive", "inverted", "period", "expect_periods", "rate", "shortest_ns"),
    [
        # seed 000 "Use steplen, stepspace, dirsetup, and/or dirhold": 16 us, dirhold 2, 31,250/s;
        # DESIGN "The seed's Gecko G202 story": falling edge, pin NOT inverted.
        (
            "seed000-g202-16us",
            G202,
            False,
            16 * US,
            {"dirhold": 2, "steplen": 1, "stepspace": 1, "dirsetup": 1},
            31_250,
            5 * US,
        ),
        # seed 000 "Choose your BASE_PERIOD": the simple 31 us period needs no lengthened parameter.
        (
            "seed000-g202-31us",
            G202,
            False,
            31 * US,
            {"dirhold": 1, "steplen": 1, "stepspace": 1, "dirsetup": 1},
            16_129,
            20 * US,
        ),
        # DESIGN: inverting the pin moves the active edge to the start: hold = (steplen+dirhold)·P − J.
        (
            "design-g202-inverted",
            G202,
            True,
            16 * US,
            {"dirhold": 1, "steplen": 1, "stepspace": 1, "dirsetup": 1},
            31_250,
            5 * US,
        ),
        # seed 000: Xylotex at 16 us: shortest output time 16 − 11 = 5 us, 31,250 steps/s.
        (
            "seed000-xylotex-16us",
            XYLOTEX,
            False,
            16 * US,
            {"dirhold": 1, "steplen": 1, "stepspace": 1, "dirsetup": 1},
            31_250,
            5 * US,
        ),
        # reference §9 [TWK]: P = 16 us, J = 11 us → shortest pulse 5 us.
        ("ref9-shortest-pulse", XYLOTEX, False, 16 * US, {"steplen": 1}, 31_250, 5 * US),
    ],
)
def test_seed_table(
    source: str,
    drive: Drive,
    inverted: bool,
    period: int,
    expect_periods: dict[str, int],
    rate: int,
    shortest_ns: int,
) -> None:
    p = plan(drive, 11 * US, period, step_inverted=inverted)
    for name, n in expect_periods.items():
        assert p.params[name].periods == n, (source, name)
        assert p.params[name].ns == n * period
    assert plan_to_dict(p)["max_step_rate_hz"] == rate
    assert p.shortest_output_ns == shortest_ns
    assert all(m >= 0 for m in p.margins_ns.values())


def test_g202_seed_hold_is_21us_at_16us() -> None:
    """Seed 000: "the minimum time from the end of the step pulse to the changing direction pin
    is 5+16=21 us" → margin 1 us over the 20 us hold."""
    p = plan(G202, 11 * US, 16 * US)
    hold = [r for r in p.requirements if r.rule == "dir_hold"]
    assert [r.worst_ns for r in hold] == [21 * US]
    assert p.margins_ns["dir_hold"] == 1 * US
    assert p.active_at == "end"


@pytest.mark.parametrize(
    ("source", "period", "dirhold", "hold_ns"),
    [
        ("seed000: P = 20 us, J = 11 us: 'the delay ... is only 9 us'", 20 * US, 1, 9 * US),
        (
            "seed000: P = 16 us, dirhold 1: '16 us − 11 us = 5 us, which is not enough'",
            16 * US,
            1,
            5 * US,
        ),
        ("seed000: P = 16 us, dirhold 2: '5+16 = 21 us'", 16 * US, 2, 21 * US),
    ],
)
def test_g202_hold_by_evaluate(source: str, period: int, dirhold: int, hold_ns: int) -> None:
    reqs = evaluate(
        G202, 11 * US, period, {"steplen": 1, "stepspace": 1, "dirsetup": 1, "dirhold": dirhold}
    )
    (hold,) = [r for r in reqs if r.rule == "dir_hold"]
    assert hold.worst_ns == hold_ns, source
    assert (hold.margin_ns >= 0) == (hold_ns >= 20 * US)


def test_inverted_reading_formula() -> None:
    """DESIGN: with the pin inverted the hold is (steplen + dirhold)·P − J and steplen is the
    drive's low ('0', t_active) time."""
    p = plan(G202, 11 * US, 16 * US, step_inverted=True)
    (hold,) = [r for r in p.requirements if r.rule == "dir_hold"]
    assert hold.params == ("steplen", "dirhold") and hold.worst_ns == 2 * 16 * US - 11 * US
    (pulse,) = [r for r in p.requirements if r.params == ("steplen",)]
    assert pulse.rule == "step_low"
    assert any("INVERTED" in a.upper() and "step_low" in a for a in p.assumptions)


def test_assumptions_state_the_reading() -> None:
    seed = plan(G202, 11 * US, 16 * US)
    text = " ".join(seed.assumptions)
    assert (
        "not inverted" in text
        and "END" in text
        and "G202 example of LinuxCNC's Stepper Tuning chapter" in text
    )
    assert "hold = dirhold·P − J" in text
    rising = plan(XYLOTEX, 11 * US)
    assert "START" in " ".join(rising.assumptions)


# --------------------------------------------------------------------------- warnings, guidance


@pytest.mark.parametrize(
    ("latency_us", "warn", "phrase"),
    [
        (11, False, "good"),  # seed: < 15-20 us very nice
        (25, False, "between"),
        (40, True, "usable"),  # seed: 30-50 us good results, disappointing rate
        (70, True, "hardware step generator"),
        (100, True, "not a candidate for software stepping"),  # seed: 100 us or more
    ],
)
def test_latency_guidance(latency_us: int, warn: bool, phrase: str) -> None:
    text, is_warning = latency_guidance(latency_us * US)
    assert is_warning is warn and phrase in text


def test_short_period_warning() -> None:
    assert any("below 25 us" in w for w in plan(XYLOTEX, 11 * US).warnings)
    assert not any("below 25 us" in w for w in plan(XYLOTEX, 11 * US, 25 * US).warnings)


def test_period_below_minimum_uses_two_periods() -> None:
    p = plan(G202, 11 * US, 12 * US)  # below 15.5 us: steplen needs 2 periods for 4.5 us
    assert p.params["steplen"].periods == 2
    assert any("below the minimum" in w for w in p.warnings)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("latency", [0, -1, Fraction(-11000), 1_000_001, 10**12])
def test_bad_latency(latency: Fraction | int) -> None:
    with pytest.raises(ConfigError) as info:
        plan(XYLOTEX, latency)
    assert "\n" not in str(info.value) and "latency" in str(info.value)


@pytest.mark.parametrize("period", [0, -16000, 11000, 5000, Fraction(31, 2)])
def test_bad_period(period: Fraction | int) -> None:
    with pytest.raises(ConfigError):
        plan(XYLOTEX, 11 * US, period)


@pytest.mark.parametrize("missing", ["step_high", "step_low", "dir_setup", "dir_hold"])
def test_incomplete_figures_name_the_missing_one(missing: str) -> None:
    kwargs: dict[str, None] = {
        {"step_high": "high", "step_low": "low", "dir_setup": "setup", "dir_hold": "hold"}[
            missing
        ]: None
    }
    drive = make_drive(**kwargs)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=f"gives no {missing} figure"):
        plan(drive, 11 * US)


def test_unsupported_drives() -> None:
    with pytest.raises(ConfigError, match="both"):
        plan(make_drive("both"), 11 * US)
    with pytest.raises(ConfigError, match="up-down"):
        plan(make_drive(interface="up-down"), 11 * US)


def test_rule_library_g202_matches_seed() -> None:
    """The shipped rule file gives the seed's G202 numbers (when the library is present)."""
    library = pytest.importorskip("wavecheck.drives.library")
    p = plan(library.load_drive("gecko-g202"), 11 * US, 16 * US)
    assert p.params["dirhold"].periods == 2
    assert p.simple_base_period_ns == 31 * US


# --------------------------------------------------------------------------- properties

ns_limits = st.one_of(
    st.integers(min_value=0, max_value=150_000),
    st.fractions(min_value=0, max_value=150_000, max_denominator=10),
)


@st.composite
def drives(draw: st.DrawFn) -> Drive:
    rate = draw(st.one_of(st.none(), st.integers(min_value=5_000, max_value=2_000_000)))
    return make_drive(
        draw(st.sampled_from(["rising", "falling"])),
        draw(ns_limits),
        draw(ns_limits),
        draw(ns_limits),
        draw(ns_limits),
        rate,
    )


@given(
    t=ns_limits,
    j=st.integers(min_value=0, max_value=1_000_000),
    p=st.integers(min_value=1, max_value=200_000),
)
def test_periods_needed_is_the_least_n(t: Fraction | int, j: int, p: int) -> None:
    n = periods_needed(t, j, p)
    assert n * p - j >= t
    assert n == 0 or (n - 1) * p - j < t


@settings(max_examples=300, deadline=None)
@given(
    drive=drives(),
    j=st.integers(min_value=1, max_value=1_000_000),
    inverted=st.booleans(),
    extra=st.one_of(st.none(), st.integers(min_value=1, max_value=300_000)),
)
def test_plan_properties(drive: Drive, j: int, inverted: bool, extra: int | None) -> None:
    period = None if extra is None else j + extra
    p = plan(drive, j, period, step_inverted=inverted)
    big_p = p.base_period_ns
    # every requirement holds: n·P − J ≥ T
    for r in p.requirements:
        assert r.worst_ns == r.periods * big_p - j
        assert r.margin_ns >= 0
    # each parameter above one period is the least that works: one period less breaks something
    for name in PARAMS:
        n = p.params[name].periods
        assert n >= 1 and p.params[name].ns == n * big_p
        if n > 1:
            shorter = p.with_params(**{name: n - 1})
            reqs = evaluate(drive, j, big_p, shorter, step_inverted=inverted)
            assert any(r.margin_ns < 0 for r in reqs), (name, p.params[name].reason)
    # rates: 1 / ((steplen + stepspace)·P), the min/simple figures as the seed computes them
    assert p.max_step_rate_hz == step_rate_hz(
        big_p, p.params["steplen"].periods + p.params["stepspace"].periods
    )
    assert p.min_base_period_ns == j + max(
        drive.limit_ns("step_high") or 0, drive.limit_ns("step_low") or 0
    )
    assert p.min_base_period_ns == min_base_period_ns(drive, j)
    assert p.simple_base_period_ns == simple_base_period_ns(drive, j) >= p.min_base_period_ns
    if period is None:
        # the minimum rounded up to a whole µs; P must also exceed J, which only matters when
        # both step limits are 0 (minimum == J): then the next whole µs above J
        assert big_p % 1000 == 0 and big_p > j
        assert 0 <= big_p - p.min_base_period_ns < 1000 or (
            p.min_base_period_ns == j and big_p - j <= 1000
        )
    if big_p >= p.min_base_period_ns:
        assert p.params["steplen"].periods == 1
        assert p.max_step_rate_hz <= step_rate_hz(big_p, 2)
    # with the simple period every parameter may stay at one period (unless fmax needs more)
    if drive.max_rate is None:
        simple = plan(
            drive, j, max(int(-(-p.simple_base_period_ns // 1)), j + 1), step_inverted=inverted
        )
        assert all(prm.periods == 1 for prm in simple.params.values())
