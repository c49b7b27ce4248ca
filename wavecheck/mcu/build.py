"""Builds for the MCU simulation, cached: the patched simavr runner and a firmware ELF.

Each build goes to a folder of the cache named by the SHA-256 of everything that goes into it (the
source tree, the patch, the runner's source, the options), so a second run with the same inputs
builds nothing, and a changed input builds anew. The cache is ``$WAVECHECK_CACHE`` or
``$XDG_CACHE_HOME/wavecheck`` (``~/.cache/wavecheck``). A build is made in a temporary folder and
renamed into place: an interrupted build leaves nothing a later run would take for finished.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from wavecheck.errors import ConfigError, UsageError

__all__ = [
    "SIMAVR_FILES",
    "build_firmware",
    "build_klippy",
    "build_runner",
    "cache_root",
    "tree_hash",
]

#: The GPL-3.0-or-later folder with the simavr patch and the runner's source.
SIMAVR_FILES = Path(__file__).resolve().parent / "simavr"
#: Folders and suffixes of build outputs, left out of a source tree's hash and copy.
_SKIP_DIRS = {".git", "build", "__pycache__"}
_SKIP_SUFFIXES = (".o", ".d", ".a", ".so", ".elf", ".hex")
#: The Debian packages each tool comes from (the hint of a missing-tool error).
_TOOLS = {
    "gcc": "gcc",
    "make": "make",
    "patch": "patch",
    "avr-gcc": "gcc-avr avr-libc binutils-avr",
}
#: Wall-time bound of one build step, s.
_BUILD_TIMEOUT_S = 600


def cache_root() -> Path:
    """The cache folder (created)."""
    root = os.environ.get("WAVECHECK_CACHE")
    if root:
        path = Path(root)
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
        path = Path(base) / "wavecheck"
    path.mkdir(parents=True, exist_ok=True)
    return path


def _files(tree: Path) -> list[Path]:
    out = []
    for dirpath, dirnames, filenames in os.walk(tree):
        dirnames[:] = sorted(
            d for d in dirnames if d not in _SKIP_DIRS and not d.startswith("obj-")
        )
        for name in sorted(filenames):
            if not name.endswith(_SKIP_SUFFIXES):
                out.append(Path(dirpath) / name)
    return out


def tree_hash(tree: Path, extra: Iterable[bytes] = ()) -> str:
    """SHA-256 (hex) of a source tree's file names and contents, then ``extra``."""
    h = hashlib.sha256()
    for path in _files(tree):
        h.update(str(path.relative_to(tree)).encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    for item in extra:
        h.update(item + b"\0")
    return h.hexdigest()


def _need(tool: str) -> None:
    if shutil.which(tool) is None:
        raise UsageError(
            f"{tool} not found: the MCU simulation builds with it "
            f"(Debian: apt-get install {_TOOLS[tool]}; or make setup)"
        )


def _run(cmd: Sequence[str], cwd: Path, what: str) -> None:
    try:
        done = subprocess.run(
            cmd, cwd=cwd, capture_output=True, text=True, timeout=_BUILD_TIMEOUT_S, check=False
        )
    except subprocess.TimeoutExpired:
        raise ConfigError(f"{what}: the build took over {_BUILD_TIMEOUT_S} s") from None
    if done.returncode:
        lines = [ln for ln in (done.stderr + done.stdout).splitlines() if "error" in ln.lower()]
        last = (lines or (done.stderr + done.stdout).splitlines() or ["?"])[-1].strip()
        raise ConfigError(f"{what}: the build failed: {last}")


def _source_tree(path: Path, what: str, marker: str) -> Path:
    if not (path / marker).is_file():
        raise UsageError(f"{path}: not a {what} source tree (no {marker})")
    return path


def _writable(tree: Path) -> None:
    """Owner write permission on a copied tree (a read-only checkout copies read-only)."""
    for dirpath, _, filenames in os.walk(tree):
        for name in (".", *filenames):
            path = Path(dirpath, name)
            path.chmod(path.stat().st_mode | 0o200)


def _cached(name: str, key: str, product: str, make: Callable[[Path], None]) -> Path:
    """``cache/NAME-KEY/PRODUCT``, made by ``make(folder)`` in a temporary folder if missing."""
    final = cache_root() / f"{name}-{key[:20]}"
    if (final / product).is_file():
        return final / product
    work = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=cache_root()))
    try:
        make(work)
        try:
            work.rename(final)
        except OSError:  # another process finished the same build first
            if not (final / product).is_file():
                raise
    finally:
        if work.exists():
            shutil.rmtree(work, ignore_errors=True)
    return final / product


def build_runner(simavr_src: Path, *, fixes: bool = True) -> Path:
    """The ``wavecheck-avr`` program, built with the patched simavr of ``simavr_src`` (or, with
    ``fixes=False``, with simavr as it is: the tests show what each fix changes)."""
    src = _source_tree(simavr_src, "simavr", "simavr/sim/avr_timer.c")
    patch = (SIMAVR_FILES / "fixes.patch").read_bytes() if fixes else b"unpatched"
    runner = (SIMAVR_FILES / "wavecheck_avr.c").read_bytes()
    key = tree_hash(src, (patch, runner))

    def make(work: Path) -> None:
        for tool in ("gcc", "make", "patch"):
            _need(tool)
        tree = work / "simavr-src"
        shutil.copytree(src, tree, ignore=shutil.ignore_patterns(".git", "obj-*", "*.o", "*.a"))
        if fixes:
            _run(["patch", "-p1", "-i", str(SIMAVR_FILES / "fixes.patch")], tree, "simavr patch")
        sim = tree / "simavr"
        _run(["make", "obj", "config"], sim, "simavr")
        _run(["make", "libsimavr"], sim, "simavr")
        (lib,) = sim.glob("obj-*/libsimavr.a")
        cmd = ["gcc", "-O2", "-Isim", "-I.", "-o", str(work / "wavecheck-avr")]
        cmd += [str(SIMAVR_FILES / "wavecheck_avr.c"), str(lib), "-lelf"]
        _run(cmd, sim, "wavecheck-avr")
        shutil.rmtree(tree)

    return _cached("simavr", key, "wavecheck-avr", make)


def build_firmware(
    src: Path,
    marker: str,
    replace: dict[str, bytes],
    target: Sequence[str],
    product: str,
    *,
    before: Sequence[Sequence[str]] = (),
    also: Sequence[str] = (),
) -> Path:
    """A firmware built with ``make TARGET`` in a copy of ``src`` whose files ``replace`` names
    (relative path → content) are replaced or added; returns the cached ``product`` (an ELF).

    ``before``: make arguments run first (each a make run); ``also``: other build outputs kept
    beside the product (by file name)."""
    tree_src = _source_tree(src, "firmware", marker)
    extra = [k.encode() + b"\0" + v for k, v in sorted(replace.items())]
    extra += [" ".join(t).encode() for t in (*before, target)] + [" ".join(also).encode()]
    key = tree_hash(tree_src, extra)

    def make(work: Path) -> None:
        _need("make")
        _need("avr-gcc")
        tree = work / "src"
        shutil.copytree(tree_src, tree, ignore=shutil.ignore_patterns(".git", "build", "*.o"))
        _writable(tree)
        for rel, content in replace.items():
            (tree / rel).parent.mkdir(parents=True, exist_ok=True)
            (tree / rel).write_bytes(content)
        (tree / "build").mkdir(exist_ok=True)
        for args in (*before, target):
            _run(["make", *args], tree, f"firmware {src.name}")
        for name in (product, *also):
            shutil.copy2(tree / name, work / Path(name).name)
        shutil.rmtree(tree)

    return _cached(f"fw-{src.name}", key, Path(product).name, make)


def build_klippy(klipper_src: Path, python: str) -> Path:
    """Klipper's host program (``klippy/``) copied into the cache with its C helper built
    (klippy compiles ``chelper/c_helper.so`` beside its sources on first use, which a read-only
    checkout forbids); returns the copy's ``klippy.py``."""
    src = _source_tree(klipper_src, "Klipper", "klippy/klippy.py") / "klippy"
    key = tree_hash(src, (python.encode(),))

    def make(work: Path) -> None:
        _need("gcc")
        tree = work / "klippy"
        shutil.copytree(src, tree, ignore=shutil.ignore_patterns("*.so", "__pycache__"))
        _writable(tree)
        code = "import chelper; chelper.get_ffi()"
        _run([python, "-c", code], tree, "klippy's C helper (needs cffi: pip install cffi)")

    return _cached("klippy", key, "klippy/klippy.py", make)
