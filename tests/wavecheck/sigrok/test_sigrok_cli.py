"""``sigrok-cli -i CAPTURE -P wavecheck:… -A wavecheck=violations`` lists exactly the violations
``wavecheck check --format json`` lists (issue 28): the same rules, at the same samples, with the
same measured values (and the same printed measured, limit and margin), over the golden captures
(sampled at 1 MHz into ``.sr`` files, as a logic analyzer would), the real captures of
sigrok-dumps' ``stepper_motor`` folder, and generated captures with edges on the boundary.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from collections import Counter
from fractions import Fraction
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import shared_capture
from tests.wavecheck.sigrok.conftest import Decoded, RunDecoder
from tools.pulseview_shot import sampled_sr
from wavecheck.capture.open import open_capture
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.units import format_ns

pytestmark = pytest.mark.sigrok

ROOT = Path(__file__).resolve().parents[3]
_FAIL = re.compile(r"^(\w+): measured (\S+ \S+), limit (\S+ \S+), margin (\S+ \S+)$")
_SEQUENCE = re.compile(r"^(state_sequence): state (\d+) → (\d+)$")
_REGION = re.compile(r"^(\d+) violations?: (.*)$")
#: The decoder's channel ids for each role (pd.py's channels).
_CHANNEL = {"step": "step", "up": "step", "phase-A": "step", "dir": "dir", "down": "dir",
            "phase-B": "dir", "enable": "enable", "phase-C": "c", "phase-D": "d", "phase-E": "e"}  # fmt: skip

Seen = Counter[tuple[str, int, int]]


def check_json(capture: Path, argv: list[str]) -> dict:  # type: ignore[type-arg]
    """``wavecheck check CAPTURE ARGV --format json`` (every violation listed)."""
    cmd = [sys.executable, "-m", "wavecheck", "check", str(capture), *argv, "--format", "json"]
    run = subprocess.run([*cmd, "--max-violations", "100000"], capture_output=True, text=True)
    assert run.returncode in (0, 1, 3), run.stderr
    return json.loads(run.stdout)  # type: ignore[no-any-return]


def json_violations(doc: dict, rate: int) -> Seen:  # type: ignore[type-arg]
    """(rule, start sample, measured samples) of every violation of ``check``'s JSON; the
    printed measured, limit and margin are checked against the decoder's separately."""
    assert len(doc["violations"]) == doc["violations_total"]
    seen: Seen = Counter()
    for v in doc["violations"]:
        start = round(Fraction(v["time_s"]) * rate)
        measured = (
            0 if v["measured_ns"] is None else round(Fraction(v["measured_ns"]) * rate / 10**9)
        )
        seen[(v["rule"], start, measured)] += 1
    return seen


def decoder_violations(decoded: Decoded, rate: int) -> Seen:
    """The same from the decoder's ``violations`` row; each printed figure is checked against
    wavecheck's own formatting of the exact samples."""
    seen: Seen = Counter()
    for ann in decoded.annotations:
        if "indeterminate" in ann.text or _REGION.match(ann.text):
            continue
        seq = _SEQUENCE.match(ann.text)
        if seq:
            seen[(seq.group(1), ann.start, 0)] += 1
            continue
        m = _FAIL.match(ann.text)
        assert m, f"not a violation annotation: {ann.text!r}"
        rule, measured = m.group(1), m.group(2)
        width = ann.end - ann.start
        if measured.startswith("-"):  # a negative interval (overlapping up/down pulses)
            start, width = ann.end, -width
        else:
            start = ann.start
        assert measured == format_ns(Fraction(width * 10**9, rate)), ann
        seen[(rule, start, width)] += 1
    return seen


def _same(decoded: Decoded, doc: dict, rate: int) -> Seen:  # type: ignore[type-arg]
    got, want = decoder_violations(decoded, rate), json_violations(doc, rate)
    assert got == want, (
        f"decoder only: {sorted((got - want).elements())[:5]}; "
        f"check only: {sorted((want - got).elements())[:5]}"
    )
    _regions_hold(decoded, got)
    limits = {r["id"]: r["limit_ns"] for r in doc["rules"]}
    for ann in decoded.annotations:
        m = _FAIL.match(ann.text)
        if m:  # the limit and margin as check prints them (text report: same formatter)
            limit = Fraction(limits[m.group(1)])
            assert m.group(3) == format_ns(limit)
            w = abs(ann.end - ann.start) * (-1 if m.group(2).startswith("-") else 1)
            margin = Fraction(w * 10**9, rate) - limit
            assert m.group(4) == format_ns(margin, signed=True)
    return got


def _decoder_options(argv: list[str]) -> tuple[dict[str, str], dict[str, str]]:
    """``check``'s arguments as the decoder's channels and options."""
    channels: dict[str, str] = {}
    options: dict[str, str] = {}
    it = iter(argv)
    limits = []
    for word in it:
        value = next(it)
        if word == "--map":
            for pair in value.split(","):
                role, ch = pair.split("=", 1)
                channels[_CHANNEL[role]] = ch
        elif word == "--drive":
            options["drive"] = value
        elif word == "--type":
            options["type"] = value
        elif word == "--limit":
            limits.append(value)
        elif word == "--invert":
            options["invert"] = " ".join([options.get("invert", ""), value]).strip()
        elif word == "--resolution":
            options["resolution"] = value
        elif word == "--active-edge":
            options["active_edge"] = value
        elif word == "--user-step-type":
            options["user_table"] = value.replace(",", "+")
        else:
            raise AssertionError(word)
    if limits:
        options["limit"] = " ".join(limits)
    return channels, options


def _regions_hold(decoded: Decoded, seen: Seen) -> None:
    """The Violation regions row (when asked for): every violation in exactly one region, each
    region's counts per rule those of the violations in it (issue 36)."""
    regions = [(a, _REGION.match(a.text)) for a in decoded.annotations]
    regions = [(a, m) for a, m in regions if m]
    if "regions" not in " ".join(decoded.command):
        return
    assert sum(int(m.group(1)) for _, m in regions) == sum(seen.values())
    for a, m in regions:
        inside: Counter[str] = Counter()
        for (rule, start, width), n in seen.items():
            if a.start <= min(start, start + width) and max(start, start + width) <= a.end:
                inside[rule] += n
        counts = {r: int(n) for r, n in re.findall(r"(\w+) ×(\d+)", m.group(2))}
        assert counts == dict(inside), (a, inside)


def _compare(run_decoder: RunDecoder, path: Path, argv: list[str], rate: int) -> Seen:
    doc = check_json(path, argv)
    channels, options = _decoder_options(argv)
    return _same(run_decoder(path, channels, options, rows="violations:regions"), doc, rate)


# -- the golden captures -----------------------------------------------------------------------
def _golden_cases() -> list[tuple[str, list[str]]]:
    cases = []
    for vcd in sorted((ROOT / "captures/golden").glob("*.vcd")):
        if vcd.stem == "user-type15-velocity":
            continue  # three phases: the decoder's two channels cannot take it (test below)
        meta = tomllib.loads(vcd.with_suffix(".toml").read_text())
        words = meta["command"].split()
        number = int(words[words.index("--type") + 1]) if "--type" in words else 0
        drive = meta.get("wavecheck", {}).get("drive", "gecko-g202")
        roles = {0: ("step", "dir"), 1: ("up", "down")}.get(number)
        if roles is None:  # phases: the channels are named after their roles
            roles = tuple(f"phase-{x}" for x in "ABCDE")[: 2 if number == 2 else 3]
        argv = ["--drive", drive, "--type", str(number)]
        argv += ["--map", ",".join(f"{r}={r}" for r in roles)]  # channels named after roles
        if number == 15:
            argv += ["--user-step-type", words[words.index("--user-step-type") + 1]]
        # limits that make each capture fail somewhere (besides its own verdict)
        argv += ["--limit", "max_rate=1kHz", "--limit", "state_hold=1ms"]
        if number == 1:
            argv += ["--limit", "dir_delay=50us"]
        cases.append((vcd.stem, argv))
    return cases


@pytest.mark.parametrize(
    "name, argv", _golden_cases(), ids=lambda v: v if isinstance(v, str) else ""
)
def test_golden_captures(
    run_decoder: RunDecoder, tmp_path: Path, name: str, argv: list[str]
) -> None:
    capture = open_capture(str(ROOT / "captures/golden" / f"{name}.vcd"))
    sr = sampled_sr(capture, tmp_path / f"{name}.sr", 1_000_000)
    seen = _compare(run_decoder, sr, argv, 1_000_000)
    assert seen, "every golden case is given limits that fail somewhere"


# -- the real captures -------------------------------------------------------------------------
REAL = [
    ("grbl_cnc/grbl_cnc_1.sr", 2_000_000,
     ["--drive", "leadshine-dm542", "--map", "step=STEP (Y axis)", "--limit", "step_high=10.25us",
      "--limit", "max_rate=4kHz"]),
    ("grbl_cnc/grbl_cnc_1.sr", 2_000_000,
     ["--drive", "gecko-g202", "--map", "step=STEP (Y axis),enable=EN",
      "--limit", "enable_setup=2s"]),
    ("smoothieware/smoothieware_snippet.sr", 12_000_000,
     ["--drive", "gecko-g202", "--map", "step=3,dir=4"]),
    ("smoothieware/smoothieware_snippet.sr", 12_000_000,
     ["--drive", "a4988", "--map", "step=5,dir=6", "--limit", "step_low=110us"]),
]  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("rel, rate, argv", REAL, ids=lambda v: v if isinstance(v, str) else "")
def test_real_captures(run_decoder: RunDecoder, rel: str, rate: int, argv: list[str]) -> None:
    path = shared_capture(f"sigrok-dumps/stepper_motor/{rel}")
    seen = _compare(run_decoder, path, argv, rate)
    assert seen, "each real case has violations to compare"


def test_three_phases_are_refused_with_a_message(run_decoder: RunDecoder, tmp_path: Path) -> None:
    capture = open_capture(str(ROOT / "captures/golden/user-type15-velocity.vcd"))
    sr = sampled_sr(capture, tmp_path / "type15.sr", 1_000_000)
    options = {"drive": "gecko-g202", "type": "15", "user_table": "1+3+2+6+4+5"}
    out = run_decoder(sr, {"step": "phase-A", "dir": "phase-B"}, options, rows="messages")
    (message,) = [a.text for a in out.annotations]
    assert "step type 15 (user-defined) has 3 phases; the decoder takes two" in message
    assert "wavecheck decoder:" in out.stderr  # also where sigrok-cli and PulseView log


def test_no_sample_rate_says_so(run_decoder: RunDecoder) -> None:
    """smoothieware's copy without a sample rate: intervals in samples, nothing judged, and a
    message that says why (``check`` refuses the file: it needs --samplerate)."""
    path = shared_capture(
        "sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet_no_samplerate.sr"
    )
    out = run_decoder(path, {"step": "3", "dir": "4"}, {"drive": "gecko-g202"},
                      rows="violations:messages:widths")  # fmt: skip
    texts = [a.text for a in out.annotations]
    assert any("no sample rate" in t for t in texts)
    assert not any(t.startswith("step_high:") for t in texts)
    assert "high 44 samples" in texts


# -- generated captures on the boundary ----------------------------------------------------------
@pytest.mark.parametrize(
    "resolution, expect",
    [
        ("0", {6: "pass", 5: "pass", 4: "fail"}),  # exact: equal passes, one sample short fails
        ("", {6: "pass", 5: "indeterminate", 4: "fail"}),  # T = one sample: (W − T, W + T)
    ],
)
def test_boundary(run_decoder: RunDecoder, tmp_path: Path, resolution: str, expect: dict) -> None:  # type: ignore[type-arg]
    """A 5 us step_high / step_low / dir_setup / dir_hold limit at 1 MHz: pulses, gaps, setups and
    holds of exactly 5 samples, and one sample more and less, on both tools."""
    # STEP: pulses of 4, 5 and 6 samples, each followed by a gap of exactly 5 (rising edges
    # at 100, 109, 119), then one at 140; DIR: changes 5, 4 and 6 samples before the first
    # three (setup) and 5, 4 and 6 after them (hold), and at the same sample as the last (a 0
    # setup and a 0 hold: ../shared/DESIGN.md "Rules")
    step = np.array([100, 104, 109, 114, 119, 125, 140, 146], dtype=np.int64)
    dirs = np.array([95, 105, 113, 125, 140], dtype=np.int64)
    path = tmp_path / "boundary.sr"
    write_sr_edges(path, ["STEP", "DIR"], [step, dirs], [0, 0], 200, samplerate=1_000_000)
    limits = ["step_high=5us", "step_low=5us", "dir_setup=5us", "dir_hold=5us"]
    argv = ["--drive", "leadshine-dm542", "--map", "step=STEP,dir=DIR"]
    for lim in limits:
        argv += ["--limit", lim]
    if resolution:
        argv += ["--resolution", resolution]
    seen = _compare(run_decoder, path, argv, 1_000_000)
    assert {w for rule, _, w in seen if rule == "step_high"} == {4}
    for rule_id in ("dir_setup", "dir_hold"):
        assert {w for rule, _, w in seen if rule == rule_id} == {0, 4}, rule_id
    doc = check_json(path, argv)
    rule = next(r for r in doc["rules"] if r["id"] == "step_high")
    assert rule["checked"] == 4
    assert rule["indeterminate"] == sum(v == "indeterminate" for v in expect.values())
    assert rule["violations"] == sum(v == "fail" for v in expect.values())


# -- the summary row -----------------------------------------------------------------------------
_RULE_LINE = re.compile(
    r"^(\w+): (pass|fail|indeterminate|unchecked), (\d+) checked, (\d+) violation\(s\)"
    r"(?:, (\d+) indeterminate.*?)?(?:, min margin (\S+ \S+))?$"
)


@pytest.mark.slow
def test_summary_is_checks_table(run_decoder: RunDecoder) -> None:
    """The summary row at the end of the input: per rule the verdict, intervals checked,
    violations, indeterminate ones and the minimum margin of ``check --format json``, side by
    side over the input after the extent it covers, then the overall verdict at its end."""
    path = shared_capture("sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr")
    argv = ["--drive", "gecko-g202", "--map", "step=3,dir=4", "--limit", "step_low=107.25us"]
    doc = check_json(path, argv)
    channels, options = _decoder_options(argv)
    out = run_decoder(path, channels, options, rows="summary")
    extent, *lines, first = out.annotations
    assert extent.start == 0 and extent.text.startswith("summary of 0 s – ")
    assert all(a.end <= b.start for a, b in pairwise(out.annotations))
    assert first.text.startswith(f"{doc['verdict'].upper()} against gecko-g202: ")
    assert f"{doc['violations_total']} violation(s), {doc['steps']['count']} steps" in first.text
    rules = {r["id"]: r for r in doc["rules"]}
    assert [a.text.split(":")[0] for a in lines] == list(rules)
    for ann in lines:
        m = _RULE_LINE.match(ann.text)
        assert m, ann.text
        rule = rules[m.group(1)]
        assert (m.group(2), int(m.group(3)), int(m.group(4))) == (
            rule["verdict"], rule["checked"], rule["violations"])  # fmt: skip
        assert int(m.group(5) or 0) == rule["indeterminate"]
        margin = rule["min_margin_ns"]
        assert m.group(6) == (None if margin is None else format_ns(Fraction(margin), signed=True))
    assert any(r["indeterminate"] for r in doc["rules"])  # the case covers indeterminate too


def test_pause_gives_a_summary_so_far(run_decoder: RunDecoder, tmp_path: Path) -> None:
    """With ``pause=``, a summary of what came so far after each pause that long, and the last
    one at the end of the input: each covers the input since the one before, its lines side by
    side (the overall verdict last), so no two summary annotations overlap."""
    # 1 MHz: three 2-sample pulses 20 samples apart, 400 ms idle, then two more
    step = [100, 102, 120, 122, 140, 142, 400_140, 400_142, 400_160, 400_162]
    path = tmp_path / "pause.sr"
    write_sr_edges(path, ["STEP"], [np.array(step, np.int64)], [0], 400_300, samplerate=1_000_000)
    out = run_decoder(path, {"step": "STEP"}, {"drive": "gecko-g202", "pause": "100ms"},
                      rows="summary")  # fmt: skip
    spans = [(a.start, a.end) for a in out.annotations]
    assert spans == sorted(spans) and all(a[1] <= b[0] for a, b in pairwise(spans))
    heads = [a for a in out.annotations if "against gecko-g202" in a.text]
    assert [a.end for a in heads] == [100_142, 400_162]  # the pause; the last edge (tail < tick)
    assert spans[0][0] == 0 and spans[len(spans) // 2][0] == 100_142
    assert heads[0].text.startswith("so far: FAIL against gecko-g202: 3 violation(s), 3 steps")
    assert heads[1].text.startswith("FAIL against gecko-g202: 5 violation(s), 5 steps")


@pytest.mark.parametrize(
    "pause, says",
    [("abc", "pause abc: not a quantity"), ("nan", "pause nan: not a quantity"),
     ("1e400s", "pause 1e400s: out of range"), ("0", "pause 0: below the floor of 1 ms"),
     ("-1s", "pause -1s: below the floor of 1 ms"), ("1fs", "pause 1fs: below the floor of 1 ms"),
     ("90000s", "pause 90000s: above the ceiling of a day")],
)  # fmt: skip
def test_a_bad_pause_is_an_option_error(
    run_decoder: RunDecoder, tmp_path: Path, pause: str, says: str
) -> None:
    """A pause that is no time, or below the floor (a summary every few edges: issue 36), is one
    option error on the Messages row and stderr, not an internal error."""
    path = tmp_path / "p.sr"
    write_sr_edges(path, ["STEP"], [np.array([10, 12, 30, 32], np.int64)], [0], 50,
                   samplerate=1_000_000)  # fmt: skip
    out = run_decoder(path, {"step": "STEP"}, {"drive": "gecko-g202", "pause": pause},
                      rows="messages:violations:summary")  # fmt: skip
    (message,) = out.annotations
    assert message.text.startswith(f"wavecheck decoder: {says}"), message.text
    assert "internal error" not in message.text and message.text in out.stderr


@pytest.mark.parametrize(
    "unit, text",
    [("auto", "high 2 us"), ("ns", "high 2000 ns"), ("us", "high 2 us"), ("ms", "high 0.002 ms"),
     ("samples", "high 2 samples")],
)  # fmt: skip
def test_units_shown(run_decoder: RunDecoder, tmp_path: Path, unit: str, text: str) -> None:
    path = tmp_path / "units.sr"
    write_sr_edges(path, ["STEP"], [np.array([10, 12, 30, 32], np.int64)], [0], 50,
                   samplerate=1_000_000)  # fmt: skip
    out = run_decoder(path, {"step": "STEP"}, {"drive": "gecko-g202", "unit": unit}, rows="widths")
    assert out.annotations[0].text == text


def test_a_vcd_read_by_sigrok(run_decoder: RunDecoder, tmp_path: Path) -> None:
    """A VCD through sigrok-cli's own reader (``-I vcd:skip=0``: sample 0 is time 0, as for
    wavecheck; one sample per timescale unit). A simulator's VCD has exact edges: ``check`` judges
    it at resolution 0, and so does the decoder with ``resolution=0``."""
    from tests.conftest import write_vcd

    step = [100, 104, 109, 114, 119, 125, 140, 146]
    vcd = write_vcd(tmp_path / "b.vcd", {"STEP": (0, step), "DIR": (0, [95, 105, 113, 125, 140])},
                    timescale="1 us", end=200)  # fmt: skip
    argv = ["--drive", "leadshine-dm542", "--map", "step=STEP,dir=DIR"]
    for lim in ("step_high=5us", "step_low=5us", "dir_setup=5us", "dir_hold=5us"):
        argv += ["--limit", lim]
    doc = check_json(vcd, argv)
    assert doc["capture"]["resolution_ns"] == 0
    channels, options = _decoder_options([*argv, "--resolution", "0"])
    decoded = run_decoder(vcd, channels, options, input_format="vcd:skip=0")
    seen = _same(decoded, doc, 1_000_000)
    assert {w for r, _, w in seen if r == "step_high"} == {4}


@pytest.mark.parametrize(
    "channels, options, says",
    [
        ({"step": "STEP"}, {"drive": "gecko-g20"}, "gecko-g202"),  # the library's suggestion
        ({"step": "STEP"}, {"drive": "gecko-g202", "resolution": "5"}, "resolution 5: give a unit"),
        ({"step": "STEP"}, {"drive": "gecko-g202", "invert": "dir"}, "invert dir: no channel"),
        ({"step": "STEP"}, {"drive": "gecko-g202", "type": "1"}, "needs its down on channel"),
        ({"step": "STEP"}, {"drive": "gecko-g202", "limit": "step_hi=5us"}, "step_hi=5us"),
        ({"step": "STEP"}, {"type": "16"}, "step type 16 does not exist"),
    ],
)
def test_bad_options_are_one_message(
    run_decoder: RunDecoder,
    tmp_path: Path,
    channels: dict,
    options: dict,
    says: str,  # type: ignore[type-arg]
) -> None:
    """A bad option is one line on the Messages row (and stderr), no traceback, nothing judged."""
    path = tmp_path / "p.sr"
    write_sr_edges(path, ["STEP", "DIR"], [np.array([10, 12, 30, 32], np.int64),
                   np.array([], np.int64)], [0, 0], 50, samplerate=1_000_000)  # fmt: skip
    out = run_decoder(path, channels, options, rows="messages:violations:widths")
    (message,) = out.annotations
    assert message.text.startswith("wavecheck decoder: ") and says in message.text
    assert message.text in out.stderr


@pytest.mark.parametrize("tail", [0, 1, 5_000, 400_000])
def test_the_summary_reaches_the_end(run_decoder: RunDecoder, tmp_path: Path, tail: int) -> None:
    """However short the tail after the last edge, the summary covers the input to within the
    decoder's tick (max(1024, samples // 1024), pd.py) of its end: the last edge when the tail
    is shorter than that."""
    step = np.array([1000, 1002, 3000, 3002], np.int64)
    n = int(step[-1]) + 1 + tail
    path = tmp_path / "tail.sr"
    write_sr_edges(path, ["STEP"], [step], [0], n, samplerate=1_000_000)
    out = run_decoder(path, {"step": "STEP"}, {"drive": "gecko-g202"}, rows="summary")
    last = out.annotations[-1]
    assert last.text.startswith("FAIL against gecko-g202: 2 violation(s), 2 steps")
    assert int(step[-1]) <= last.end <= n - 1 and n - 1 - last.end < max(1024, n // 1024)
