"""Words a user sees (issue 12): no internal look-up words in anything printed or shipped, every
rule-file source a document a user can find, uncertain figures marked in the check reports, the
check's assumptions stated, the HTML report's sources listed, identical violations grouped."""

from __future__ import annotations

import json
import re
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from tests.engine_probe import run_check
from tests.wavecheck.waves import capture, drive, pulses
from wavecheck.cli import COMMANDS
from wavecheck.cli import main as wavecheck_main
from wavecheck.drives.library import list_drives, load_drive, rules_dir
from wavecheck.report import render_json, render_text
from wavecheck.report.html import render_html

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = ROOT / "captures" / "golden"

#: Words of the project's own notes, meaningless to a user: "the seed" (the design's seed
#: documents), section signs and citation tags of ../shared/reference, search-index ids.
INTERNAL = re.compile(
    r"§|\bthe seeds?\b|\bseeds?'s?|\(seed\b|\bseed:|\[(TWK|SC|HL|SG|IS|MAN|HAL|LT|CT)\]"
    r"|shared/reference|\bindex ids?\b|find_string|in the index\b|\bid \d{6,}",
    re.IGNORECASE,
)


def _internal(text: str) -> list[str]:
    return [m.group(0) for m in INTERNAL.finditer(text)]


def _strings(value: object) -> Iterator[str]:
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from _strings(v)
    elif isinstance(value, list):
        for v in value:
            yield from _strings(v)


RULE_FILES = sorted(rules_dir().glob("*.toml"))


@pytest.mark.parametrize("path", RULE_FILES, ids=lambda p: p.stem)
def test_rule_files_speak_no_internal_words(path: Path) -> None:
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    found = [(s[:60], _internal(s)) for s in _strings(data) if _internal(s)]
    assert not found, found


#: A reference a user can look up: a URL or web address, a repository path, or a titled manual
#: or datasheet (with its maker's name in front).
FINDABLE = re.compile(
    r"https?://|\b[\w.-]+\.(com|org|io|net|de)\b|\b[\w.-]+/[\w.-]+|\b(datasheet|manual)\b",
    re.IGNORECASE,
)


@pytest.mark.parametrize("path", RULE_FILES, ids=lambda p: p.stem)
def test_rule_file_sources_are_documents_a_user_can_find(path: Path) -> None:
    sources = tomllib.loads(path.read_text(encoding="utf-8"))["sources"]
    for key, text in sources.items():
        assert FINDABLE.search(text), f"{path.name} [{key}] names nothing findable: {text}"
        assert not re.search(r"\b(code comment|text cop(y|ies))\b", text, re.IGNORECASE), (
            f"{path.name} [{key}] cites an anonymous copy instead of the document: {text}"
        )


def test_dm542_cites_the_leadshine_manual_by_title_and_revision() -> None:
    text = load_drive("leadshine-dm542").sources["D1"]
    assert "User's Manual for DM542 Fully Digital Stepper Drive" in text
    assert "Version 1.0 (2012)" in text
    assert "index" not in text and "find_string" not in text and "text copy" not in text


def _run(main: object, argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    try:
        main(argv)  # type: ignore[operator]
    except SystemExit:  # --help
        pass
    out, err = capsys.readouterr()
    return out + err


def test_every_user_visible_output_speaks_no_internal_words(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Help of both tools, the drive library, stepgen plan in every latency range and format, and
    check reports (text, JSON, JUnit, HTML) of the golden traces."""
    seen: dict[str, str] = {}
    seen["wavecheck --help"] = _run(wavecheck_main, ["--help"], capsys)
    for name in COMMANDS:
        seen[f"wavecheck {name} --help"] = _run(wavecheck_main, [name, "--help"], capsys)
    for argv in (["--help"], ["plan", "--help"], ["simulate", "--help"]):
        seen["stepgen " + " ".join(argv)] = _run(stepgen_main, argv, capsys)
    seen["wavecheck drives"] = _run(wavecheck_main, ["drives"], capsys)
    for d in list_drives():
        for fmt in ("text", "json"):
            seen[f"drives {d.id} {fmt}"] = _run(
                wavecheck_main, ["drives", d.id, "--format", fmt], capsys
            )
    for latency in ("11us", "25us", "40us", "70us", "150us", "2ms"):
        for fmt in ("text", "json", "hal", "ini"):
            argv = ["plan", "--drive", "gecko-g202", "--latency", latency, "--format", fmt]
            seen[" ".join(argv)] = _run(stepgen_main, argv, capsys)
    argv = [
        "plan",
        "--drive",
        "xylotex",
        "--latency",
        "11us",
        "--base-period",
        "16us",
        "--invert-step",
    ]
    seen[" ".join(argv)] = _run(stepgen_main, argv, capsys)
    for vcd in sorted(GOLDEN.glob("*.vcd")):
        want = tomllib.loads(vcd.with_suffix(".toml").read_text()).get("wavecheck")
        if want is None:  # not a step/dir trace with a drive to check against
            continue
        for fmt in ("text", "json", "junit"):
            argv = ["check", str(vcd), "--drive", want["drive"], "--format", fmt]
            seen[" ".join(argv)] = _run(wavecheck_main, argv, capsys)
    html = tmp_path / "all.html"
    _run(
        wavecheck_main,
        [
            "check",
            *map(str, sorted(GOLDEN.glob("g202*.vcd"))),
            "--drive",
            "gecko-g202",
            "--html",
            str(html),
        ],
        capsys,
    )
    seen["--html"] = html.read_text()
    assert len(seen) > 100
    found = {what: _internal(text) for what, text in seen.items() if _internal(text)}
    assert not found, found


def test_the_internal_word_filter_catches_what_it_must() -> None:
    for bad in (
        "(seed: below 15 us)",
        "the seed's G202",
        "reference §2.3",
        "[TWK]",
        "text copy (index id 291557402)",
        "find_string id 19045341668",
    ):
        assert _internal(bad), bad
    for fine in ("--seed 3", "seed of the random latency models", "latency uniform:3us seed 0"):
        assert not _internal(fine), fine


# ------------------------------------------------------------------ marks and assumptions


def _tmc2209_report():
    """TMC2209 (step_high/step_low 100 ns, status uncertain) against clean 1 us pulses."""
    cap = capture({"S": (0, pulses([i * 10_000 for i in range(1, 20)], 1000))})
    return run_check(cap, load_drive("tmc2209"), {"step": "S"})


def test_uncertain_limits_carry_their_mark_into_every_report() -> None:
    report = _tmc2209_report()
    text = render_text(report)
    row = next(ln for ln in text.splitlines() if ln.startswith("step_high "))
    assert row.split()[1:3] == ["100", "ns?"]
    assert "? = uncertain figure" in text
    data = json.loads(render_json(report))
    high = next(r for r in data["rules"] if r["id"] == "step_high")
    assert high["limit_status"] == "uncertain" and high["limit_source"] == "R3"
    assert data["drive"]["active_edge_status"] == "secondary"
    page = render_html([report], plots=False)
    assert '<td class="num">100 ns?</td>' in page
    assert "R3</a> (uncertain)" in page


def test_a_firmware_default_is_marked_with_a_star(tmp_path: Path) -> None:
    own = tmp_path / "fw.toml"
    own.write_text(
        'id = "fw"\nname = "firmware default"\nkind = "user"\ninterface = "step-dir"\n'
        'active_edge = "rising"\n'
        '[limits.step_high]\nvalue = "2us"\nsource = "M"\nstatus = "firmware-default"\n'
        '[sources]\nM = "MarlinFirmware/Marlin Marlin/src/inc/Conditionals-4-adv.h"\n'
    )
    cap = capture({"S": (0, pulses([10_000, 20_000], 1000))})
    report = run_check(cap, load_drive(str(own)), {"step": "S"})
    text = render_text(report)
    assert "2 us*" in text and "* = firmware default" in text
    assert "step_high  measured 1 us  limit 2 us*" in text.replace("2 × ", "")
    assert "Limits marked * are firmware defaults (step_high)" in text


def test_assumptions_are_stated_enable_and_dir() -> None:
    step = pulses([i * 10_000 for i in range(2, 8)], 5000)
    sig = {"S": (0, step), "D": (0, [35_000]), "E": (0, [1000])}
    d = drive(step_high=1000, enable_setup=2000)
    plain = run_check(capture(sig), d, {"step": "S", "dir": "D", "enable": "E"})
    text = render_text(plain)
    assert "note: ENABLE: active high" in text and "--invert enable" in text
    assert "note: DIR: low = forward" in text
    assert "note: Levels are judged as captured (no --invert)" in text
    low = run_check(
        capture({**sig, "E": (1, [1000])}),
        d,
        {"step": "S", "dir": "D", "enable": "E"},
        invert=["enable"],
        forward_level=1,
    )
    text = render_text(low)
    assert "note: ENABLE: active low at the capture (--invert enable)." in text
    assert "note: DIR: high = forward" in text
    assert "enable inverted from the capture" in text
    data = json.loads(render_json(low))
    assert any(a.startswith("ENABLE: active low") for a in data["capture"]["assumptions"])
    assert any(
        "ENABLE: active low" in li
        for li in re.findall(r"<li>(.*?)</li>", render_html([low], plots=False))
    )


def test_an_uncertain_active_edge_is_stated() -> None:
    cap = capture({"S": (0, pulses([10_000, 20_000], 3000))})
    report = run_check(cap, load_drive("leadshine-hbs86h"), {"step": "S"})
    text = render_text(report)
    assert "steps on the rising? edge" in text
    assert "note: STEP: the rising active edge is uncertain [D7]" in text
    overridden = run_check(
        cap, load_drive("leadshine-hbs86h"), {"step": "S"}, active_edge="falling"
    )
    text = render_text(overridden)
    assert "steps on the falling edge" in text and "(--active-edge)" in text


# ------------------------------------------------------------------------------ HTML sources


def test_html_lists_the_sources_its_source_column_cites() -> None:
    cap = capture({"S": (0, pulses([10_000, 20_000], 5000))})
    d = load_drive("gecko-g202")
    page = render_html([run_check(cap, d, {"step": "S"})], plots=False)
    assert "<h3>Sources</h3>" in page
    cited = set(re.findall(r'<a href="#(src-1-[^"]+)">', page))
    assert cited == {"src-1-L1"}
    for key, text in d.sources.items():
        assert f'<dt id="src-1-{key}">{key}</dt><dd>' in page
        assert text.replace("'", "&#x27;").replace('"', "&quot;")[:80] in page


# ------------------------------------------------------------------------------- grouping


def _repeated_report():
    """Step-high violations: 5 pulses of 3 us, then 4 of 4 us, then 3 of 3 us (limit 4.5 us)."""
    widths = [3000] * 5 + [4000] * 4 + [3000] * 3
    edges: list[int] = []
    for i, w in enumerate(widths):
        edges += pulses([(i + 1) * 20_000], w)
    return run_check(capture({"S": (0, edges)}), drive(step_high=4500), {"step": "S"})


def test_identical_violations_are_grouped_in_text_worst_first() -> None:
    report = _repeated_report()
    text = render_text(report, max_violations=10)
    lines = text.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("violations: "))
    assert lines[head] == (
        "violations: 12 (worst first; the 10 worst shown as 2 groups of identical violations, "
        "each counted over the whole capture)"
    )
    assert lines[head + 1] == (
        "  8 × step_high  measured 3 us  limit 4.5 us  margin -1.5 us  "
        "first at 0.000020000 s, last at 0.000240000 s"
    )
    # issue 34: each group counts every identical violation, not only those shown: 8 and 4
    assert lines[head + 2].startswith("  4 × step_high  measured 4 us  limit 4.5 us")
    assert lines[head + 3] == ""  # every violation is in a group shown: no "… and N more"


def test_identical_violations_are_grouped_in_html_and_kept_one_by_one_in_json() -> None:
    report = _repeated_report()
    page = render_html([report], plots=False, max_violations=20)
    assert "12 violation(s), worst first. The 12 worst are shown as 2 groups" in page
    rows = re.findall(
        r'<tr><td class="num">\d+</td><td>step_high</td><td class="num">(\d+)</td>', page
    )
    assert rows == ["8", "4"]
    data = json.loads(render_json(report))
    assert len(data["violations"]) == 12 == data["violations_total"]
    assert [v["measured_ns"] for v in data["violations"]] == [3000] * 8 + [4000] * 4


def test_distinct_violations_stay_one_line_each() -> None:
    edges = pulses([10_000], 4000) + pulses([30_000], 3000)
    text = render_text(run_check(capture({"S": (0, edges)}), drive(step_high=4500), {"step": "S"}))
    assert "violations: 2 (worst first)\n" in text
    assert " × " not in text
