"""``wavecheck sigrok install``: put the decoder where libsigrokdecode looks, and prove it runs.

libsigrokdecode 0.5.3 loads a decoder by its folder name from, in order: its own decoder
directory (``/usr/share/libsigrokdecode/decoders``), ``libsigrokdecode/decoders`` under each
``$XDG_DATA_DIRS`` entry and under the user data directory (``$XDG_DATA_HOME``, by default
``~/.local/share``), and ``$SIGROKDECODE_DIR``. PulseView and sigrok-cli both use it.

The decoder runs in libsigrokdecode's embedded Python (Debian 12: the system's 3.11), which does
not see the environment wavecheck is installed in; so the folder gets an ``install.json``
naming the directories this Python imports wavecheck and numpy from, and the Python version
(compiled modules such as numpy's load only into the same minor version). :func:`probe` then runs
sigrok-cli with the installed decoder on a small capture with one known violation.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from wavecheck.errors import UsageError
from wavecheck.output import atomic_write

__all__ = [
    "DECODER_ID",
    "Installed",
    "decoder_files",
    "install",
    "install_record",
    "probe",
    "searched_dirs",
    "user_dir",
]

#: The decoder's id and folder name (``-P wavecheck``; PulseView's decoder list).
DECODER_ID = "wavecheck"
_FILES = ("__init__.py", "pd.py")
_SYSTEM_DIR = Path("/usr/share/libsigrokdecode/decoders")


def user_dir() -> Path:
    """``libsigrokdecode/decoders`` in the user data directory (searched by default)."""
    base = os.environ.get("XDG_DATA_HOME") or os.path.join(Path.home(), ".local", "share")
    return Path(base) / "libsigrokdecode" / "decoders"


def searched_dirs() -> list[Path]:
    """The decoder directories libsigrokdecode 0.5.3 searches in this environment."""
    system = os.environ.get("XDG_DATA_DIRS") or "/usr/local/share:/usr/share"
    dirs = [_SYSTEM_DIR]
    dirs += [Path(d) / "libsigrokdecode" / "decoders" for d in system.split(":") if d]
    dirs.append(user_dir())
    if os.environ.get("SIGROKDECODE_DIR"):
        dirs.append(Path(os.environ["SIGROKDECODE_DIR"]))
    return dirs


def decoder_files() -> dict[str, str]:
    """The decoder's files as shipped in the package: name → text."""
    pkg = resources.files("wavecheck.sigrok.decoder")
    return {name: pkg.joinpath(name).read_text(encoding="utf-8") for name in _FILES}


def install_record() -> dict[str, object]:
    """What the decoder needs to import wavecheck from libsigrokdecode's Python."""
    import numpy

    import wavecheck

    paths: list[str] = []
    for p in (
        Path(wavecheck.__file__).resolve().parent.parent,
        Path(numpy.__file__).resolve().parent.parent,
        Path(sysconfig.get_paths()["purelib"]),
        Path(sysconfig.get_paths()["platlib"]),
    ):
        if str(p) not in paths:
            paths.append(str(p))
    return {
        "wavecheck": wavecheck.__version__,
        "python": "{}.{}".format(*sys.version_info[:2]),
        "executable": sys.executable,
        "paths": paths,
    }


@dataclass(frozen=True)
class Installed:
    """Where the decoder went, and whether libsigrokdecode finds it there without help."""

    folder: Path
    searched: bool
    """True when the directory is one libsigrokdecode searches by default."""

    @property
    def env_line(self) -> str:
        """The ``SIGROKDECODE_DIR`` line for a directory libsigrokdecode does not search, quoted
        for a POSIX shell (a space or ``;`` in the path stays part of it)."""
        return f"export SIGROKDECODE_DIR={shlex.quote(str(self.folder.parent))}"


def install(directory: str | os.PathLike[str] | None = None) -> Installed:
    """Write the decoder (its files and ``install.json``) into ``directory``/wavecheck (default:
    :func:`user_dir`); an existing folder of that name is replaced only if it is this decoder.

    Raises:
        UsageError: the folder exists and is not this decoder, or cannot be written.
    """
    base = Path(directory) if directory is not None else user_dir()
    folder = base / DECODER_ID
    if folder.exists() and not _ours(folder):
        raise UsageError(
            f"{folder}: exists and is not wavecheck's decoder; remove it or give another --dir"
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"{folder}: cannot create ({err.strerror or err})") from None
    for name, text in decoder_files().items():
        atomic_write(folder / name, text)
    atomic_write(folder / "install.json", json.dumps(install_record(), indent=2) + "\n")
    shutil.rmtree(folder / "__pycache__", ignore_errors=True)  # compiled by an older copy
    return Installed(folder, any(_same(base, d) for d in searched_dirs()))


def _ours(folder: Path) -> bool:
    pd = folder / "pd.py"
    try:
        return pd.is_file() and 'id = "wavecheck"' in pd.read_text(encoding="utf-8")
    except OSError:
        return False


def _same(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


@dataclass(frozen=True)
class Probe:
    """What sigrok-cli said when it ran the installed decoder on the probe capture."""

    ok: bool
    text: str


def probe(installed: Installed, sigrok_cli: str = "sigrok-cli") -> Probe:
    """Run sigrok-cli with the installed decoder on a small capture (1 MHz) whose second STEP
    pulse is 2 us high, against the Gecko G202 (high time at least 4.5 us)."""
    if shutil.which(sigrok_cli) is None:
        return Probe(False, "sigrok-cli is not installed: the decoder was not tried")
    import numpy as np

    from wavecheck.capture.srzip import write_sr_edges

    env = dict(os.environ, SIGROKDECODE_DIR=str(installed.folder.parent))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "probe.sr"
        step = np.array([10, 20, 30, 32, 40, 50], dtype=np.int64)
        write_sr_edges(path, ["STEP"], [step], [0], 60, samplerate=1_000_000)
        spec = f"{DECODER_ID}:step=STEP:drive=gecko-g202"
        cmd = [sigrok_cli, "-i", str(path), "-P", spec, "-A", f"{DECODER_ID}=violations:messages"]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=60)
        except (OSError, subprocess.TimeoutExpired) as err:
            return Probe(False, f"sigrok-cli did not run: {err}")
    out = (run.stdout + run.stderr).strip()
    if "step_high: measured 2 us" in run.stdout:
        return Probe(True, "sigrok-cli ran the decoder: it found the probe's 2 us pulse")
    return Probe(False, out.splitlines()[-1] if out else f"sigrok-cli exited {run.returncode}")
