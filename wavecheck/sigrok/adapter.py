"""Everything the sigrok decoder asks of wavecheck's engine, in one module.

The decoder (:mod:`wavecheck.sigrok.decoder`) runs inside libsigrokdecode; all it knows of
wavecheck goes through :func:`open_check`, which returns a :class:`Check`:

- its :class:`Plan`: the step type, the roles of the decoder's channels, inversions, the active
  edge and every rule of the rule table (:mod:`wavecheck.rules`) that applies, with the drive
  library's limit (:func:`wavecheck.drives.library.load_drive`, ``--limit``/``--margin`` applied
  by :func:`wavecheck.drives.overrides.tune_drive`) and the engine's exact pass/fail thresholds in
  samples — the same drive, rules and thresholds ``wavecheck check`` uses;
- the engine (:class:`wavecheck.engine.run.MachineCheck`, fed
  :class:`~wavecheck.capture.blocks.EdgeBlock` s of the edges the decoder collects), whose figures
  make the summary row (:meth:`Check.summary`): per rule checked, violations, minimum margin,
  verdict; the step counts and rates at the end.

The engine is set up exactly as ``check`` sets it up for a ``.sr`` whose channels are named after
their roles (one :class:`~wavecheck.engine.options.CheckOptions`, the axis planned on a capture
skeleton: :func:`wavecheck.engine.run.machine_for`), so a rule, a limit or a verdict is never
restated here. Only this module imports the engine for the decoder: when the
engine's names change, this is the one place to follow them.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction

import numpy as np

from wavecheck.capture.blocks import EdgeBlock
from wavecheck.capture.edges import Capture, Channel
from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.engine import CheckOptions, MachineCheck, RuleResult, machine_for
from wavecheck.engine.planning import default_step_type, figure_of
from wavecheck.engine.planning import pulse_level as level_at_drive
from wavecheck.engine.planning import thresholds as engine_thresholds
from wavecheck.errors import UsageError
from wavecheck.rules import Rule, applicable
from wavecheck.steps.interface import build_interface, role_name
from wavecheck.steps.mapping import AxisMap
from wavecheck.steptypes import StepKind, StepType, step_type
from wavecheck.timebase import Timebase
from wavecheck.units import format_frequency, format_ns, parse_option

__all__ = [
    "CHANNEL_ROLES",
    "DECODER_API",
    "FAIL",
    "INDETERMINATE",
    "MEASURED",
    "PASS",
    "Check",
    "Plan",
    "RuleSpec",
    "open_check",
]

#: The interface the decoder (``pd.py``'s ``API``) expects of this module; change both together.
DECODER_API = 1
#: The decoder's outcome of one interval: passes, fails, undecided at the sampling resolution,
#: or measured but not judged (the drive states no limit, or there is no sample rate).
PASS, FAIL, INDETERMINATE, MEASURED = 0, 1, 2, 3
#: The decoder's channels in ``pd.py``'s order (the required one, then the optional ones) → the
#: role each plays for a kind of step type (None: not used by that kind). Two phases at most:
#: every channel a decoder declares costs libsigrokdecode time at every sample.
CHANNEL_ROLES: Mapping[StepKind, tuple[str | None, ...]] = {
    "step-dir": ("step", "dir", "enable"),
    "up-down": ("up", "down", "enable"),
    "phases": ("phase-A", "phase-B", "enable"),
}
#: The decoder's channel names (``pd.py``), for messages.
CHANNEL_NAMES = ("STEP/UP/A", "DIR/DOWN/B", "ENABLE")
UNITS = ("auto", "ns", "us", "ms", "samples")
_UNIT_NS = {"ns": 1, "us": 10**3, "ms": 10**6}
#: Edges the decoder gathers before handing them to the block engine.
FEED_EDGES = 4096
#: The shortest ``pause`` taken (s): a summary so far after every pause shorter than this would
#: come every few edges (one grbl capture: 251,359 summaries with ``pause=1fs``).
PAUSE_FLOOR_S = Fraction(1, 1000)
#: The longest ``pause`` taken (s): a day (libsigrokdecode counts samples in 64 bits).
PAUSE_CEILING_S = Fraction(86_400)


@dataclass(frozen=True)
class RuleSpec:
    """One rule of the table as the decoder measures it: its limit and the engine's thresholds.

    ``pass_min``/``fail_max`` (samples): pass ⟺ W ≥ pass_min, fail ⟺ W ≤ fail_max, pass tested
    first (:func:`wavecheck.engine.judge.evaluate`); None when the rule is only measured.
    """

    rule: Rule
    limit_ns: Fraction | None
    pass_min: int | None = None
    fail_max: int | None = None

    def outcome(self, ticks: int) -> int:
        """PASS, FAIL, INDETERMINATE, or MEASURED for an interval of ``ticks`` samples."""
        if self.pass_min is None or self.fail_max is None:
            return MEASURED
        if ticks >= self.pass_min:
            return PASS
        return FAIL if ticks <= self.fail_max else INDETERMINATE


@dataclass(frozen=True)
class Plan:
    """What the decoder measures and how (levels are at the drive's input, after inversion)."""

    step_type: StepType
    roles: tuple[str | None, ...]
    """The role of each decoder channel (None: unassigned, or not used by this step type)."""
    inverted: frozenset[str]
    active_edge: ActiveEdge
    forward_level: int
    pulse_level: int
    """The level of the generator's pulses at the drive's input (``dir_delay``'s pulse ends)."""
    rules: tuple[RuleSpec, ...]
    timebase: Timebase | None
    """None: no sample rate (intervals in samples, nothing judged)."""
    resolution_ns: Fraction | None
    unit: str
    drive: Drive | None
    notes: tuple[str, ...] = ()

    def duration(self, ns: Fraction, *, signed: bool = False) -> str:
        """``ns`` in the chosen unit (``"9 us"``, ``"-11 us"``, ``"18 samples"``)."""
        sign = "+" if signed else ""
        if self.unit == "samples" and self.timebase is not None:
            n = ns / self.timebase.tick_ns
            text = f"{n.numerator:{sign}d}" if n.denominator == 1 else f"{float(n):{sign}.4g}"
            return f"{text} samples"
        scale = _UNIT_NS.get(self.unit)
        if scale is None:
            return format_ns(ns, signed=signed)
        return f"{float(ns / scale):{sign}.4g} {self.unit}"

    def interval(self, ticks: int) -> str:
        """``ticks`` samples as a duration (in samples when the sample rate is not known)."""
        if self.timebase is None:
            return f"{ticks} samples"
        return self.duration(self.timebase.tick_ns * ticks)

    def margin(self, spec: RuleSpec, ticks: int) -> str:
        """measured − limit, signed."""
        assert self.timebase is not None and spec.limit_ns is not None
        return self.duration(self.timebase.tick_ns * ticks - spec.limit_ns, signed=True)

    def limit(self, spec: RuleSpec) -> str:
        """The rule's limit."""
        assert spec.limit_ns is not None
        return self.duration(spec.limit_ns)

    def rate(self, ticks: int) -> str:
        """The step rate of a step period of ``ticks`` samples (``"4.065 kHz"``)."""
        if self.timebase is None or ticks <= 0:
            return f"1/{ticks} samples"
        return format_frequency(Fraction(10**9) / (self.timebase.tick_ns * ticks), 4)


def _text(options: Mapping[str, object], key: str) -> str:
    return str(options.get(key, "")).strip()


def _drive(options: Mapping[str, object]) -> Drive | None:
    """The ``drive`` option: an id or a rule file (or a :class:`Drive`, from Python), tuned by
    ``limit`` (``step_high=5us dir_hold=20us``) and ``margin`` (``2x``, ``+500ns``)."""
    ref = options.get("drive")
    limits = _text(options, "limit").replace(";", " ").split()
    margin = _text(options, "margin") or None
    if isinstance(ref, Drive):
        return tune_drive(ref, limits, margin)
    text = str(ref or "").strip()
    return tune_drive(load_drive(text), limits, margin) if text else None


def _step_type(options: Mapping[str, object], drive: Drive | None) -> StepType:
    text = _text(options, "type") or "drive"
    if text == "drive":
        number = default_step_type(drive) if drive is not None else 0
    elif text.isdigit():
        number = int(text)
    else:
        raise UsageError(f"type {text!r}: give a LinuxCNC step type 0..15 or 'drive'")
    table_text = _text(options, "user_table").replace(" ", "")
    try:
        table = tuple(int(v, 0) for v in table_text.split("+") if v) or None
    except ValueError:
        raise UsageError(f"user_table {table_text!r}: give state values as 1+3+2+0") from None
    return step_type(number, table)


def _choice(options: Mapping[str, object], key: str, allowed: Sequence[str], default: str) -> str:
    value = _text(options, key) or default
    if value not in allowed:
        raise UsageError(f"{key} {value!r}: give one of {', '.join(allowed)}")
    return value


def _roles(st: StepType, assigned: Sequence[bool]) -> tuple[str | None, ...]:
    roles = tuple(
        role if k < len(assigned) and assigned[k] else None
        for k, role in enumerate(CHANNEL_ROLES[st.kind])
    )
    layout = CHANNEL_ROLES[st.kind]
    for role in st.outputs if st.kind != "step-dir" else ("step",):
        if role not in layout:
            raise UsageError(
                f"step type {st.number} ({st.name}) has {len(st.outputs)} phases; the decoder "
                "takes two (types 0, 1, 2 and two-phase user tables): check it with wavecheck "
                "check"
            )
        if role not in roles:
            k = layout.index(role)
            raise UsageError(
                f"step type {st.number} ({st.name}) needs its {role} on channel "
                f"{CHANNEL_NAMES[k]}: assign it"
            )
    return roles


def _skeleton(roles: Sequence[str | None], timebase: Timebase, known: bool) -> Capture:
    """A capture with no edges whose channels are named after the mapped roles."""
    empty = np.zeros(0, dtype=np.int64)
    channels = [
        Channel(role, k, 0, empty.copy(), counted=0)
        for k, role in enumerate(r for r in roles if r is not None)
    ]
    rate = 1 / timebase.tick_s if known else None
    return Capture("sigrok", "sigrok-decoder", timebase, 1, rate, 0, 0, channels, time_known=known)


@dataclass
class Check:
    """One decoder run: its :class:`Plan`, and the block engine fed the decoder's edges."""

    plan: Plan
    engine: MachineCheck | None = None
    skeleton: Capture | None = None
    pause: int = 0
    """The ``pause`` option in samples (0: none): a summary so far after each pause that long."""
    _parts: list[list[int]] = field(default_factory=list)
    _pending: int = 0
    _first: dict[int, tuple[int, int]] | None = None
    _end: int = 0
    _counts: dict[str, int] = field(default_factory=dict)

    def start(self, levels: Sequence[int]) -> None:
        """The raw level of each mapped channel at sample 0 (in the mapped roles' order)."""
        self._parts = [[] for _ in levels]
        self._first = {k: (0, int(v)) for k, v in enumerate(levels)}

    def edge(self, tick: int, changed: Sequence[int]) -> None:
        """The mapped channels ``changed`` (their indices) at sample ``tick``."""
        if self.engine is None:
            return
        for k in changed:
            self._parts[k].append(tick)
        self._pending += len(changed)
        self._end = tick + 1
        if self._pending >= FEED_EDGES:
            self._feed()

    def _feed(self) -> None:
        assert self.engine is not None
        block = EdgeBlock(
            end=self._end,
            edges={k: np.array(p, dtype=np.int64) for k, p in enumerate(self._parts) if p},
            known=self._first or {},
            start=0 if self._first is not None else None,
        )
        self._first = None
        self._parts = [[] for _ in self._parts]
        self._pending = 0
        self.engine.feed(block)

    def summary(self, end: int, *, final: bool) -> list[list[str]]:
        """The summary row's texts (each a list of long-to-short variants): the overall line,
        then one per rule, as ``check`` gives them for the input up to ``end`` (a copy of the
        engine finishes there: more input may follow); ``final``: the input has ended (else the
        lines say "so far")."""
        if self.engine is None or self.skeleton is None:
            return []
        self._end = max(self._end, end)
        self._feed()
        engine = copy.deepcopy(self.engine)
        report = engine.finish(replace(self.skeleton, end=self._end)).axes[0]
        rules, steps, verdict, rates = report.rules, report.steps, report.verdict, report.rates
        self._counts = {r.rule: r.violations for r in rules}
        assert self.plan.drive is not None
        fails = sum(r.violations for r in rules)
        head = "" if final else "so far: "
        top = (
            f"{head}{verdict.upper()} against {self.plan.drive.id}: {fails} violation(s), "
            f"{steps.count} steps"
        )
        if steps.final_position is not None:
            top += f", final position {steps.final_position:+d}"
        if rates is not None and rates.observed is not None:
            top += f", up to {format_frequency(rates.observed, 4)}"
        return [[top, f"{head}{verdict.upper()}"], *(_rule_line(r) for r in rules)]

    def resolution(self) -> str:
        """The resolution the verdicts assume (``"500 ns"``)."""
        return format_ns(self.plan.resolution_ns) if self.plan.resolution_ns is not None else "-"

    def violations(self) -> dict[str, int]:
        """Violations per rule as the block engine counted them (at the last :meth:`summary`)."""
        return dict(self._counts)


def _rule_line(r: RuleResult) -> list[str]:
    text = f"{r.rule}: {r.verdict}, {r.checked} checked, {r.violations} violation(s)"
    if r.indeterminate:
        text += f", {r.indeterminate} indeterminate"
        decide = r.decide_samplerate_hz
        if decide is not None:
            text += f" (a sample rate ≥ {format_frequency(decide, 4)} decides them)"
    if r.min_margin_ns is not None:
        text += f", min margin {format_ns(r.min_margin_ns, signed=True)}"
    return [text, f"{r.rule}: {r.verdict}"]


def open_check(
    options: Mapping[str, object], samplerate: int | None, assigned: Sequence[bool]
) -> Check:
    """Resolve the decoder's options (as libsigrokdecode gives them) for a capture sampled at
    ``samplerate`` Hz (None or 0: not known) with the decoder channels ``assigned``.

    Raises:
        WavecheckError: an unknown drive, a bad rule file or option value, a missing channel.
    """
    drive = _drive(options)
    st = _step_type(options, drive)
    roles = _roles(st, assigned)
    inverted = frozenset(role_name(r) for r in _text(options, "invert").replace("+", " ").split())
    unknown = sorted(inverted - {r for r in roles if r is not None})
    if unknown:
        raise UsageError(f"invert {' '.join(unknown)}: no channel of that role is assigned")
    edge_opt = _choice(options, "active_edge", ("drive", "rising", "falling", "both"), "drive")
    forward = _choice(options, "dir_forward", ("low", "high"), "low") == "high"
    generator = _choice(options, "pulse_level", ("high", "low"), "high") == "high"
    unit = _choice(options, "unit", UNITS, "auto")
    res_text = _text(options, "resolution")
    resolution = parse_option(res_text, "resolution", "time") if res_text else None
    known = bool(samplerate and samplerate > 0)
    timebase = (
        Timebase.from_samplerate(samplerate) if known and samplerate else Timebase(Fraction(1))
    )
    skeleton = _skeleton(roles, timebase, known)
    mapping = {r: r for r in roles if r is not None}
    edge: ActiveEdge
    if edge_opt != "drive":
        edge = edge_opt  # type: ignore[assignment]
    else:
        edge = drive.active_edge if drive is not None else "rising"
    iface = build_interface(skeleton, mapping, sorted(inverted))
    level = level_at_drive(iface, st, int(generator))
    table = st.states if st.number == 15 else None
    engine = None
    resolution_ns: Fraction | None = None
    if drive is not None and known:
        check_options = CheckOptions(
            drive={None: drive}, axes=(AxisMap(None, mapping),), step_type={None: st.number},
            forward_level={None: int(forward)}, invert=tuple(sorted(inverted)),
            active_edge=edge, user_table=table, pulse_level=int(generator),
            resolution=resolution, keep_violations=1,
        )  # fmt: skip
        engine = machine_for(skeleton, check_options, check_options.axes)
        axis_plan = engine.axes[0].plan
        notes = [*axis_plan.notes, *filter(None, [axis_plan.resolution_note])]
        resolution_ns = axis_plan.resolution_ns
    elif drive is None:
        notes = ["no drive chosen (option drive): intervals measured, nothing judged"]
    else:
        notes = ["no sample rate: intervals in samples, nothing judged"]
    tb = timebase if known else None
    rules = tuple(_spec(r, drive, tb, resolution_ns) for r in applicable(st.kind))
    plan = Plan(
        st, roles, inverted, edge, int(forward), level, rules, tb, resolution_ns, unit, drive,
        tuple(notes),
    )  # fmt: skip
    return Check(plan, engine, skeleton, _pause(options, timebase if known else None))


def _pause(options: Mapping[str, object], timebase: Timebase | None) -> int:
    """The ``pause`` option in samples (0: not given, or no sample rate to count it in)."""
    text = _text(options, "pause")
    if not text:
        return 0
    seconds = parse_option(text, "pause", "time")
    if seconds < PAUSE_FLOOR_S:
        raise UsageError(
            f"pause {text}: below the floor of {format_ns(PAUSE_FLOOR_S * 10**9)} (a summary "
            "after every shorter pause would come every few edges): give e.g. 100ms, or "
            "nothing for a summary at the end only"
        )
    if seconds > PAUSE_CEILING_S:
        raise UsageError(f"pause {text}: above the ceiling of a day: give e.g. 100ms")
    if timebase is None:
        return 0
    return max(1, int(seconds / timebase.tick_s))


def _spec(
    r: Rule, drive: Drive | None, timebase: Timebase | None, resolution_ns: Fraction | None
) -> RuleSpec:
    fig = figure_of(drive, r) if drive is not None else None
    if fig is None or timebase is None or resolution_ns is None:
        return RuleSpec(r, fig[0] if fig is not None else None)
    pass_min, fail_max = engine_thresholds(fig[0], timebase.tick_ns, resolution_ns)
    return RuleSpec(r, fig[0], pass_min, fail_max)
