"""The report carries the ``config`` and ``latency_safe`` step rates of a stepgen configuration
with the settings they assume, and every output shows them per capture (issue 11: they used to be
patched into the text and JSON after the report was built, and the HTML page showed the first
capture's rates for every capture)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest
from lxml import etree

import wavecheck
from tests.engine_probe import run_check
from wavecheck.capture.open import open_capture
from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig
from wavecheck.report.html import render_html
from wavecheck.report.json import report_dict
from wavecheck.report.junit import render_junit
from wavecheck.report.text import render_text
from wavecheck.units import time_ns

pytest_plugins = ["pytester"]

REPO = Path(__file__).resolve().parents[3]
GOOD = REPO / "captures/golden/g202-p16-dirhold2-worst.vcd"


def _check(period_ns: int, dirhold_ns: int, latency: str | None) -> wavecheck.Report:
    cfg = LinuxCNCConfig(base_period_ns=period_ns, params={"dirhold": dirhold_ns})
    j = None if latency is None else time_ns(latency)
    return run_check(open_capture(GOOD), "gecko-g202", stepgen=cfg, latency_ns=j).report


def test_report_carries_the_configured_rates_and_their_settings() -> None:
    # The seed's plan: P = 16 us, dirhold 2 periods, J = 11 us -> 1 / (2 x 16 us) = 31,250 steps/s.
    r = _check(16_000, 32_000, "11us")
    assert r.rates.config == Fraction(31250)
    assert r.rates.latency_safe == Fraction(31250)
    cfg = r.rates.configured
    assert cfg is not None and (cfg.base_period_ns, cfg.latency_ns) == (16_000, 11_000)
    # dirhold 1 period: hold 16 - 11 = 5 us < 20 us at any rate, so none is latency-safe.
    assert _check(16_000, 16_000, "11us").rates.latency_safe is None


def test_without_a_configuration_there_are_no_configured_rates() -> None:
    r = wavecheck.check(GOOD, "gecko-g202")
    assert r.rates.configured is None and r.rates.config is None
    assert "config" not in report_dict(r)["max_step_rate_hz"]
    assert "BASE_PERIOD" not in render_text(r)


def test_every_output_shows_each_captures_own_rates() -> None:
    a = _check(16_000, 32_000, "11us")  # 31,250 steps/s
    b = _check(31_000, 31_000, None)  # 1 / 62 us = 16,129 steps/s, no latency_safe
    assert report_dict(a)["max_step_rate_hz"]["config"] == 31250
    assert report_dict(b)["max_step_rate_hz"]["latency_safe"] is None
    assert "config 31.25 kHz" in render_text(a) and "config 16.129 kHz" in render_text(b)
    html = render_html([a, b], plots=False)
    sections = html.split("<section")[1:]
    assert len(sections) == 2
    assert "31.25 kHz" in sections[0] and "31.25 kHz" not in sections[1]
    assert "16.129 kHz" in sections[1] and "BASE_PERIOD 31 us" in sections[1]
    suites = etree.fromstring(render_junit([a, b]).encode()).findall("testsuite")
    props = [{p.get("name"): p.get("value") for p in s.iter("property")} for s in suites]
    assert props[0]["max_step_rate_hz.config"] == "31250"
    assert props[1]["max_step_rate_hz.config"] == "16129"
    assert "max_step_rate_hz.latency_safe" not in props[1]


def test_python_api_reads_linuxcnc_files(tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 16000\nSERVO_PERIOD = 1000000\n")
    hal = tmp_path / "m.hal"
    hal.write_text("loadrt stepgen step_type=0\nsetp stepgen.0.dirhold 32000\n")
    r = wavecheck.check(GOOD, "gecko-g202", ini=ini, hal=hal, latency="11us")
    assert (r.rates.config, r.rates.latency_safe) == (31250, 31250)


@pytest.mark.parametrize("latency", ["11us", None])
def test_pytest_plugin_shows_the_rates(pytester: pytest.Pytester, latency: str | None) -> None:
    pytester.makefile(".ini", m="[EMCMOT]\nBASE_PERIOD = 16000\n")
    pytester.makefile(".hal", m="setp stepgen.0.dirhold 32000\n")
    extra = f'latency = "{latency}"\n' if latency else ""
    pytester.makefile(
        ".toml",
        wavecheck=f'[[capture]]\nname = "g"\npath = "{GOOD}"\ndrive = "gecko-g202"\n'
        f'ini = "m.ini"\nhal = "m.hal"\nexpect = "fail"\n{extra}',
    )
    result = pytester.runpytest("--junitxml=out.xml")
    # the capture passes, so expect = "fail" makes the verdict item fail and describe the report
    result.assert_outcomes(failed=1, passed=5)
    result.stdout.fnmatch_lines(
        ["*max step rate (stepgen channel 0, BASE_PERIOD 16 us): config 31.25 kHz*"]
    )
    xml = (pytester.path / "out.xml").read_text()
    assert 'name="max_step_rate_hz.config" value="31250' in xml
    assert ('name="max_step_rate_hz.latency_safe"' in xml) == (latency is not None)


def test_every_output_says_why_latency_safe_is_missing() -> None:
    """Issue 26: ``check --ini … --latency`` against a drive without a DIR hold figure left
    ``latency_safe`` empty; every report says why and how to give the figure."""
    cfg = LinuxCNCConfig(base_period_ns=16_000, params={"dirhold": 32_000})
    r = run_check(open_capture(GOOD), "leadshine-dm542", stepgen=cfg, latency_ns=11_000).report
    assert r.rates.latency_safe is None and r.rates.config is not None
    why = "latency_safe not computed: drive leadshine-dm542"
    how = "--limit dir_hold=T"
    text = render_text(r)
    assert any(line.startswith(f"note: {why}") and how in line for line in text.splitlines())
    notes = report_dict(r)["max_step_rate_hz"]["config_notes"]
    assert any(n.startswith(why) and how in n for n in notes)
    page = etree.HTML(render_html([r], plots=False))
    row = page.xpath('//table[@class="rates"]/tr[td[1]="latency_safe"]')[0]
    meaning = "".join(row.xpath("td[3]//text()"))
    assert why in meaning and how in meaning and "gives no dir_hold figure" in meaning
