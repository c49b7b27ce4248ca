"""``require`` in ``wavecheck.toml`` (issue 26): a rule the entry (or axis) requires that is not
checked fails its item and the capture's ``verdict`` item, saying why, instead of being skipped;
a rule not required is still skipped, and the skip says why."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from wavecheck.pytest_plugin import WavecheckConfigError, load_specs

pytest_plugins = ["pytester"]

REPO = Path(__file__).resolve().parents[2]

CONFIG = """\
[[capture]]
name = "x-without-dir"
path = "two-axis.vcd"
drive = "gecko-g202"
map = { step = "x_step" }
require = ["dir_hold"]

[[capture]]
name = "not-required"
path = "two-axis.vcd"
drive = "gecko-g202"
map = { step = "x_step" }

[[capture]]
name = "machine"
path = "two-axis.vcd"
drive = "gecko-g202"
require = "all"
axes.x = { step = "x_step", dir = "x_dir", expect = "fail", require = [] }
axes.y = { step = "y_step" }
"""


def test_required_rules_fail_their_items(pytester: pytest.Pytester) -> None:
    shutil.copy(REPO / "captures" / "examples" / "two-axis.vcd", pytester.path)
    (pytester.path / "wavecheck.toml").write_text(CONFIG)
    result = pytester.runpytest("-v", "-rs", "-p", "no:cacheprovider")
    out = result.stdout.str()
    assert "wavecheck.toml::x-without-dir::dir_hold FAILED" in out
    assert "x-without-dir: dir_hold is required but not checked: no DIR channel" in out
    assert "wavecheck.toml::x-without-dir::dir_setup SKIPPED" in out
    assert "dir_setup not checked in two-axis.vcd: no DIR channel" in out  # the skip says why
    assert "wavecheck.toml::x-without-dir::verdict FAILED" in out
    assert "x-without-dir: required but not decided: dir_hold not checked" in out
    assert "wavecheck.toml::not-required::verdict PASSED" in out
    assert "wavecheck.toml::not-required::dir_hold SKIPPED" in out
    # the machine: y requires all (the entry's), x requires nothing (its own)
    assert "wavecheck.toml::machine::y::dir_setup FAILED" in out
    assert "wavecheck.toml::machine::y::verdict FAILED" in out
    assert "wavecheck.toml::machine::x::verdict PASSED" in out
    assert "machine: axis y: required but not decided: dir_setup, dir_hold" in out


def test_require_names_rules(tmp_path: Path) -> None:
    config = tmp_path / "wavecheck.toml"
    config.write_text(CONFIG.replace('["dir_hold"]', '["dir_hld"]'))
    with pytest.raises(WavecheckConfigError, match="capture 1: --require 'dir_hld' is not a rule"):
        load_specs(config)
    config.write_text(CONFIG.replace('["dir_hold"]', "3"))
    with pytest.raises(WavecheckConfigError, match="'require' must be"):
        load_specs(config)
