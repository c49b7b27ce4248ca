"""The libsigrokdecode protocol decoder ``wavecheck`` (API version 3).

libsigrokdecode imports this package under its folder name, ``wavecheck`` (the name ``-P`` and
PulseView use), so the real ``wavecheck`` package is imported only in :meth:`Decoder.decode`, after
this package has stepped out of its way in ``sys.modules`` (:func:`_wavecheck`), from the paths
``wavecheck sigrok install`` recorded in ``install.json`` beside this file (libsigrokdecode's
embedded Python does not see the virtual environment wavecheck lives in).

Per edge (``wait()`` on an edge of any assigned channel) the judge
(:mod:`wavecheck.sigrok.judge`) decides the intervals that edge closes and the decoder puts
them at once: nothing tells a decoder that the capture has ended (module doc of the judge). The
edges also go to the block engine, whose summary is put when libsigrokdecode ends the input
(sigrok-cli) and, optionally, at every pause of ``pause`` without an edge (PulseView).
"""

from __future__ import annotations

import importlib
import json
import os
import sys
import threading
from typing import Any

try:
    import sigrokdecode as srd
except ImportError:  # imported outside libsigrokdecode (tests, tools): a plain base class
    srd = None

_Base: Any = srd.Decoder if srd is not None else object
#: What this copy of the decoder expects of :mod:`wavecheck.sigrok.adapter` (its ``DECODER_API``):
#: an installed copy older or newer than the wavecheck it imports says so instead of failing.
API = 1
_HERE = os.path.dirname(os.path.abspath(__file__))
_LOCK = threading.Lock()
_ADAPTER: dict[str, Any] = {}

CHANNELS = ({"id": "step", "name": "STEP/UP/A", "desc": "STEP (type 0), UP (type 1) or phase A"},)
#: As few as can be: libsigrokdecode 0.5.3 copies every declared channel's level at every sample,
#: assigned or not, so each one costs time on long captures (hence no phases C to E).
OPTIONAL_CHANNELS = (
    {"id": "dir", "name": "DIR/DOWN/B", "desc": "DIR (type 0), DOWN (type 1) or phase B"},
    {"id": "enable", "name": "ENABLE", "desc": "ENABLE (active high; invert=enable if low)"},
)
#: Annotation classes. PulseView 0.4.2 colours a class by the hue of the decode signal (green
#: for the first) + 20° per row + 55° per class index: this order makes a violation red and an
#: indeterminate one orange, and nothing else red but the messages.
ANNOTATIONS = (
    ("high", "STEP high time"),
    ("low", "STEP low time"),
    ("setup", "DIR setup"),
    ("hold", "DIR hold"),
    ("rate", "Step rate"),
    ("enable", "ENABLE setup"),
    ("state", "Phase state held"),
    ("delay", "UP/DOWN switch delay"),
    ("position", "Position"),
    ("message", "Message"),
    ("fail", "Violation"),
    ("indeterminate", "Indeterminate at this sample rate"),
    ("rule", "Summary"),
)
_CLASS = {name: k for k, (name, _) in enumerate(ANNOTATIONS)}
ANNOTATION_ROWS = (
    ("widths", "Pulse widths", (0, 1, 6)),
    ("dir", "DIR and ENABLE timing", (2, 3, 5, 7)),
    ("violations", "Violations", (10, 11)),
    ("steps", "Position", (8,)),
    ("rates", "Step rate", (4,)),
    ("summary", "Summary", (12,)),
    ("messages", "Messages", (9,)),
)
OPTIONS = (
    {"id": "drive", "desc": "Drive id (wavecheck drives) or rule file", "default": ""},
    {
        "id": "type",
        "desc": "LinuxCNC step type (0 step/dir, 1 up/down, 2-15 phases)",
        "default": "drive",
        "values": ("drive", *(str(n) for n in range(16))),
    },
    {"id": "user_table", "desc": "Type 15 states (1+3+2+0)", "default": ""},
    {
        "id": "active_edge",
        "desc": "Active STEP edge",
        "default": "drive",
        "values": ("drive", "rising", "falling", "both"),
    },
    {"id": "invert", "desc": "Roles to invert (step dir enable)", "default": ""},
    {
        "id": "dir_forward",
        "desc": "DIR level = forward",
        "default": "low",
        "values": ("low", "high"),
    },
    {
        "id": "pulse_level",
        "desc": "Generator pulse level",
        "default": "high",
        "values": ("high", "low"),
    },
    {"id": "limit", "desc": "Limits to override (step_high=5us dir_hold=20us)", "default": ""},
    {"id": "margin", "desc": "Tighten every limit (2x, +500ns)", "default": ""},
    {"id": "resolution", "desc": "Resolution (default: one sample)", "default": ""},
    {
        "id": "unit",
        "desc": "Units shown",
        "default": "auto",
        "values": ("auto", "ns", "us", "ms", "samples"),
    },
    {
        "id": "pause",
        "desc": "Summary after a pause of (e.g. 200ms; empty: at the end)",
        "default": "",
    },
)


class _Unusable(Exception):
    """The decoder cannot check (its message says why and what to do)."""


def _install_record() -> dict[str, Any]:
    """What ``wavecheck sigrok install`` recorded (paths, Python version), or {}."""
    try:
        with open(os.path.join(_HERE, "install.json"), encoding="utf-8") as fh:
            data = json.load(fh)
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _wavecheck() -> Any:
    """The adapter module of the real ``wavecheck`` package (imported once).

    This decoder is ``sys.modules["wavecheck"]`` while libsigrokdecode loads it; the real package
    takes the name over (libsigrokdecode keeps its own references to this module).
    """
    with _LOCK:
        if "adapter" in _ADAPTER:
            return _ADAPTER["adapter"]
        record = _install_record()
        import site

        # numpy's BLAS would start a thread per core for nothing: the decoder uses no BLAS
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        paths = [p for p in record.get("paths", []) if isinstance(p, str)]
        for p in reversed(paths):
            if p not in sys.path:
                sys.path.insert(0, p)
        for p in paths:
            site.addsitedir(p)  # runs .pth files (an editable install's finder)
        mine = {
            n: m for n, m in sys.modules.items() if n == "wavecheck" or n.startswith("wavecheck.")
        }
        loaded = getattr(sys.modules.get("wavecheck"), "__file__", None) or ""
        ours = os.path.realpath(loaded) == os.path.realpath(os.path.join(_HERE, "__init__.py"))
        if ours:
            for name in mine:
                del sys.modules[name]
        # this decoder's own folder (libsigrokdecode's decoder directory) would be found first
        where = os.path.dirname(_HERE)
        at = [i for i, p in enumerate(sys.path) if os.path.realpath(p) == os.path.realpath(where)]
        for i in reversed(at):
            del sys.path[i]
        try:
            adapter = importlib.import_module("wavecheck.sigrok.adapter")
        except Exception as err:
            if ours:
                for name in [
                    n for n in sys.modules if n == "wavecheck" or n.startswith("wavecheck.")
                ]:
                    del sys.modules[name]
                sys.modules.update(mine)
            raise _Unusable(_import_help(err, record)) from None
        finally:
            for i in at:
                sys.path.insert(i, where)
        if getattr(adapter, "DECODER_API", None) != API:
            raise _Unusable(
                "wavecheck decoder: this copy of the decoder does not match wavecheck "
                f"{getattr(sys.modules.get('wavecheck'), '__version__', '?')}: run "
                "'wavecheck sigrok install' again"
            )
        _ADAPTER["adapter"] = adapter
        return adapter


def _import_help(err: Exception, record: dict[str, Any]) -> str:
    here = "{}.{}".format(*sys.version_info[:2])
    text = (
        f"wavecheck decoder: cannot import wavecheck ({type(err).__name__}: {err}) "
        f"in libsigrokdecode's Python {here}"
    )
    if not record:
        return text + "; run 'wavecheck sigrok install' from the Python that has wavecheck"
    made = record.get("python", "?")
    if made != here:
        return text + (
            f"; it was installed from Python {made}, whose compiled modules (numpy) this Python "
            f"cannot load: install wavecheck into a Python {here} environment and run "
            "'wavecheck sigrok install' from it"
        )
    return text + f"; searched {record.get('paths')}: run 'wavecheck sigrok install' again"


class Decoder(_Base):  # type: ignore[misc]
    """STEP/DIR timing against a drive's datasheet (module docstring)."""

    api_version = 3
    id = "wavecheck"
    name = "wavecheck"
    longname = "Stepper STEP/DIR timing (wavecheck)"
    desc = "STEP/DIR pulse widths, DIR setup/hold and step rate against a drive datasheet."
    license = "mit"
    inputs = ["logic"]
    outputs: list[str] = []
    tags = ["Embedded/industrial"]
    channels = CHANNELS
    optional_channels = OPTIONAL_CHANNELS
    options = OPTIONS
    annotations = ANNOTATIONS
    annotation_rows = ANNOTATION_ROWS

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.samplerate = 0
        self.out_ann: Any = None

    def metadata(self, key: int, value: int) -> None:
        if srd is not None and key == srd.SRD_CONF_SAMPLERATE:
            self.samplerate = int(value)

    def start(self) -> None:
        self.out_ann = self.register(srd.OUTPUT_ANN)

    # -- output ----------------------------------------------------------------------------------
    def _put(self, ss: int, es: int, cls: str, texts: list[str]) -> None:
        self.put(min(ss, es), max(ss, es), self.out_ann, [_CLASS[cls], texts])

    def _message(self, text: str, until: int | None = None) -> None:
        """A message on the messages row, from sample 0 (to ``until``, else about a second)."""
        span = until if until is not None else max(self.samplerate, 1_000_000)
        self._put(0, span, "message", [text, text.split(":")[0]])

    # -- decoding --------------------------------------------------------------------------------
    def decode(self) -> None:
        try:
            adapter = _wavecheck()
            from wavecheck.errors import WavecheckError
            from wavecheck.sigrok.judge import Judge

            assigned = [self.has_channel(k) for k in range(1 + len(OPTIONAL_CHANNELS))]
            try:
                check = adapter.open_check(self.options, self.samplerate, assigned)
            except WavecheckError as err:
                raise _Unusable(f"wavecheck decoder: {err}") from None
        except _Unusable as err:
            self._message(str(err))
            sys.stderr.write(f"{err}\n")  # also where PulseView and sigrok-cli log
            self._idle()
            return
        try:
            _Run(self, check, Judge(check.plan)).loop()
        except Exception as err:  # a bug: said on the Messages row, not a traceback per sample
            text = f"wavecheck decoder: internal error {type(err).__name__}: {err} (please report)"
            self._message(text)
            sys.stderr.write(text + "\n")
            self._idle()

    def _idle(self) -> None:
        """Take the samples without looking at them (libsigrokdecode 0.5 needs a decoder to keep
        waiting), until the input ends."""
        try:
            while True:
                self.wait({"skip": 1 << 40})
        except (EOFError, SystemError):
            return


class _Run:
    """One pass over the input: the wait loop and the annotations."""

    def __init__(self, pd: Decoder, check: Any, judge: Any) -> None:
        from wavecheck.sigrok.adapter import FAIL, INDETERMINATE
        from wavecheck.sigrok.judge import INTERVAL, STEP

        self.kinds = (INTERVAL, STEP)
        self.flagged = (FAIL, INDETERMINATE)
        self.pd = pd
        self.check = check
        self.judge = judge
        self.plan = check.plan
        self.chans = [k for k, role in enumerate(self.plan.roles) if role is not None]
        self.classes = [_class_of(s.rule) for s in self.plan.rules]
        self.labels = [_label_of(s.rule) for s in self.plan.rules]
        self.last_step: int | None = None
        self.steps = 0
        self.counts: dict[str, int] = {}
        self.texts: dict[tuple[int, int], list[str]] = {}  # (rule, samples) → texts: they repeat
        self.ids = [_CLASS[c] for c in self.classes]

    def _texts(self, k: int, w: int) -> list[str]:
        """The texts of an interval of rule ``k``, ``w`` samples long (long to short)."""
        texts = self.texts.get((k, w))
        if texts is None:
            if len(self.texts) > 1 << 16:
                self.texts.clear()
            if self.classes[k] == "rate":
                rate = self.plan.rate(w)
                texts = [rate, rate.split()[0]]
            else:
                measured = self.plan.interval(w)
                texts = [f"{self.labels[k]} {measured}", measured]
            self.texts[(k, w)] = texts
        return texts

    def loop(self) -> None:
        """Wait for an edge of any assigned channel (or, with ``pause``, that long without one),
        judge and annotate it; the summary when the input ends."""
        pd, judge, show, feed, chans = self.pd, self.judge, self._show, self.check.edge, self.chans
        pins = pd.wait()
        raw = [pins[k] for k in chans]
        judge.start(raw)
        self.check.start(raw)
        pause = self._pause()
        edges: list[dict[Any, Any]] = [{k: "e"} for k in chans]
        waiting = edges + [{"skip": pause}] if pause else edges
        conds, last = edges, 0
        try:
            while True:
                pins = pd.wait(conds)
                t = pd.samplenum
                if conds is not edges and pd.matched[-1]:  # a pause: the summary so far
                    self._summary(last, t, final=False)
                    conds = edges
                    continue
                if last == 0:
                    for note in self.plan.notes:
                        pd._message("wavecheck: " + note, until=t)
                for out in judge.at(t, [pins[k] for k in chans]):
                    show(out)
                feed(t, judge.changed)
                conds, last = waiting, t
        except (EOFError, SystemError) as end:  # libsigrokdecode ends the input (module doc)
            if isinstance(end, SystemError) and "wait" not in str(end):
                raise
        self._summary(0, last, final=True)

    def _pause(self) -> int:
        options: Any = self.pd.options  # libsigrokdecode's dict of option values
        text = str(options.get("pause", "")).strip()
        if not text or self.plan.timebase is None or self.check.engine is None:
            return 0
        from wavecheck.units import parse_option

        seconds = parse_option(text, "pause", "time")
        return max(1, int(seconds / self.plan.timebase.tick_s))

    def _show(self, out: tuple[int, int, int, int, int]) -> None:
        kind = out[0]
        plan, pd = self.plan, self.pd
        if kind == self.kinds[0]:  # an interval: (rule, start, end, outcome)
            _, k, start, end, outcome = out
            texts = self._texts(k, end - start)
            if start <= end:
                pd.put(start, end, pd.out_ann, [self.ids[k], texts])
            else:  # a negative up/down switch delay (overlapping pulses)
                pd.put(end, start, pd.out_ann, [self.ids[k], texts])
            if outcome in self.flagged:
                self._violation(plan.rules[k], start, end, end - start, outcome)
        elif kind == self.kinds[1]:  # a step: (sample, direction, position)
            _, t, direction, position, _ = out
            self.steps += 1
            since = t if self.last_step is None else self.last_step
            self.last_step = t
            if direction:
                texts = [f"step {self.steps}, position {position:+d}", f"{position:+d}"]
            else:
                texts = [f"step {self.steps}, direction unknown", "?"]
            pd._put(since, t, "position", texts)
        else:  # a state sequence error: (rule, sample, state before, after)
            _, k, t, before, after = out
            rule = plan.rules[k].rule.id
            self.counts[rule] = self.counts.get(rule, 0) + 1
            pd._put(t, t, "fail", [f"{rule}: state {before} → {after}", rule, "!"])

    def _violation(self, spec: Any, start: int, end: int, w: int, outcome: int) -> None:
        """A failed interval (``check``'s words: rule, measured, limit, margin), or one this
        resolution cannot decide."""
        plan, rule = self.plan, spec.rule.id
        measured, limit = plan.interval(w), plan.limit(spec)
        if outcome == self.flagged[0]:
            self.counts[rule] = self.counts.get(rule, 0) + 1
            margin = plan.margin(spec, w)
            texts = [
                f"{rule}: measured {measured}, limit {limit}, margin {margin}",
                f"{rule} {measured} < {limit}",
                rule,
                "!",
            ]
            self.pd._put(start, end, "fail", texts)
        else:
            res = self.check.resolution()
            texts = [
                f"{rule}: measured {measured}, limit {limit}: indeterminate at a resolution of {res}",
                f"{rule} {measured} ≈ {limit}?",
                "?",
            ]
            self.pd._put(start, end, "indeterminate", texts)

    def _summary(self, start: int, end: int, *, final: bool) -> None:
        """The block engine's summary, over ``start``..``end`` (so far: over a pause)."""
        for texts in self.check.summary(end + 1, final=final):
            self.pd._put(start, end, "rule", texts)
        engine = self.check.violations()
        if final and engine and engine != {r: self.counts.get(r, 0) for r in engine}:
            text = (
                f"wavecheck decoder: the per-edge violations {self.counts} differ from the "
                f"engine's {engine} (please report)"
            )
            self.pd._message(text, until=end)
            sys.stderr.write(text + "\n")


def _class_of(rule: Any) -> str:
    """The annotation class of a rule's intervals (from the rule table's check and events)."""
    if rule.check == "width":
        return "high" if rule.level == 1 else "low"
    if rule.check == "period":
        return "rate" if rule.ref == "step" else "state"
    if rule.check == "setup":
        return "enable" if rule.ref == "enable" else "setup"
    return {"hold": "hold", "switch": "delay"}.get(rule.check, "fail")


def _label_of(rule: Any) -> str:
    return {
        "high": "high",
        "low": "low",
        "state": "state",
        "enable": "enable setup",
        "setup": "setup",
        "hold": "hold",
        "delay": "delay",
    }.get(_class_of(rule), rule.id)
