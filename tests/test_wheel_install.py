"""The project as users get it: a wheel, installed (not editable) into a fresh venv, run from a
folder outside the source tree.

The wheel is built from a copy of the checkout (so the build leaves nothing in the source tree)
with ``pip wheel --no-deps``; the venv gets the runtime dependencies from the package index as any
user's would (no ``--system-site-packages``: it would hide a missing dependency). Then
``wavecheck check`` on a golden trace, ``wavecheck drives``, ``stepgen plan`` and ``stepgen
simulate`` must work with nothing of the source tree on the path.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parent.parent
GOLDEN = REPO / "captures" / "golden"
#: Top-level folders of a checkout that are not part of the source (venvs, caches, outputs).
_NOT_SOURCE = {
    ".git", ".venv", "build", "dist", "out", "bench",
    ".pytest_cache", ".mypy_cache", ".ruff_cache", ".hypothesis",
}  # fmt: skip
_TIMEOUT_S = 600


def _clean_env() -> dict[str, str]:
    """The environment without anything that would put the source tree or this venv on the path
    (pip's own configuration, e.g. an index or find-links, is kept)."""
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP")
    }
    env["PYTHONNOUSERSITE"] = "1"
    return env


def _run(argv: list[str | Path], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(a) for a in argv],
        cwd=cwd,
        env=_clean_env(),
        capture_output=True,
        text=True,
        timeout=_TIMEOUT_S,
        check=False,
    )


def _must(proc: subprocess.CompletedProcess[str]) -> subprocess.CompletedProcess[str]:
    assert proc.returncode == 0, f"{proc.args}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


def _ignore(folder: str, names: list[str]) -> set[str]:
    top = Path(folder).resolve() == REPO
    return {
        n
        for n in names
        if n == "__pycache__" or n.endswith(".egg-info") or (top and n in _NOT_SOURCE)
    }


def _build_wheel(base: Path) -> Path:
    """The project's wheel, built from a copy of the checkout in ``base``."""
    base.mkdir(parents=True)
    src = base / "src"
    shutil.copytree(REPO, src, symlinks=True, ignore=_ignore)
    dist = base / "dist"
    _must(_run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", dist, src], base))
    (whl,) = dist.glob("wavecheck-*.whl")
    return whl


def _install(wheel: Path, base: Path) -> Path:
    """A fresh venv in ``base`` with ``wheel`` installed (not editable); its bin folder."""
    base.mkdir(parents=True)
    env = base / "env"
    _must(_run([sys.executable, "-m", "venv", env], base))
    bindir = env / ("Scripts" if os.name == "nt" else "bin")
    _must(_run([bindir / "python", "-m", "pip", "install", "-q", wheel], base))
    return bindir


def _wheel_holds_the_packages_and_drives_not_the_tools(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "wavecheck/_rules/gecko-g202.toml" in names
    assert {"wavecheck/py.typed", "stepgen/py.typed", "wavecheck/compare.py"} <= names
    assert "wavecheck/sigrok/decoder/pd.py" in names  # the protocol decoder (issue 28)
    assert not [n for n in names if n.startswith(("tools/", "tests/", "bench/"))]
    assert "stepgen/story.py" not in names and "stepgen/golden.py" not in names


def _installed_not_from_the_source_tree(venv: Path, outside: Path) -> None:
    code = (
        "import importlib.util as u, wavecheck, stepgen; "
        "print(wavecheck.__file__); print(stepgen.__file__); "
        "print([m for m in ('vcdvcd', 'pylibfst', 'tools', 'stepgen.story') if u.find_spec(m)])"
    )
    lines = _must(_run([venv / "python", "-c", code], outside)).stdout.splitlines()
    for path in lines[:2]:
        assert "site-packages" in path and not Path(path).is_relative_to(REPO)
    assert lines[2] == "[]"  # bench-only readers are not runtime dependencies; no dev tools


def _check_a_golden_trace_fails_dir_hold(venv: Path, outside: Path) -> None:
    vcd = GOLDEN / "g202-p20-worst-dirhold.vcd"
    proc = _run([venv / "wavecheck", "check", vcd.resolve(), "--drive", "gecko-g202"], outside)
    assert proc.returncode == 1, proc.stderr
    fails = [line for line in proc.stdout.splitlines() if line.startswith("dir_hold")]
    assert fails and "FAIL" in fails[0] and "9 us" in fails[0]


def _drives_lists_the_library(venv: Path, outside: Path) -> None:
    out = _must(_run([venv / "wavecheck", "drives"], outside)).stdout
    ids = {line.split()[0] for line in out.splitlines()[1:] if line.strip()}
    assert {"gecko-g202", "xylotex", "a4988"} <= ids


def _stepgen_plan(venv: Path, outside: Path) -> None:
    argv = ["plan", "--drive", "gecko-g202", "--latency", "11us", "--base-period", "16us"]
    out = _must(_run([venv / "stepgen", *argv], outside)).stdout
    dirhold = next(line for line in out.splitlines() if line.startswith("dirhold"))
    assert dirhold.split()[1:3] == ["2", "32000"]
    assert "max step rate 31,250 steps/s" in out


def _stepgen_simulate_then_check(venv: Path, outside: Path) -> None:
    """README's simulate line (the seed's G202 at P = 20 us), then wavecheck on its VCD."""
    argv = [
        "simulate", "--base-period", "20us", "--mode", "velocity", "--steplen", "20us",
        "--stepspace", "20us", "--dirhold", "20us", "--dirsetup", "20us",
        "--command", GOLDEN / "reversal-p20.csv", "--duration", "500ms",
        "--latency", "worst:11us:dir_hold", "--active-edge", "falling", "-o", "g202.vcd",
    ]  # fmt: skip
    _must(_run([venv / "stepgen", *argv], outside))
    vcd = outside / "g202.vcd"
    head = vcd.read_text(encoding="ascii")[:2000]
    assert "$timescale 1 ns $end" in head and " step $end" in head
    proc = _run([venv / "wavecheck", "check", vcd, "--drive", "gecko-g202"], outside)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stdout.splitlines()
    assert any(line.startswith("dir_hold") and "9 us" in line for line in lines)


def _sigrok_decoder_imports_the_installed_package(venv: Path, outside: Path) -> None:
    """``wavecheck sigrok install`` from the wheel: libsigrokdecode's Python finds wavecheck and
    numpy in this venv (its probe runs sigrok-cli with the decoder, when sigrok-cli is here)."""
    proc = _must(_run([venv / "wavecheck", "sigrok", "install", "--dir", outside / "dec"], outside))
    assert (outside / "dec/wavecheck/pd.py").is_file()
    if shutil.which("sigrok-cli"):
        assert "ok: sigrok-cli ran the decoder" in proc.stdout, proc.stdout


def test_installed_wheel_runs_without_the_source_tree(tmp_path: Path) -> None:
    """One test (one build, one venv: under xdist, separate tests would each build their own)."""
    wheel = _build_wheel(tmp_path / "build")
    _wheel_holds_the_packages_and_drives_not_the_tools(wheel)
    venv = _install(wheel, tmp_path / "venv")
    outside = tmp_path / "work"
    outside.mkdir()
    assert not outside.resolve().is_relative_to(REPO)
    _installed_not_from_the_source_tree(venv, outside)
    _check_a_golden_trace_fails_dir_hold(venv, outside)
    _drives_lists_the_library(venv, outside)
    _stepgen_plan(venv, outside)
    _stepgen_simulate_then_check(venv, outside)
    _sigrok_decoder_imports_the_installed_package(venv, outside)
