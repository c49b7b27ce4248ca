"""The libsigrokdecode protocol decoder ``wavecheck`` (API version 3).

libsigrokdecode imports this package under its folder name, ``wavecheck`` (the name ``-P`` and
PulseView use), so the real ``wavecheck`` package is imported only in :meth:`Decoder.decode`, after
this package has stepped out of its way in ``sys.modules`` (:func:`_wavecheck`), from the paths
``wavecheck sigrok install`` recorded in ``install.json`` beside this file (libsigrokdecode's
embedded Python does not see the virtual environment wavecheck lives in).

Per edge (``wait()`` on an edge of any assigned channel) the judge
(:mod:`wavecheck.sigrok.judge`) decides the intervals that edge closes and the decoder puts
them at once. The edges also go to the block engine, whose summary (side by side on the Summary
row, the overall verdict last) and the violation regions (:mod:`wavecheck.sigrok.regions`) are
put when the input ends: sigrok-cli ends it (``wait()`` raises), PulseView 0.4.2 never says so
(module doc of the judge), so a watcher thread (:class:`_Watch`) takes the input as ended when
none has come for :data:`IDLE_S` seconds; the decoder also wakes at least every 0.1 % of the
input without an edge (:data:`TICK_SHARE`), so the summary reaches the capture's end however
short the tail after the last edge. With ``pause``, also a summary so far after each pause.
"""

from __future__ import annotations

import importlib
import json
import os
import sys
import threading
import time
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
#: Without an edge, the decoder looks up at least every max(TICK_MIN, samples so far //
#: TICK_SHARE) samples: the input it knows of ends within 0.1 % of where the capture ends
#: (a pixel at PulseView's full zoom-out), at a few thousand extra wake-ups per capture.
TICK_MIN = 1024
TICK_SHARE = 1024
#: Seconds of no input after which the decoder takes the input as ended (:class:`_Watch`).
IDLE_S = 1.5
_LOCK = threading.Lock()
_ADAPTER: dict[str, Any] = {}

CHANNELS = ({"id": "step", "name": "STEP/UP/A", "desc": "STEP (type 0), UP (type 1) or phase A"},)
#: As few as can be: libsigrokdecode 0.5.3 copies every declared channel's level at every sample,
#: assigned or not, so each one costs time on long captures (hence no phases C to E).
OPTIONAL_CHANNELS = (
    {"id": "dir", "name": "DIR/DOWN/B", "desc": "DIR (type 0), DOWN (type 1) or phase B"},
    {"id": "enable", "name": "ENABLE", "desc": "ENABLE (active high; invert=enable if low)"},
)
#: Annotation classes. PulseView 0.4.2 colours a class by the hue of the decode signal (120°, the
#: green of the first) + 20° per row index + 55° per class index (decodetrace.cpp): this order
#: makes a violation and a violation region red (10°, 5°), an indeterminate one orange (40°) and
#: every other class at least 55° away from red (``test_pulseview.py`` checks the screen).
ANNOTATIONS = (
    ("high", "STEP high time"),
    ("setup", "DIR setup"),
    ("hold", "DIR hold"),
    ("low", "STEP low time"),
    ("indeterminate", "Indeterminate at this sample rate"),
    ("rate", "Step rate"),
    ("enable", "ENABLE setup"),
    ("message", "Message"),
    ("state", "Phase state held"),
    ("delay", "UP/DOWN switch delay"),
    ("fail", "Violation"),
    ("region", "Violation region"),
    ("position", "Position"),
    ("rule", "Summary"),
)
_CLASS = {name: k for k, (name, _) in enumerate(ANNOTATIONS)}
ANNOTATION_ROWS = (
    ("regions", "Violation regions", (_CLASS["region"],)),
    ("widths", "Pulse widths", tuple(_CLASS[c] for c in ("high", "low", "state"))),
    (
        "dir",
        "DIR and ENABLE timing",
        tuple(_CLASS[c] for c in ("setup", "hold", "enable", "delay")),
    ),
    ("violations", "Violations", (_CLASS["fail"], _CLASS["indeterminate"])),
    ("steps", "Position", (_CLASS["position"],)),
    ("rates", "Step rate", (_CLASS["rate"],)),
    ("summary", "Summary", (_CLASS["rule"],)),
    ("messages", "Messages", (_CLASS["message"],)),
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
        "desc": "Also a summary so far after each pause of (1ms or more; empty: at the end only)",
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
        # the summary: the input seen up to sample ``seen``; violations not yet in a region
        # (starts, ends, rules); the end of the last summary (None: none yet); edges since it
        self.seen = 0
        self.fails: tuple[list[int], list[int], list[str]] = ([], [], [])
        self.summed: int | None = None
        self.pending = False
        # the decoder holds the lock but while it waits in wait(); wakes counts the waits
        self.lock = threading.Lock()
        self.wakes = 0
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
        """Wait for an edge of any assigned channel, or a tick without one; judge and annotate
        each edge. The summary and the violation regions come when the input ends: at the end
        of input (sigrok-cli), when no input has come for :data:`IDLE_S` (:class:`_Watch`:
        PulseView), and with ``pause`` also after each pause that long (so far)."""
        pd, judge, show, feed, chans = self.pd, self.judge, self._show, self.check.edge, self.chans
        pins = pd.wait()
        judge.start([pins[k] for k in chans])
        self.check.start([pins[k] for k in chans])
        pause, lock = self.check.pause, self.lock
        edges: list[dict[Any, Any]] = [{k: "e"} for k in chans]
        last = None  # the last edge
        watch = _Watch(self)
        watch.start()
        lock.acquire()
        try:
            while True:
                skip = max(TICK_MIN, self.seen // TICK_SHARE)
                if pause and self.pending and last is not None:
                    skip = min(skip, max(1, last + pause - self.seen))
                self.wakes += 1
                lock.release()
                try:
                    pins = pd.wait([*edges, {"skip": skip}])
                finally:
                    lock.acquire()
                self.wakes += 1
                t = self.seen = pd.samplenum
                if not any(pd.matched[:-1]):  # a tick: no edge
                    if pause and self.pending and last is not None and t - last >= pause:
                        self._finish(t, final=False)
                    continue
                if last is None:
                    for note in self.plan.notes:
                        pd._message("wavecheck: " + note, until=t)
                for out in judge.at(t, [pins[k] for k in chans]):
                    show(out)
                feed(t, judge.changed)
                last, self.pending = t, True
        except (EOFError, SystemError) as end:  # libsigrokdecode ends the input (module doc)
            if isinstance(end, SystemError) and "wait" not in str(end):
                raise
        finally:
            watch.stop = True
            lock.release()
        with lock:
            self._finish(self.seen, final=True)

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
            self._keep(t, t, rule)

    def _keep(self, start: int, end: int, rule: str) -> None:
        """A violation for the next violation regions."""
        self.fails[0].append(start)
        self.fails[1].append(end)
        self.fails[2].append(rule)

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
            self._keep(start, end, rule)
        else:
            res = self.check.resolution()
            texts = [
                f"{rule}: measured {measured}, limit {limit}: indeterminate at a resolution of {res}",
                f"{rule} {measured} ≈ {limit}?",
                "?",
            ]
            self.pd._put(start, end, "indeterminate", texts)

    def _finish(self, end: int, *, final: bool, say: bool = False) -> None:
        """The summary and the violation regions of the input since the last summary, up to
        sample ``end`` (the caller holds :attr:`lock`); ``say``: the summary lines also on
        stderr (PulseView's log: the input was taken as ended)."""
        if self.summed is not None and end <= self.summed and not self.pending:
            return  # nothing new since the summary before
        begin = 0 if self.summed is None else self.summed
        from wavecheck.sigrok.regions import regions

        for region in regions(*self.fails, begin, end):
            self.pd._put(region.start, region.end, "region", region.texts())
        self.fails = ([], [], [])
        lines = self.check.summary(end + 1, final=final)
        if lines:  # side by side, the overall verdict last (at the end): none hides another
            # first what the figures cover, the input from its start (under the row's title)
            extent = f"{self.plan.interval(0)} – {self.plan.interval(end)}"
            lines = [[f"summary of {extent}", extent], *lines[1:], lines[0]]
            n, span = len(lines), max(end - begin, len(lines))
            for k, texts in enumerate(lines):
                self.pd._put(begin + span * k // n, begin + span * (k + 1) // n, "rule", texts)
                if say:
                    sys.stderr.write(f"wavecheck decoder: summary to sample {end}: {texts[0]}\n")
        self.summed, self.pending = end, False
        engine = self.check.violations()
        if final and engine and engine != {r: self.counts.get(r, 0) for r in engine}:
            text = (
                f"wavecheck decoder: the per-edge violations {self.counts} differ from the "
                f"engine's {engine} (please report)"
            )
            self.pd._message(text, until=end)
            sys.stderr.write(text + "\n")


class _Watch(threading.Thread):
    """Ends the input for the decoder when none has come for :data:`IDLE_S` (PulseView 0.4.2
    never says that the input has ended: the decoder waits in ``wait()`` for samples that do
    not come). The summary and the regions it puts show at PulseView's next repaint (the pointer
    moving over the view); if more input comes after all (a live capture), the decoder goes on
    and the next summary covers what came since."""

    def __init__(self, run: _Run) -> None:
        super().__init__(name="wavecheck-idle", daemon=True)
        self.run_ = run
        self.stop = False

    def run(self) -> None:
        r = self.run_
        wakes, since = -1, time.monotonic()
        while not self.stop:
            time.sleep(IDLE_S / 4)
            if r.wakes != wakes:  # input came
                wakes, since = r.wakes, time.monotonic()
                continue
            # the lock is free only while the decoder waits in wait()
            if time.monotonic() - since < IDLE_S or not r.lock.acquire(blocking=False):
                continue
            try:
                if r.wakes == wakes and not self.stop:
                    r._finish(r.seen, final=True, say=True)
            finally:
                r.lock.release()


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
