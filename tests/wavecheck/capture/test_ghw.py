"""GHDL's GHW files (issues 26, 27): the time unit they do not record, and every corrupt file a
one-line error.

Facts checked (``wavecheck/capture/ghw.py``): a GHW file's times are counts of GHDL's
``--time-resolution``, which the file does not record (the same run at fs and ps gives the same
file but for the times); GHDL's default resolution is fs. pywellen turns some malformed files
into Rust panics (pyo3's PanicException, not an Exception), RuntimeErrors, or prints ``WARN:
time decreased … Skipping!`` on standard output and goes on without the skipped data.
"""

from __future__ import annotations

import json
import random
import shutil
import subprocess
from pathlib import Path

import pytest

from wavecheck.api import check
from wavecheck.capture.ghw import read_ghw_header
from wavecheck.capture.open import open_capture
from wavecheck.cli import main
from wavecheck.errors import CaptureError, UsageError

SIM = Path(__file__).parent / "sim"
MAP = {"step": "dut.step", "dir": "dut.dir"}
pytestmark = pytest.mark.skipif(
    shutil.which("ghdl") is None, reason="needs Debian's ghdl (make system-deps)"
)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """gen.vhd run at GHDL's default resolution (fs) and at ps, each as GHW and VCD."""
    tmp = tmp_path_factory.mktemp("ghw")
    shutil.copy(SIM / "gen.vhd", tmp / "gen.vhd")
    subprocess.run(["ghdl", "-a", "gen.vhd"], check=True, cwd=tmp)
    subprocess.run(["ghdl", "-e", "tb"], check=True, cwd=tmp)
    for unit in ("fs", "ps"):
        subprocess.run(
            ["ghdl", "-r", f"--time-resolution={unit}", "tb", f"--vcd={unit}.vcd",
             f"--wave={unit}.ghw"],
            check=True, cwd=tmp, capture_output=True,
        )  # fmt: skip
    return {f"{u}.{e}": tmp / f"{u}.{e}" for u in ("fs", "ps") for e in ("vcd", "ghw")}


def _rules(report: object) -> list[tuple[object, ...]]:
    return [(r.rule, r.checked, r.violations, r.min_margin_ns) for r in report.rules]  # type: ignore[attr-defined]


def test_the_unit_is_stated_and_can_be_given(runs: dict[str, Path]) -> None:
    """A ps run read as fs is 1000x too short: the assumption is in every report's notes, and
    ``ghw:timescale=1ps`` reads it as the run's own VCD says."""
    truth = _rules(check(runs["ps.vcd"], "drv8825", map=MAP))
    given = check(runs["ps.ghw"], "drv8825", map=MAP, input_format="ghw:timescale=1ps")
    assert _rules(given) == truth
    assert any("1 ps per tick" in n for n in given.notes)
    assumed = check(runs["ps.ghw"], "drv8825", map=MAP)
    assert _rules(assumed) != truth
    assert any("1 fs per tick ASSUMED" in n and "ghw:timescale=1ps" in n for n in assumed.notes)
    # GHDL's default run is read right without the option, and says what it assumed
    default = check(runs["fs.ghw"], "drv8825", map=MAP)
    assert _rules(default) == _rules(check(runs["fs.vcd"], "drv8825", map=MAP)) == truth
    assert any("ASSUMED" in n for n in default.notes)


@pytest.mark.parametrize("fmt", ["text", "json"])
def test_every_report_says_the_unit(
    runs: dict[str, Path], capsys: pytest.CaptureFixture[str], fmt: str
) -> None:
    argv = ["check", str(runs["fs.ghw"]), "--drive", "drv8825", "--map", "step=dut.step"]
    main([*argv, "--format", fmt])
    out = capsys.readouterr().out
    text = json.dumps(json.loads(out)) if fmt == "json" else out
    assert "1 fs per tick ASSUMED" in text
    main(["info", str(runs["fs.ghw"])])
    assert "1 fs per tick ASSUMED" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("fmt", "message"),
    [
        ("ghw:timescale=1", "give a unit"),
        ("ghw:timescale=-1ps", "must be positive"),
        ("ghw:timescale=1MHz", "frequency where a time"),
        ("ghw:rate=1ps", "ghw takes one option, timescale=TIME"),
    ],
)
def test_bad_timescale_options(runs: dict[str, Path], fmt: str, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        open_capture(runs["fs.ghw"], input_format=fmt)


def _mutants(data: bytes, seed: int) -> list[bytes]:
    """Every truncation, and byte changes of every part of the file."""
    rng = random.Random(seed)
    out = [data[:n] for n in range(16, len(data))]
    for _ in range(400):
        b = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            b[rng.randrange(16, len(b))] = rng.randrange(256)
        out.append(bytes(b))
    return out


def test_corrupt_files_are_one_line_errors(
    runs: dict[str, Path], tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Truncated and corrupted files: a capture or a one-line CaptureError naming the file,
    never a Rust panic, a RuntimeError, or pywellen's own lines on the terminal."""
    data = runs["fs.ghw"].read_bytes()
    path = tmp_path / "bad.ghw"
    outcomes: dict[str, int] = {}
    for mutant in _mutants(data, 27):
        path.write_bytes(mutant)
        try:
            open_capture(path)
            outcomes["read"] = outcomes.get("read", 0) + 1
        except CaptureError as err:
            assert "\n" not in str(err) and str(path) in str(err)
            outcomes["refused"] = outcomes.get("refused", 0) + 1
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert outcomes.get("refused", 0) > len(data) - 16  # every truncation at least


def test_a_cut_header_names_the_byte(runs: dict[str, Path], tmp_path: Path) -> None:
    data = runs["fs.ghw"].read_bytes()
    path = tmp_path / "cut.ghw"
    path.write_bytes(data[:100])
    with pytest.raises(CaptureError, match=r"cut.ghw: byte \d+: the (file ends|string table)"):
        read_ghw_header(path)
    path.write_bytes(data[:9] + b"\x10\x00\x07" + data[12:])
    with pytest.raises(CaptureError, match="GHW version 7"):
        read_ghw_header(path)


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_one_bad_file_of_several_is_one_error_line(
    runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str], jobs: str
) -> None:
    """A panicking GHW among good captures: its error line, the others reported, -o written."""
    data = runs["fs.ghw"].read_bytes()
    bad = tmp_path / "b-panics.ghw"
    for mutant in _mutants(data, 5):  # the first mutant pywellen panics on
        bad.write_bytes(mutant)
        try:
            open_capture(bad)
        except CaptureError as err:
            if "ends inside" not in str(err) and "byte" not in str(err):
                break
    else:
        pytest.fail("no mutant reached pywellen")
    good = [shutil.copy(runs["fs.ghw"], tmp_path / f"{k}-good.ghw") for k in ("a", "c")]
    report = tmp_path / "report.json"
    argv = ["check", str(good[0]), str(bad), str(good[1]), "--drive", "drv8825",
            "--map", "step=dut.step,dir=dut.dir", "--format", "json", "-o", str(report), "-j", jobs]  # fmt: skip
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2
    assert [ln for ln in err.splitlines() if "error" in ln] == [
        ln for ln in err.splitlines() if str(bad) in ln
    ]
    doc = json.loads(report.read_text())
    assert len(doc["reports"]) == 2 and [e["path"] for e in doc["errors"]] == [str(bad)]


def test_a_port_is_the_signal_it_is_connected_to(runs: dict[str, Path]) -> None:
    """GHDL's GHW records a port and the signal it is connected to as one signal (pywellen gives
    ``tb.step`` and ``tb.dut.step`` one ``SignalId``): one channel, the port its alias. Read
    again after other reads (the flaky ``onehot.ghw`` of the roles tests took a freed object's
    ``id()`` for a signal's identity and lost ``tb.c`` as an "alias" of another line)."""
    for _ in range(3):
        cap = open_capture(runs["fs.ghw"])
        names = [c.name for c in cap.channels]
        assert names == ["tb.step", "tb.dir", "spare", "s", "d"], names
        assert cap.aliases == {
            "tb.spare": "spare",
            "tb.dut.step": "tb.step",
            "tb.dut.dir": "tb.dir",
            "tb.dut.s": "s",
            "tb.dut.d": "d",
        }
        assert cap.channel("tb.dut.step") is cap.channel("tb.step")


class _Ref:
    """pywellen 0.25's ``SignalId``: made anew at each access, its index only in its text (a
    small object whose freed address CPython hands to the next one at once)."""

    __slots__ = ("at",)

    def __init__(self, index: int) -> None:
        self.at = index

    def __str__(self) -> str:
        return f"SignalId({self.at})"


class _FakeVar:
    def __init__(self, full: str, index: int) -> None:
        self.full_name, self.name, self.index_ = full, full.rsplit(".", 1)[-1], index
        self.bitwidth, self.is_real, self.is_string = 1, False, False

    @property
    def signal_ref(self) -> _Ref:
        return _Ref(self.index_)

    @property
    def signal(self) -> list[tuple[int, int]]:
        return [(0, 0), (10 * (self.index_ + 1), 1)]


class _FakeWave:
    timescale = None

    def __init__(self, signals: list[tuple[str, int]]) -> None:
        self.vars = [_FakeVar(full, i) for full, i in signals]

    def all_vars(self) -> list[_FakeVar]:
        return self.vars


def test_signal_identity_is_the_index_not_the_object(
    runs: dict[str, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Eight distinct signals whose identity objects are freed as soon as read (their
    addresses reused) are eight channels; two names of index 3 are one channel and an alias."""
    from wavecheck.capture import wellen

    signals = [(f"tb.s{i}", i) for i in range(8)] + [("tb.dut.s3", 3)]
    monkeypatch.setattr(wellen, "_open", lambda path: _FakeWave(signals))
    cap = open_capture(runs["fs.ghw"])
    assert [c.name for c in cap.channels] == [f"s{i}" if i != 3 else "tb.s3" for i in range(8)]
    assert {c.name: int(c.edges[0]) for c in cap.channels} == {
        c.name: 10 * (int(c.name[-1]) + 1) for c in cap.channels
    }
    short = {f"tb.s{i}": f"s{i}" for i in range(8) if i != 3}
    assert cap.aliases == {**short, "tb.dut.s3": "tb.s3"}
