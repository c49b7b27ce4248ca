"""``wavecheck sigrok install``: where the decoder goes, what it records, and what the decoder says
when libsigrokdecode's Python cannot import wavecheck (issue 28)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import wavecheck
from tests.wavecheck.sigrok.conftest import need
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.cli import main
from wavecheck.sigrok.decoder import pd
from wavecheck.sigrok.install import Installed, install, probe, searched_dirs, user_dir


def test_install_writes_the_decoder_and_what_its_python_needs(tmp_path: Path) -> None:
    got = install(tmp_path)
    files = sorted(p.name for p in got.folder.iterdir())
    assert files == ["__init__.py", "install.json", "pd.py"]
    record = json.loads((got.folder / "install.json").read_text())
    assert record["python"] == "{}.{}".format(*sys.version_info[:2])
    assert record["wavecheck"] == wavecheck.__version__
    assert str(Path(np.__file__).resolve().parent.parent) in record["paths"]
    assert not got.searched and got.env_line == f"export SIGROKDECODE_DIR={tmp_path}"


def test_the_user_directory_is_searched(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    monkeypatch.delenv("SIGROKDECODE_DIR", raising=False)
    assert user_dir() == tmp_path / "libsigrokdecode" / "decoders"
    assert user_dir() in searched_dirs()
    assert install().searched


def test_a_foreign_decoder_folder_is_not_replaced(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "wavecheck").mkdir()
    (tmp_path / "wavecheck" / "pd.py").write_text("id = 'someone-else'\n")
    assert main(["sigrok", "install", "--dir", str(tmp_path), "--no-probe"]) == 2
    err = capsys.readouterr().err
    assert "exists and is not wavecheck's decoder" in err and err.count("\n") == 1
    assert (tmp_path / "wavecheck" / "pd.py").read_text() == "id = 'someone-else'\n"
    install(tmp_path / "again")
    assert install(tmp_path / "again").folder.is_dir()  # its own copy is replaced


def test_the_installed_copy_is_the_packaged_decoder(tmp_path: Path) -> None:
    folder = install(tmp_path).folder
    assert (folder / "pd.py").read_text() == Path(pd.__file__).read_text()


def test_cli_install_probes_with_sigrok_cli(tmp_path: Path) -> None:
    need("sigrok-cli")
    run = subprocess.run(
        [sys.executable, "-m", "wavecheck", "sigrok", "install", "--dir", str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    assert "ok: sigrok-cli ran the decoder: it found the probe's 2 us pulse" in run.stdout
    assert f"export SIGROKDECODE_DIR={tmp_path}" in run.stdout


def _spoil(folder: Path, **record: object) -> None:
    data = json.loads((folder / "install.json").read_text())
    data.update(record)
    (folder / "install.json").write_text(json.dumps(data))


@pytest.mark.parametrize(
    "record, says",
    [
        ({"paths": []}, "No module named 'wavecheck'"),
        ({"paths": [], "python": "3.99"}, "it was installed from Python 3.99"),
    ],
)
def test_the_decoder_says_when_it_cannot_import_wavecheck(
    tmp_path: Path, record: dict[str, object], says: str
) -> None:
    """libsigrokdecode's Python without the recorded paths: the Messages row and stderr say why
    and what to do; sigrok-cli goes on (no traceback)."""
    need("sigrok-cli")
    folder = install(tmp_path / "decoders").folder
    _spoil(folder, **record)
    result = probe(Installed(folder, searched=False))
    assert not result.ok
    path = tmp_path / "p.sr"
    write_sr_edges(path, ["STEP"], [np.array([10, 20], np.int64)], [0], 30, samplerate=1_000_000)
    env = dict(os.environ, SIGROKDECODE_DIR=str(folder.parent))
    spec = "wavecheck:step=STEP:drive=gecko-g202"
    run = subprocess.run(
        ["sigrok-cli", "-i", str(path), "-P", spec, "-A", "wavecheck=messages"],
        capture_output=True, text=True, env=env,
    )  # fmt: skip
    assert "Traceback" not in run.stderr
    (line,) = run.stdout.splitlines()
    assert "cannot import wavecheck" in line and says in line
    assert "wavecheck sigrok install" in line
    assert line.split(": ", 1)[1] in run.stderr


def test_a_stale_installed_copy_says_so(tmp_path: Path) -> None:
    need("sigrok-cli")
    folder = install(tmp_path / "decoders").folder
    text = (folder / "pd.py").read_text()
    (folder / "pd.py").write_text(text.replace("\nAPI = 1\n", "\nAPI = 0\n"))
    result = probe(Installed(folder, searched=False))
    assert not result.ok
    assert "this copy of the decoder does not match wavecheck" in result.text
    assert "run 'wavecheck sigrok install' again" in result.text


def test_the_decoder_needs_wavecheck_only_when_it_runs() -> None:
    """Loading the decoder (``sigrok-cli -L`` loads them all) imports nothing of wavecheck."""
    code = (
        "import sys, importlib.util; sys.modules['sigrokdecode'] = None\n"
        f"spec = importlib.util.spec_from_file_location('wavecheck', {pd.__file__!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "print(sorted(n for n in sys.modules if n.startswith(('wavecheck.', 'numpy'))))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.stdout.strip() == "[]", run.stderr


@pytest.mark.parametrize("name", ["PATH WITH SPACE", "a;touch PWNED", "it's $HOME `id`"])
def test_the_export_line_is_quoted_for_the_shell(tmp_path: Path, name: str) -> None:
    """Issue 34: ``sigrok install --dir "PATH WITH SPACE"`` printed an unquoted export line; with
    a ``;`` in the path, pasting it ran a command. The printed line, run by a real shell, sets
    the variable to the path and runs nothing else."""
    target = tmp_path / name
    run = subprocess.run(
        [sys.executable, "-m", "wavecheck", "sigrok", "install", "--dir", str(target)],
        capture_output=True,
        text=True,
    )
    assert run.returncode in (0, 1), run.stderr  # 1: no sigrok-cli to probe with
    line = next(ln.strip() for ln in run.stdout.splitlines() if "SIGROKDECODE_DIR=" in ln)
    shell = subprocess.run(
        ["sh", "-c", f'{line}\nprintf %s "$SIGROKDECODE_DIR"'],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert shell.returncode == 0, shell.stderr
    assert shell.stdout == str(target)
    assert not (tmp_path / "PWNED").exists()
