"""Raw binary samples (sigrok-cli's ``-O binary``), read natively from a file or a pipe (issue 14,
"From a pipe"): the same edges as the ``.sr`` reader on the same bytes, at any chunk size, and
``sigrok-cli -i X.sr -O binary | wavecheck check -`` gives ``wavecheck check X.sr``'s result."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.doc_pages import marked
from tests.wavecheck.capture.srutil import write_sr
from wavecheck.capture.binary import parse_binary_format, read_binary
from wavecheck.capture.open import open_capture
from wavecheck.capture.sigrokcli import find_sigrok_cli, read_with_sigrok
from wavecheck.capture.sr import read_sr
from wavecheck.errors import CaptureError, UsageError

REPO = Path(__file__).resolve().parents[3]
MHZ = Fraction(10**6)


def _edges(raw: np.ndarray, unitsize: int, bit: int) -> list[int]:
    """Sample indexes where bit ``bit`` changes, counted with plain numpy (independent)."""
    samples = raw.reshape(-1, unitsize)
    level = (samples[:, bit // 8] >> (bit % 8)) & 1
    return (np.flatnonzero(np.diff(level.astype(np.int8))) + 1).tolist()


@settings(max_examples=60)
@given(
    numchannels=st.integers(1, 20),
    nsamples=st.integers(1, 300),
    chunk=st.integers(1, 64),
    seed=st.integers(0, 2**32 - 1),
    stream=st.booleans(),
)
def test_edges_equal_the_sr_reader_at_any_chunk_size(
    tmp_path_factory: pytest.TempPathFactory,
    numchannels: int,
    nsamples: int,
    chunk: int,
    seed: int,
    stream: bool,
) -> None:
    """The bytes of a ``.sr``'s logic chunks, read as raw binary (from a file or a stream, in
    chunks down to one byte), give the ``.sr`` reader's channels, and a plain numpy count."""
    unitsize = (numchannels + 7) // 8
    rng = np.random.default_rng(seed)
    raw = (rng.random(nsamples * unitsize) < 0.1).astype(np.uint8) * rng.integers(
        0, 256, nsamples * unitsize, dtype=np.uint8
    )
    raw = np.bitwise_xor.accumulate(raw.reshape(-1, unitsize), axis=0).ravel().astype(np.uint8)
    tmp = tmp_path_factory.mktemp("bin")
    sr = write_sr(
        tmp / "x.sr", raw, probes={i: str(i) for i in range(numchannels)}, total=numchannels,
        unitsize=unitsize,
    )  # fmt: skip
    (tmp / "x.bin").write_bytes(raw.tobytes())
    src = io.BytesIO(raw.tobytes()) if stream else tmp / "x.bin"
    got = read_binary(src, f"binary:numchannels={numchannels}", name="x", samplerate=MHZ,
                      chunk_bytes=chunk)  # fmt: skip
    ref = read_sr(sr)
    assert got.end == ref.end == nsamples
    assert [c.name for c in got.channels] == [c.name for c in ref.channels]
    for a, b in zip(got.channels, ref.channels, strict=True):
        assert (a.index, a.initial, a.edges.tolist()) == (b.index, b.initial, b.edges.tolist())
        assert a.edges.tolist() == _edges(raw, unitsize, a.index)


def test_bits_above_numchannels_are_ignored() -> None:
    """numchannels=3: bits 3–7 of each byte are not channels (sigrok-cli ignores them too)."""
    cap = read_binary(io.BytesIO(bytes([0xF8, 0x01, 0xF9, 0x00])), "binary:numchannels=3",
                      samplerate=MHZ)  # fmt: skip
    assert [c.name for c in cap.channels] == ["0", "1", "2"]
    assert cap.channels[0].edges.tolist() == [1, 3] and cap.channels[1].edges.tolist() == []


@pytest.mark.parametrize(
    ("spec", "numchannels", "rate"),
    [
        ("binary", 8, None),
        ("binary:numchannels=4", 4, None),
        ("binary:numchannels=9:samplerate=24000000", 9, Fraction(24_000_000)),
        ("binary: samplerate = 1000 ", 8, Fraction(1000)),
    ],
)
def test_format_options(spec: str, numchannels: int, rate: Fraction | None) -> None:
    fmt = parse_binary_format(spec)
    assert (fmt.numchannels, fmt.samplerate, fmt.unitsize) == (
        numchannels, rate, (numchannels + 7) // 8
    )  # fmt: skip


@pytest.mark.parametrize(
    "spec",
    [
        "binary:bogus=1",
        "binary:numchannels=0",
        "binary:numchannels=x",
        "binary:samplerate",
        "binary:numchannels=513",
    ],  # fmt: skip
)
def test_bad_format_options_are_usage_errors(spec: str) -> None:
    with pytest.raises(UsageError, match="--input-format"):
        parse_binary_format(spec)


def test_rate_from_the_format_option_and_override_noted() -> None:
    data = bytes([0, 1, 0, 1])
    cap = read_binary(io.BytesIO(data), "binary:numchannels=1:samplerate=2000000")
    assert cap.samplerate_hz == 2_000_000 and cap.notes == []
    cap = read_binary(io.BytesIO(data), "binary:numchannels=1:samplerate=2000000", samplerate=MHZ)
    assert cap.samplerate_hz == MHZ and "overrides" in cap.notes[0]


@pytest.mark.parametrize(
    ("data", "spec", "kwargs", "match"),
    [
        (b"", "binary", {"samplerate": MHZ}, "x: holds no samples"),
        (bytes(5), "binary:numchannels=9", {"samplerate": MHZ},
         r"x: byte 4: .*partial sample \(1 of 2 bytes\)"),
        (bytes(4), "binary", {}, "x: raw binary data states no sample rate.*--samplerate"),
    ],
)  # fmt: skip
def test_refusals(data: bytes, spec: str, kwargs: dict[str, Fraction], match: str) -> None:
    with pytest.raises(CaptureError, match=match) as info:
        read_binary(io.BytesIO(data), spec, name="x", **kwargs)  # type: ignore[arg-type]
    assert "\n" not in str(info.value)


def test_untimed_for_info() -> None:
    cap = read_binary(io.BytesIO(bytes([0, 1, 1, 0])), "binary:numchannels=1", require_time=False)
    assert not cap.time_known and cap.channels[0].edges.tolist() == [1, 3]


def test_channel_names_and_too_many() -> None:
    data = io.BytesIO(bytes(4))
    cap = read_binary(data, "binary:numchannels=3", samplerate=MHZ, channel_names=["STEP", "DIR"])
    assert [c.name for c in cap.channels] == ["STEP", "DIR", "2"]
    with pytest.raises(UsageError, match="3 channel names given for 2 channels"):
        read_binary(io.BytesIO(bytes(4)), "binary:numchannels=2", samplerate=MHZ,
                    channel_names=["a", "b", "c"])  # fmt: skip


def test_open_capture_reads_binary_natively(tmp_path: Path) -> None:
    path = tmp_path / "x.bin"
    path.write_bytes(bytes([0, 1, 3, 2, 0]))
    cap = open_capture(path, input_format="binary:numchannels=2", samplerate=MHZ)
    assert cap.format == "binary" and cap.path == str(path)
    assert [c.edges.tolist() for c in cap.channels] == [[1, 3], [2, 4]]


# -- against sigrok-cli, and the pipeline of issue 14 ------------------------------------------------
def _need_sigrok() -> None:
    if find_sigrok_cli() is None:
        if os.environ.get("CI") == "true":
            pytest.fail("sigrok-cli missing in CI")
        pytest.skip("sigrok-cli not installed")


@pytest.mark.sigrok
def test_same_channels_as_sigrok_cli_reads(tmp_path: Path) -> None:
    """sigrok-cli's own ``-I binary`` (converted to .sr) gives the same names, levels and edges."""
    _need_sigrok()
    rng = np.random.default_rng(3)
    raw = np.bitwise_xor.accumulate((rng.random(4000) < 0.05) * rng.integers(0, 512, 4000))
    data = raw.astype("<u2").tobytes()
    path = tmp_path / "x.bin"
    path.write_bytes(data)
    ours = open_capture(path, input_format="binary:numchannels=9", samplerate=MHZ)
    theirs = read_with_sigrok(path, "binary:numchannels=9", samplerate=MHZ)
    assert ours.end == theirs.end == 4000
    for a, b in zip(ours.channels, theirs.channels, strict=True):
        assert (a.name, a.initial, a.edges.tolist()) == (b.name, b.initial, b.edges.tolist())


def _pipeline(sr: Path, args: list[str]) -> tuple[int, dict[str, object]]:
    """``sigrok-cli -i SR -O binary | wavecheck check - ARGS --format json``."""
    exe = find_sigrok_cli()
    assert exe is not None
    src = subprocess.Popen([exe, "-i", str(sr), "-O", "binary"], stdout=subprocess.PIPE)
    assert src.stdout is not None
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "wavecheck", "check", "-", *args, "--format", "json"],
            stdin=src.stdout,
            capture_output=True,
            timeout=300,
            cwd=REPO,
            check=False,
        )
    finally:
        src.stdout.close()
        src.wait(timeout=60)
    assert src.returncode == 0
    assert proc.stdout, proc.stderr.decode()
    return proc.returncode, json.loads(proc.stdout)


def _direct(sr: Path, args: list[str]) -> tuple[int, dict[str, object]]:
    proc = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(sr), *args, "--format", "json"],
        capture_output=True, timeout=300, cwd=REPO, check=False,
    )  # fmt: skip
    return proc.returncode, json.loads(proc.stdout)


def _same_but_source(a: dict[str, object], b: dict[str, object]) -> None:
    """Equal reports but for where the capture came from (path, format, the .sr's notes)."""
    ca, cb = a.pop("capture"), b.pop("capture")
    assert isinstance(ca, dict) and isinstance(cb, dict)
    assert ca.pop("path") == "<stdin>" and ca.pop("format") == "binary"
    cb.pop("path"), cb.pop("format")
    cb["notes"] = [n for n in cb.get("notes", []) if "logic channels were disabled" not in n]
    assert ca == cb
    assert a == b


@pytest.mark.sigrok
@pytest.mark.parametrize(
    ("capture", "pipe_args", "args"),
    [
        ("grbl_sr", ["--input-format", "binary:numchannels=4", "--samplerate", "2MHz",
                     "--channels", "EN,STEP (Y axis),TX,RX"],
         ["--drive", "gecko-g202", "--map", "step=STEP (Y axis),enable=EN"]),
        ("smoothie_sr", ["--input-format", "binary:numchannels=8", "--samplerate", "12MHz"],
         ["--drive", "gecko-g202", "--map", "x.step=5,x.dir=6,y.step=3,y.dir=4"]),
    ],
)  # fmt: skip
def test_sigrok_binary_pipe_gives_the_files_result(
    request: pytest.FixtureRequest, capture: str, pipe_args: list[str], args: list[str]
) -> None:
    """Issue 14: ``sigrok-cli -i X.sr -O binary | wavecheck check - --input-format
    binary:numchannels=N --samplerate R …`` gives exactly ``wavecheck check X.sr …``'s result."""
    _need_sigrok()
    sr: Path = request.getfixturevalue(capture)
    rc_pipe, piped = _pipeline(sr, [*pipe_args, *args])
    rc_file, direct = _direct(sr, args)
    assert rc_pipe == rc_file
    _same_but_source(piped, direct)


@pytest.mark.sigrok
def test_readme_pipe_block(grbl_sr: Path, tmp_path: Path) -> None:
    """The README's "From a pipe" block, run by a shell as written (the grbl capture beside it),
    gives the verdict and rule table of checking the ``.sr`` itself."""
    import shutil

    _need_sigrok()
    block = marked("pipe")
    (tmp_path / "captures" / "real").mkdir(parents=True)
    (tmp_path / "captures" / "real" / "grbl_cnc_1.sr").symlink_to(grbl_sr)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    assert shutil.which("wavecheck", path=env["PATH"]) is not None
    piped = subprocess.run(["bash", "-o", "pipefail", "-c", block], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=300, check=False)  # fmt: skip
    direct = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(grbl_sr), "--drive", "gecko-g202",
         "--map", "step=STEP (Y axis)"], capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert piped.returncode == direct.returncode, piped.stderr

    def table(out: str) -> list[str]:
        return [
            ln for ln in out.splitlines() if ln.startswith(("verdict:", "step_", "dir_", "steps:"))
        ]

    assert table(piped.stdout) == table(direct.stdout) and table(piped.stdout)


# -- SampleBlocks: samples arriving in pieces (wavecheck watch) ------------------------------------
@settings(max_examples=60)
@given(
    numchannels=st.integers(1, 20),
    nsamples=st.integers(1, 300),
    cuts=st.lists(st.integers(0, 10**6), max_size=12),
    seed=st.integers(0, 2**32 - 1),
)
def test_sample_blocks_give_the_edges_of_the_whole_data_at_any_split(
    numchannels: int, nsamples: int, cuts: list[int], seed: int
) -> None:
    """Bytes cut anywhere (inside a sample too) give, block by block, the edges a plain numpy
    count finds in the whole data; the unwanted channels are only counted."""
    from wavecheck.capture.binary import SampleBlocks

    unitsize = (numchannels + 7) // 8
    rng = np.random.default_rng(seed)
    raw = rng.integers(0, 256, nsamples * unitsize, dtype=np.uint8)
    raw[rng.random(len(raw)) < 0.8] = 0
    raw = np.bitwise_xor.accumulate(raw.reshape(-1, unitsize), axis=0).ravel().astype(np.uint8)
    data = raw.tobytes()
    scanner = SampleBlocks("x", numchannels, MHZ)
    scanner.want(range(0, numchannels, 2))
    got: dict[int, list[int]] = {}
    at = sorted({c % (len(data) + 1) for c in cuts} | {0, len(data)})
    ends = []
    for a, b in zip(at, at[1:], strict=False):
        block = scanner.scan(data[a:b])
        ends.append(block.end)
        for ch, e in block.edges.items():
            got.setdefault(ch, []).extend(e.tolist())
    assert ends == sorted(ends) and scanner.nsamples == nsamples and scanner.partial == 0
    cap = scanner.capture()
    for bit in range(numchannels):
        want = _edges(raw, unitsize, bit)
        assert got.get(bit, []) == (want if bit % 2 == 0 else [])
        assert cap.channels[bit].edge_count == len(want)
        assert cap.channels[bit].initial == (raw[bit // 8] >> (bit % 8)) & 1


def test_sample_blocks_keep_a_partial_sample_until_it_completes() -> None:
    from wavecheck.capture.binary import SampleBlocks

    scanner = SampleBlocks("x", 12, MHZ)  # two bytes per sample
    assert scanner.scan(b"\x00\x00\x01").end == 1 and scanner.partial == 1
    block = scanner.scan(b"\x00")
    assert block.end == 2 and scanner.partial == 0 and block.edges[0].tolist() == [1]
