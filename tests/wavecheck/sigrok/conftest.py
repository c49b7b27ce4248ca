"""The decoder installed for the tests (``wavecheck sigrok install --dir``) and run by sigrok-cli."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

from wavecheck.sigrok.install import install

_LINE = re.compile(r"^(\d+)-(\d+) wavecheck-1: (.*)$")
#: sigrok-cli's exit code says little (../shared/reference/sigrok.md §7): these on stderr fail.
STDERR_FAILURES = (
    "Traceback",
    "srd:",
    "No channel with name",
    "Required channel",
    "Error",
    "please report",  # the decoder's per-edge judge and the block engine disagree (pd.py)
)


@dataclass(frozen=True)
class Annotation:
    """One annotation line of ``sigrok-cli --protocol-decoder-samplenum``."""

    start: int
    end: int
    text: str


@dataclass(frozen=True)
class Decoded:
    annotations: list[Annotation]
    stderr: str
    command: list[str]


def need(tool: str) -> None:
    """Skip when ``tool`` is missing (make setup installs it: a CI run has it)."""
    if shutil.which(tool) is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"{tool} missing in CI (make setup installs it)")
        pytest.skip(f"needs {tool}")


@pytest.fixture(scope="session")
def decoder_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory holding the installed decoder (``SIGROKDECODE_DIR``)."""
    need("sigrok-cli")
    base = tmp_path_factory.mktemp("decoders")
    install(base)
    return base


RunDecoder = Callable[..., Decoded]


@pytest.fixture
def run_decoder(decoder_dir: Path) -> RunDecoder:
    """``run_decoder(capture, channels, options, rows)``: sigrok-cli with the decoder, parsed."""

    def run(
        capture: Path,
        channels: Mapping[str, str],
        options: Mapping[str, str] | None = None,
        rows: str = "violations",
        input_format: str | None = None,
    ) -> Decoded:
        spec = ":".join(
            ["wavecheck", *(f"{k}={v}" for k, v in {**channels, **(options or {})}.items())]
        )
        cmd = ["sigrok-cli", "-i", str(capture)]
        if input_format:
            cmd += ["-I", input_format]
        cmd += ["-P", spec, "-A", f"wavecheck={rows}", "--protocol-decoder-samplenum"]
        env = dict(os.environ, SIGROKDECODE_DIR=str(decoder_dir))
        run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
        bad = [w for w in STDERR_FAILURES if w in run.stderr]
        assert not bad and run.returncode == 0, f"{cmd}: rc {run.returncode}\n{run.stderr}"
        anns = []
        for line in run.stdout.splitlines():
            m = _LINE.match(line)
            assert m, f"unexpected sigrok-cli output line {line!r}"
            anns.append(Annotation(int(m.group(1)), int(m.group(2)), m.group(3)))
        return Decoded(anns, run.stderr, cmd)

    return run
