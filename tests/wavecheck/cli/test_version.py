"""``--version`` on both command lines, from the one version literal (``wavecheck.__version__``)."""

from __future__ import annotations

import importlib.metadata
import tomllib
from collections.abc import Callable
from pathlib import Path

import pytest

import stepgen.cli
import wavecheck
import wavecheck.cli

REPO = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize(
    ("prog", "main"), [("wavecheck", wavecheck.cli.main), ("stepgen", stepgen.cli.main)]
)
def test_version_option(prog: str, main: Callable[[list[str]], int], capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out == f"{prog} {wavecheck.__version__}\n"


def test_version_is_written_once_and_installed_as_such() -> None:
    """pyproject.toml takes the version from ``wavecheck.__version__`` (no second literal), so the
    installed distribution carries exactly that value."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "wavecheck.__version__"}
    assert importlib.metadata.version("wavecheck") == wavecheck.__version__
