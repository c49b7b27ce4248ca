"""Longer fuzz runs of each reader, outside the test suite (issues 8, 27).

    .venv/bin/python -m tests.reliability.fuzz                     # all readers, 2000 mutants each
    .venv/bin/python -m tests.reliability.fuzz --reader vcd -n 20000 --seed 7
    .venv/bin/python -m tests.reliability.fuzz --reader sr --atheris -- -runs=100000   # coverage-guided

Each reader gets its fixed corpus (``corpus.py``), the truncations of a valid file at every
offset, and ``-n`` random mutants of valid files (byte flips, cuts, splices of other files,
inserted tokens, repeated ranges). The contract: a result, or a :class:`WavecheckError` whose
message is one line naming the file; any other exception is a failure, grouped by type and
place and printed with a reproducer. Each case is also bounded: a case taking more than
``MAX_CASE_SECONDS`` or a peak of more than ``MAX_CASE_BYTES`` traced memory (tracemalloc) is a
failure too, so the hostile shapes (chunk numbers far apart, overlapping zip entries, 20,000
``$var`` lines, a body without whitespace) must cost bounded time and memory. ``make fuzz`` runs
the default. Exit 1 if anything failed.

The readers whose work is in native code or a C extension (GHW through pywellen; FST through
our decoder, whose zlib/LZ4 is native, and pywellen; a Rust panic or abort, memory tracemalloc
cannot see) and the newer readers (Saleae CSV and binary,
latency files and histograms, ``follow`` command files) run each case in a forked child under
``RLIMIT_AS`` (:data:`FORK_EXTRA_BYTES` beyond the parent's address space) and a wall-clock
bound: a child killed by a signal, past its time, or out of memory is a failure.

``--atheris`` uses atheris (``pip install atheris``) when it is installed: libFuzzer-style
coverage-guided mutation of the same targets; arguments after ``--`` go to libFuzzer.
"""

from __future__ import annotations

import argparse
import os
import random
import resource
import signal
import sys
import tempfile
import time
import traceback
import tracemalloc
from collections import Counter
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

from tests.reliability.corpus import (
    base_sr_raw,
    rule_cases,
    rule_text,
    sr_bytes,
    sr_cases,
    vcd_cases,
    vcd_text,
)
from tests.reliability.seeds import (
    follow_seeds,
    fst_seeds,
    ghw_seeds,
    latency_seeds,
    saleae_bin_seeds,
    saleae_csv_seeds,
)
from wavecheck.errors import WavecheckError

_TOKENS = [b"#", b"#0", b"#-1", b"$end", b"$var wire 1 ! x $end", b"x!", b"1?", b"b1 !", b"\x00",
           b"PK\x03\x04", b"[device 1]", b"unitsize=0", b"samplerate=0", b"\n", b"=", b"\xff" * 8]  # fmt: skip


def _read_sr(path: Path) -> None:
    from wavecheck.capture.sr import read_sr

    read_sr(path, chunk_bytes=64)


def _read_vcd(path: Path) -> None:
    from wavecheck.capture.vcd import read_vcd

    read_vcd(path, chunk_bytes=37)


def _read_rules(path: Path) -> None:
    from wavecheck.drives.library import load_drive

    load_drive(path)


def _read_sigrok(path: Path) -> None:
    from fractions import Fraction

    from wavecheck.capture.sigrokcli import read_with_sigrok

    read_with_sigrok(path, "csv", samplerate=Fraction(10**6))


def _read_ghw(path: Path) -> None:
    from wavecheck.capture.open import open_capture

    cap = open_capture(path, input_format="ghw")
    for key, vec in cap.vectors.items():  # a bit of each vector, read again from the file
        cap.bit(key, vec.lsb)


def _read_fst(path: Path) -> None:
    from wavecheck.capture.open import open_capture
    from wavecheck.capture.wellen import read_wellen

    open_capture(path, input_format="fst")  # the native reader (capture/fst.py)
    read_wellen(path, kind="fst")  # through pywellen


def _read_saleae_csv(path: Path) -> None:
    from wavecheck.capture.open import open_capture

    open_capture(path, input_format="saleae-csv")


def _read_saleae_bin(path: Path) -> None:
    from wavecheck.capture.saleae_binary import read_saleae_binary

    read_saleae_binary(path, samplerate=Fraction(10**7))  # version 0 states no rate


def _read_latency(path: Path) -> None:
    from stepgen.latencyfiles import read_latency_file

    read_latency_file(path)


def _read_histogram(path: Path) -> None:
    from stepgen.latencyfiles import read_histogram

    read_histogram(path)


def _read_follow(path: Path) -> None:
    from wavecheck.follow import read_command

    read_command(path)


def _read_halsampler(path: Path) -> None:
    from wavecheck.follow import read_command

    read_command(path, sample_period_s=Fraction(1, 1000), tagged=True)


READERS: dict[str, tuple[Callable[[Path], None], str, list[bytes]]] = {
    "sr": (_read_sr, ".sr", [sr_bytes(base_sr_raw()), sr_bytes(base_sr_raw(300), chunk=7)]),
    "vcd": (_read_vcd, ".vcd", [vcd_text().encode(), vcd_text(timescale="10 us").encode()]),
    "rules": (_read_rules, ".toml", [rule_text().encode()]),
    "sigrok": (
        _read_sigrok,
        ".csv",
        [b"a,b,c\n" + b"".join(b"%d,%d,%d\n" % (i & 1, i >> 1 & 1, i >> 2 & 1) for i in range(40))],
    ),
    "ghw": (_read_ghw, ".ghw", list(ghw_seeds())),
    "fst": (_read_fst, ".fst", list(fst_seeds())),
    "saleae-csv": (_read_saleae_csv, ".csv", list(saleae_csv_seeds())),
    "saleae-bin": (_read_saleae_bin, ".bin", list(saleae_bin_seeds())),
    "latency": (_read_latency, ".txt", list(latency_seeds())),
    "histogram": (_read_histogram, ".txt", list(latency_seeds())),
    "follow": (_read_follow, ".csv", list(follow_seeds())),
    "halsampler": (_read_halsampler, ".txt", list(follow_seeds())),
}
FIXED = {"sr": sr_cases, "vcd": vcd_cases, "rules": rule_cases}
#: Readers run in a forked child per case, under RLIMIT_AS and a time bound.
FORKED = {"ghw", "fst", "saleae-csv", "saleae-bin", "latency", "histogram", "follow", "halsampler"}
#: Address space a forked case may add to the parent's.
FORK_EXTRA_BYTES = 512 << 20


def mutate(rng: random.Random, data: bytes, others: list[bytes]) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(6)
        pos = rng.randrange(len(b) + 1) if b else 0
        if op == 0 and b:
            b[min(pos, len(b) - 1)] ^= rng.randint(1, 255)
        elif op == 1:
            del b[pos:]
        elif op == 2:
            b[pos:pos] = rng.choice(_TOKENS)
        elif op == 3 and b:
            end = min(len(b), pos + rng.randint(1, 64))
            b[pos:pos] = b[pos:end] * rng.randint(1, 4)
        elif op == 4:
            other = rng.choice(others)
            j = rng.randrange(len(other) + 1)
            b[pos:] = other[j:]
        elif op == 5 and b:
            del b[pos : pos + rng.randint(1, 16)]
    return bytes(b)


#: Bounds for one case in-process (the hostile shapes of issue 12 included): wall time and the
#: peak of memory allocated while reading (tracemalloc sees Python objects and numpy buffers).
MAX_CASE_SECONDS = 20.0
MAX_CASE_BYTES = 256 << 20


class Tally:
    def __init__(
        self, name: str, max_seconds: float | None = None, max_bytes: int | None = None
    ) -> None:
        self.name = name
        self.max_seconds = max_seconds
        self.max_bytes = max_bytes
        self.peak_bytes = 0
        self.cases = 0
        self.errors = 0
        self.results = 0
        self.failures: Counter[str] = Counter()
        self.examples: dict[str, bytes] = {}
        self.slowest = 0.0

    def run_forked(self, reader: Callable[[Path], None], path: Path, data: bytes) -> None:
        """One case in a forked child: address space limited, killed past the time bound."""
        path.write_bytes(data)
        self.cases += 1
        start = time.monotonic()
        kind, text = _forked(reader, path, self.max_seconds or MAX_CASE_SECONDS)
        self.slowest = max(self.slowest, time.monotonic() - start)
        if kind == "result":
            self.results += 1
            return
        if kind == "error":
            self.errors += 1
            if "\n" in text or str(path) not in text:
                kind, text = "contract", f"message not one line naming the file: {text[:120]!r}"
            else:
                return
        key = f"{kind}: {text}"
        self.failures[key] += 1
        self.examples.setdefault(key, data)

    def run(self, reader: Callable[[Path], None], path: Path, data: bytes) -> None:
        path.write_bytes(data)
        self.cases += 1
        if self.max_bytes is not None:
            tracemalloc.start()
        start = time.monotonic()
        try:
            reader(path)
            self.results += 1
        except WavecheckError as err:
            text = str(err)
            self.errors += 1
            if "\n" in text or str(path) not in text:
                key = f"contract: message not one line naming the file: {text[:120]!r}"
                self.failures[key] += 1
                self.examples.setdefault(key, data)
        except Exception as exc:  # noqa: BLE001 - every other exception is a finding
            tb = traceback.extract_tb(exc.__traceback__)[-1]
            key = f"{type(exc).__name__}: {str(exc)[:80]} at {Path(tb.filename).name}:{tb.lineno}"
            self.failures[key] += 1
            self.examples.setdefault(key, data)
        finally:
            took = time.monotonic() - start
            peak = 0
            if self.max_bytes is not None:
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
        self.slowest = max(self.slowest, took)
        self.peak_bytes = max(self.peak_bytes, peak)
        for what, value, bound in (
            ("slow", took, self.max_seconds),
            ("memory", peak, self.max_bytes),
        ):
            if bound is not None and value > bound:
                key = f"bound: {what} {value:.4g} > {bound:.4g} on a {len(data)}-byte input"
                self.failures[key] += 1
                self.examples.setdefault(key, data)

    def report(self, out: Path) -> str:
        lines = [
            f"{self.name}: {self.cases} cases, {self.errors} refused (exit 2), {self.results} read, "
            f"{sum(self.failures.values())} failures of {len(self.failures)} kinds, "
            f"slowest {self.slowest:.2f} s"
            + (f", peak {self.peak_bytes / 2**20:.1f} MiB" if self.max_bytes is not None else "")
        ]
        for i, (key, n) in enumerate(self.failures.most_common()):
            repro = out / f"{self.name}-failure-{i}{READERS[self.name][1]}"
            repro.write_bytes(self.examples[key])
            lines.append(f"  {n:6d} × {key}  (reproducer: {repro})")
        return "\n".join(lines)


def _address_space() -> int:
    """This process's address space in bytes (VmSize)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
    return 1 << 30


def _forked(reader: Callable[[Path], None], path: Path, seconds: float) -> tuple[str, str]:
    """Run ``reader(path)`` in a forked child under RLIMIT_AS and a time bound: ("result", ""),
    ("error", message of a WavecheckError), or a failure kind ("exception", "killed",
    "bound") with what happened."""
    limit = _address_space() + FORK_EXTRA_BYTES
    rfd, wfd = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        code = 0
        try:
            os.close(rfd)
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
            try:
                reader(path)
                out = "result\t"
            except WavecheckError as err:
                out = f"error\t{err}"
            except MemoryError:
                out = "bound\tmemory: MemoryError under RLIMIT_AS"
            except BaseException as exc:  # noqa: BLE001 - a Rust panic included
                tb = traceback.extract_tb(exc.__traceback__)[-1]
                out = (f"exception\t{type(exc).__name__}: {str(exc)[:80]} at "
                       f"{Path(tb.filename).name}:{tb.lineno}")  # fmt: skip
            os.write(wfd, out.encode("utf-8", "replace")[: 1 << 15])
        except BaseException:  # noqa: BLE001
            code = 70
        finally:
            os._exit(code)
    os.close(wfd)
    deadline = time.monotonic() + seconds
    chunks = []
    status = None
    while status is None:
        done, st = os.waitpid(pid, os.WNOHANG)
        if done:
            status = st
            break
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(rfd)
            return "bound", f"slow: past {seconds:g} s"
        time.sleep(0.002)
    while chunk := os.read(rfd, 1 << 15):
        chunks.append(chunk)
    os.close(rfd)
    if os.WIFSIGNALED(status):
        return "killed", f"by {signal.Signals(os.WTERMSIG(status)).name} (a crash or an abort)"
    kind, _, text = b"".join(chunks).decode("utf-8", "replace").partition("\t")
    return (kind, text) if kind else ("killed", f"exit status {os.WEXITSTATUS(status)}")


def run_random(
    name: str,
    n: int,
    seed: int,
    out: Path,
    *,
    max_seconds: float | None = MAX_CASE_SECONDS,
    max_bytes: int | None = MAX_CASE_BYTES,
    cuts: int = 400,
) -> Tally:
    """The fixed corpus, the truncations (at most ``cuts`` per seed, evenly spread, the whole
    seed included) and ``n`` mutants of ``name``'s reader; a case past ``max_seconds`` or
    ``max_bytes`` (None: unmeasured) is a failure like an exception."""
    reader, suffix, seeds = READERS[name]
    tally = Tally(name, max_seconds, max_bytes)
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory(prefix=f"fuzz-{name}-") as tmp:
        # a rule file's name must be its id
        path = Path(tmp) / ("fuzz-drive.toml" if name == "rules" else f"input{suffix}")
        one = tally.run_forked if name in FORKED else tally.run
        if name in FORKED and seeds:  # the reader's modules imported once, not in every child
            path.write_bytes(seeds[0])
            try:
                reader(path)
            except WavecheckError:
                pass
        if name in FIXED:
            for case in FIXED[name]():
                one(reader, path, case.data)
        if name != "sigrok":
            for s in seeds:
                step = max(1, len(s) // cuts)  # every offset of a small seed
                for cut in [*range(0, len(s), step), len(s)]:  # the whole seed too
                    one(reader, path, s[:cut])
        # splice material: the small fixed cases (the big hostile shapes run once, above)
        others = (
            [c.data for c in FIXED[name]() if len(c.data) < 1 << 16] if name in FIXED else seeds
        )
        for _ in range(n):
            one(reader, path, mutate(rng, rng.choice(seeds), others + seeds))
    return tally


def run_atheris(name: str, argv: list[str]) -> None:  # pragma: no cover - optional tool
    import atheris  # type: ignore[import-not-found]

    import wavecheck.capture.sigrokcli
    import wavecheck.capture.sr
    import wavecheck.capture.vcd
    import wavecheck.drives.library  # noqa: F401 - loaded before instrumenting

    reader, suffix, seeds = READERS[name]
    tmp = Path(tempfile.mkdtemp(prefix=f"atheris-{name}-"))
    path = tmp / ("fuzz-drive.toml" if name == "rules" else f"input{suffix}")
    corpus = tmp / "corpus"
    corpus.mkdir()
    for i, data in enumerate(
        [*seeds, *(c.data for c in FIXED[name]())] if name in FIXED else seeds
    ):
        (corpus / f"seed{i}").write_bytes(data)

    def one(data: bytes) -> None:
        path.write_bytes(data)
        try:
            reader(path)
        except WavecheckError as err:
            if "\n" in str(err) or str(path) not in str(err):
                raise AssertionError(f"bad message: {err}") from None

    atheris.instrument_all()
    print(f"atheris: seed corpus in {corpus}", flush=True)
    crashes = Path(tempfile.gettempdir()) / "wavecheck-fuzz"
    crashes.mkdir(exist_ok=True)
    args = [*argv, f"-artifact_prefix={crashes}/{name}-"]
    atheris.Setup([sys.argv[0], *args, str(corpus)], one)
    atheris.Fuzz()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reader", choices=[*READERS, "all"], default="all")
    p.add_argument("-n", type=int, default=2000, help="random mutants per reader")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "wavecheck-fuzz")
    p.add_argument("--atheris", action="store_true", help="coverage-guided (needs atheris)")
    p.add_argument("rest", nargs="*", help="after --: libFuzzer arguments (with --atheris)")
    args = p.parse_args(argv)
    if args.atheris:
        if args.reader == "all":
            p.error("--atheris needs one --reader")
        run_atheris(args.reader, args.rest)
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    names = list(READERS) if args.reader == "all" else [args.reader]
    failed = 0
    for name in names:
        if name == "sigrok":
            import shutil

            if shutil.which("sigrok-cli") is None:
                print("sigrok: skipped (sigrok-cli not installed)")
                continue
        if not READERS[name][2]:
            print(f"{name}: skipped (the tool that makes its seeds is not installed)")
            continue
        n = args.n if name != "sigrok" else max(1, args.n // 20)  # one subprocess per case
        tally = run_random(name, n, args.seed, args.out)
        print(tally.report(args.out), flush=True)
        failed += sum(tally.failures.values())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
