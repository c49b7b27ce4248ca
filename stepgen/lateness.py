"""Base-thread latency: when each make-pulses invocation really runs.

Invocation k is due at k·P and runs at ``t_k = max(k·P + l_k, t_{k−1} + G)``: l_k ≥ 0 is drawn
from the model, and G (``catchup_ns``, default 1 µs) is how long an invocation takes to run: the
next one cannot start before it ends (so after a latency longer than a period the thread catches
up G apart). So latency never reorders invocations, and times strictly increase. Every pin change
made by invocation k appears at t_k. With l_k ≤ P − G the clamp never acts.

For ``worst:J:RULE`` with P − G < J < P the clamp would act: an invocation J late ends after the
next, on-time one is due, which then starts late too, and an interval that ends right after a
late invocation is (n − 1)·P + G long instead of n·P − J. :func:`catchup_for` therefore takes
G = P − J when the run time was left at its default (a shorter run time only makes intervals
shorter: still the worst case), and notes it; a run time given explicitly is kept, with a
warning saying which length the intervals get instead (see :func:`catchup_for`).

Models (``--latency``; every time carries its unit, docs/reference.md "Numbers and units"; a J, SIGMA or
MAX below 100 ns other than 0 gives a warning):

``none``                every invocation on time: all edges on the k·P grid.
``uniform:J``           l_k uniform on the integers [0, J] ns (``--seed``).
``normal:SIGMA,MAX``    l_k = min(round(|N(0, SIGMA)|), MAX) — a half-normal (``--seed``).
``spike:J@EVERY``       l_k = J for the first invocation due at or after each multiple of EVERY
                        (not at 0), else 0 — Stepper Tuning's "every 64 s a 300 µs latency" is
                        ``spike:300us@64s``.
``histogram:FILE``      l_k drawn from cyclictest ``-h`` bins (b µs exactly), or a half-normal
                        from latency-histogram ``--nox`` sdev/max (see :mod:`stepgen.latencyfiles`).
``worst:J:RULE``        the assignment of l_k ∈ {0, J} that makes RULE's intervals shortest:
                        invocations that make an *end* event of the rule run on time, every
                        other one J late, so each interval is n·P − J (DESIGN "Worst case,
                        precisely"). RULE is one of step_high, step_low, step_period, dir_setup,
                        dir_hold (type 0), dir_delay (type 1), state_hold (types ≥ 2). For
                        step_period and state_hold, whose intervals start and end with the same
                        kind of event, those events alternate on time / late (for types ≥ 2
                        step_period is state_hold's intervals: the state changes).

The active STEP edge (rising by default; ``falling`` for a drive such as the Gecko G202 fed by a
non-inverted pin) decides which edges are the dir_setup, step_period and dir_delay events. With the falling
edge active, dir_hold runs from the end of the pulse to the DIR change: dirhold·P − J.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from stepgen.reference import InvocationRun
from wavecheck.errors import ConfigError, UnitError
from wavecheck.steptypes import kind_of
from wavecheck.units import LATENCY, Plausible, option_ns, shorten

if TYPE_CHECKING:
    from wavecheck.drives.datasheet import ActiveEdge

__all__ = [
    "DEFAULT_CATCHUP_NS",
    "RULES",
    "LatencyModel",
    "Clock",
    "catchup_for",
    "describe",
    "invocation_clock",
    "invocation_times",
    "parse_latency",
]

DEFAULT_CATCHUP_NS = 1000
RULES: tuple[str, ...]  # loaded on first use (module __getattr__ below)


def __getattr__(name: str) -> tuple[str, ...]:
    """``RULES``: the rules ``worst:J:RULE`` can target
    (:data:`wavecheck.linuxcnc.worstcase.WORST_RULES`), loaded with the worst-case module only
    when asked for (a simulation under another latency model does not need it: ~2 ms)."""
    if name == "RULES":
        from wavecheck.linuxcnc.worstcase import WORST_RULES

        return WORST_RULES
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class LatencyModel:
    """A parsed ``--latency`` model (see the module docstring). All times in integer ns."""

    kind: str
    text: str = "none"
    j_ns: int = 0
    sigma_ns: int = 0
    every_ns: int = 0
    rule: str = ""
    path: str = ""

    @property
    def random(self) -> bool:
        """True if the model draws from ``--seed``."""
        return self.kind in ("uniform", "normal", "histogram")


def _warn(message: str) -> None:
    print(f"stepgen: warning: {message}", file=sys.stderr)


def _ns(text: str, what: str, model: str, plausible: Plausible | None = LATENCY) -> int:
    """One time of a latency model in whole ns; a unit is required (:func:`parse_option`), and
    a latency below 100 ns is warned about."""
    try:
        value = option_ns(
            text.strip(), f"latency model {shorten(model)!r}: {what}", plausible, _warn
        )
    except UnitError as err:
        raise ConfigError(str(err)) from None
    if value < 0 or value.denominator != 1:
        raise ConfigError(
            f"latency model {shorten(model)!r}: {what} {shorten(text)!r} must be a whole number "
            "of ns >= 0"
        )
    return int(value)


def parse_latency(text: str) -> LatencyModel:
    """Parse a ``--latency`` string (``none``, ``uniform:11us``, ``worst:11us:step_high`` …).

    Raises:
        ConfigError: unknown model or bad value, one line with the value and a hint.
    """
    t = text.strip()
    kind, _, rest = t.partition(":")
    kind = kind.lower()
    if kind == "none" and not rest:
        return LatencyModel("none", t)
    if kind == "uniform" and rest:
        return LatencyModel("uniform", t, j_ns=_ns(rest, "J", t))
    if kind == "normal" and rest:
        parts = rest.split(",")
        if len(parts) != 2:
            raise ConfigError(f"latency model {t!r}: write normal:SIGMA,MAX (e.g. normal:2us,20us)")
        return LatencyModel(
            "normal", t, sigma_ns=_ns(parts[0], "SIGMA", t), j_ns=_ns(parts[1], "MAX", t)
        )
    if kind == "spike" and "@" in rest:
        j, every = rest.split("@", 1)
        every_ns = _ns(every, "EVERY", t, None)
        if every_ns <= 0:
            raise ConfigError(f"latency model {t!r}: EVERY must be > 0 (e.g. spike:300us@64s)")
        return LatencyModel("spike", t, j_ns=_ns(j, "J", t), every_ns=every_ns)
    if kind == "histogram" and rest:
        from stepgen.latencyfiles import check_latency_path  # only for latency files

        try:
            check_latency_path(rest)
        except ConfigError as err:
            raise ConfigError(f"latency model {t!r}: {err}") from None
        return LatencyModel("histogram", t, path=rest)
    if kind == "worst" and rest.count(":") == 1:
        j, rule = rest.split(":")
        rule = rule.strip().lower().replace("-", "_")
        from wavecheck.linuxcnc.worstcase import WORST_RULES

        if rule not in WORST_RULES:
            raise ConfigError(
                f"latency model {t!r}: unknown rule {rule!r} (rules: {', '.join(WORST_RULES)})"
            )
        return LatencyModel("worst", t, j_ns=_ns(j, "J", t), rule=rule)
    raise ConfigError(
        f"unknown latency model {text!r} (use none, uniform:J, normal:SIGMA,MAX, spike:J@EVERY, "
        "histogram:FILE or worst:J:RULE, e.g. worst:11us:step_high)"
    )


def _offsets(
    model: LatencyModel, run: InvocationRun, seed: int | None, active_edge: ActiveEdge
) -> np.ndarray | None:
    """l_k for every invocation (None for ``none``)."""
    n = run.n_periods
    base = run.config.base_period_ns
    if model.kind == "none":
        return None
    if model.kind == "uniform":
        return np.random.default_rng(seed).integers(0, model.j_ns + 1, n, dtype=np.int64)
    if model.kind == "normal":
        draw = np.abs(np.random.default_rng(seed).normal(0.0, float(model.sigma_ns), n))
        return np.minimum(np.rint(draw), model.j_ns).astype(np.int64)
    if model.kind == "spike":
        out = np.zeros(n, dtype=np.int64)
        m = np.arange(1, (n * base) // model.every_ns + 2, dtype=np.int64)
        k = -(-(m * model.every_ns) // base)  # first invocation due at or after m·EVERY
        out[k[k < n]] = model.j_ns
        return out
    if model.kind == "histogram":
        from stepgen.latencyfiles import read_histogram

        hist = read_histogram(model.path)
        rng = np.random.default_rng(seed)
        if hist.half_normal is not None:
            sigma, cap = hist.half_normal
            return np.minimum(np.rint(np.abs(rng.normal(0.0, float(sigma), n))), cap).astype(
                np.int64
            )
        return rng.choice(hist.values_ns, size=n, p=hist.weights).astype(np.int64)
    if model.kind == "worst":
        out = np.full(n, model.j_ns, dtype=np.int64)
        on_time = _end_events(model.rule, run, active_edge)
        out[on_time] = 0
        return out
    raise ConfigError(f"unknown latency model kind {model.kind!r}")


def _end_events(rule: str, run: InvocationRun, active_edge: ActiveEdge) -> np.ndarray:
    """Invocations that make the end events of ``rule``'s intervals (to run on time;
    :func:`wavecheck.linuxcnc.worstcase.end_events`)."""
    t = run.toggles
    stype = run.config.step_type
    kind = kind_of(stype)
    if active_edge == "both":
        raise ConfigError("the worst-case latency model needs one active edge (rising or falling)")
    if kind == "phases":
        lines = run.pins
    else:
        lines = ("step",) if kind == "step-dir" else ("up", "down")
    pulses = [(t[p][0::2], t[p][1::2]) for p in lines]  # pins start at 0: rise, fall, ...
    dirs = t["dir"] if kind == "step-dir" else np.zeros(0, np.int64)
    from wavecheck.linuxcnc.worstcase import end_events

    out = end_events(rule, kind, pulses, dirs, active_rising=active_edge == "rising")
    if out is not None:
        return out
    if kind == "phases":
        # a phase type's steps are its state changes: step_period measures the same intervals
        raise ConfigError(
            f"rule {rule!r} does not apply to step type {stype} (use state_hold or step_period)"
        )
    raise ConfigError(f"rule {rule!r} does not apply to step type {stype}")


def catchup_for(
    model: LatencyModel, base_ns: int, catchup_ns: int | None = None
) -> tuple[int, str | None]:
    """The run time G (ns) to use under ``model`` at base period ``base_ns``, and a note or None.

    ``catchup_ns`` None means "the default": ``DEFAULT_CATCHUP_NS``, lowered to P − J for
    ``worst:J:RULE`` when J > P − G so that the bound n·P − J is reached (see the module doc).
    An explicit G is kept; the note then warns when it prevents the bound.

    Raises:
        ConfigError: a run time < 1 ns (invocations must stay in order).
    """
    if catchup_ns is not None and catchup_ns < 1:
        raise ConfigError(
            f"catch-up gap {catchup_ns} ns must be >= 1 ns (keeps invocations in order)"
        )
    g = DEFAULT_CATCHUP_NS if catchup_ns is None else catchup_ns
    if model.kind != "worst":
        return g, None
    j, p = model.j_ns, base_ns
    if j >= p:
        return g, (
            f"{model.text}: J = {j} ns >= P = {p} ns: a late invocation runs after the next one "
            f"was due, the thread catches up {g} ns apart, and intervals are not n·P − J"
        )
    if g <= p - j:
        return g, None
    if catchup_ns is None:
        return p - j, (
            f"{model.text}: an invocation is taken to run in P − J = {p - j} ns (not "
            f"{DEFAULT_CATCHUP_NS} ns) so that one J late ends when the next is due and every "
            "interval reaches n·P − J"
        )
    return g, (
        f"warning: {model.text} with --catchup {g} ns > P − J = {p - j} ns: an invocation J late "
        f"delays the next, on-time one by {g - (p - j)} ns, so intervals ending right after a late "
        f"invocation are (n − 1)·P + {g} ns, not n·P − J (give --catchup {p - j} or less)"
    )


def invocation_times(
    model: LatencyModel,
    run: InvocationRun,
    seed: int | None = None,
    active_edge: ActiveEdge = "rising",
    catchup_ns: int | None = None,
) -> np.ndarray | None:
    """t_k in ns for every invocation, or None when every invocation is on time (k·P).

    ``catchup_ns`` is the run time G; None takes :func:`catchup_for`'s default.

    Raises:
        ConfigError: a rule that does not apply to the step type, a catch-up gap < 1 ns.
    """
    catchup_ns, _ = catchup_for(model, run.config.base_period_ns, catchup_ns)
    offs = _offsets(model, run, seed, active_edge)
    if offs is None:
        return None
    return _caught_up(offs, run.config.base_period_ns, catchup_ns)


def _caught_up(offs: np.ndarray, base: int, catchup_ns: int) -> np.ndarray:
    """t_k = max(k·P + l_k, t_{k−1} + G) for every k."""
    k = np.arange(len(offs), dtype=np.int64)
    due = k * base + offs
    # t_k = max(due_k, t_{k-1} + G)  ⇔  t_k − k·G = running max of (due_k − k·G)
    return np.maximum.accumulate(due - k * catchup_ns) + k * catchup_ns


@dataclass(frozen=True)
class Clock:
    """When the invocations of a run happen: :meth:`at` gives t_k (ns) for indices k.

    When no latency exceeds P − G no invocation is held back by the one before (t_k = k·P + l_k:
    see the module docstring), so only the offsets are kept and t_k is computed for the indices
    asked for; otherwise every t_k (:func:`invocation_times`)."""

    base_ns: int
    offsets: np.ndarray | None = None  #: l_k, when t_k = k·P + l_k
    times: np.ndarray | None = None  #: every t_k otherwise

    def at(self, k: np.ndarray) -> np.ndarray:
        """t_k (int64 ns) of the invocation indices ``k``."""
        if self.times is not None:
            return self.times[k]
        t = np.asarray(k, dtype=np.int64) * self.base_ns
        return t if self.offsets is None else t + self.offsets[k]


def invocation_clock(
    model: LatencyModel,
    run: InvocationRun,
    seed: int | None = None,
    active_edge: ActiveEdge = "rising",
    catchup_ns: int | None = None,
) -> Clock:
    """:func:`invocation_times` as a :class:`Clock` (the same times; arguments and errors as
    there), without the per-invocation arrays when no catch-up can act."""
    base = run.config.base_period_ns
    catchup_ns, _ = catchup_for(model, base, catchup_ns)
    offs = _offsets(model, run, seed, active_edge)
    if offs is None or not len(offs) or int(offs.max()) <= base - catchup_ns:
        return Clock(base, offsets=offs)
    return Clock(base, times=_caught_up(offs, base, catchup_ns))


def describe(model: LatencyModel, base_ns: int) -> str:
    """A short human description (used in VCD comments and summaries)."""
    if model.kind == "worst" and model.j_ns >= base_ns:
        return f"{model.text} (J >= P: late invocations catch up, intervals are not n·P − J)"
    return model.text
