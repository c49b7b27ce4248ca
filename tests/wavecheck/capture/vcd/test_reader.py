"""VCD reader: semantics, the shared corpus, fast path = simple path, and bad input."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import shared_capture, write_vcd
from wavecheck.capture.edges import Capture
from wavecheck.capture.vcd import read_vcd, read_vcd_reference
from wavecheck.capture.vcd.reader import _timestamps_swar, _token_bounds
from wavecheck.errors import CaptureError, UsageError

CORPUS = [
    "sigrok-dumps/spi/spiflash_read16/chronovu_la8/chronovu_la8_spiflash_read16.vcd",
    "sigrok-dumps/misc/vcd/real-analog.vcd",
    "sigrok-dumps/misc/vcd/vectors-integers.vcd",
]


def assert_same(a: Capture, b: Capture) -> None:
    assert (a.start, a.end, a.timebase, a.resolution_ticks) == (
        b.start,
        b.end,
        b.timebase,
        b.resolution_ticks,
    )
    assert [c.name for c in a.channels] == [c.name for c in b.channels]
    for ca, cb in zip(a.channels, b.channels, strict=True):
        assert (ca.initial, ca.known_from) == (cb.initial, cb.known_from), ca.name
        np.testing.assert_array_equal(ca.edges, cb.edges, err_msg=ca.name)
        np.testing.assert_array_equal(ca.xz_times, cb.xz_times, err_msg=ca.name)
        assert ca.edges.dtype == np.int64
        assert np.all(np.diff(ca.edges) > 0)


def write(tmp_path: Path, text: str, name: str = "t.vcd") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


HEAD = '$timescale 1 ns $end\n$scope module top $end\n$var wire 1 ! a $end\n$var wire 1 " b $end\n$upscope $end\n$enddefinitions $end\n'


@pytest.mark.parametrize("relpath", CORPUS)
@pytest.mark.parametrize("chunk", [4 << 20, 97, 8, 3])
def test_corpus_fast_equals_simple(relpath: str, chunk: int) -> None:
    path = shared_capture(relpath)
    assert_same(read_vcd(path, chunk_bytes=chunk), read_vcd_reference(path))


def test_chronovu_channels_and_edges() -> None:
    cap = read_vcd(shared_capture(CORPUS[0]))
    assert [c.name for c in cap.channels] == [f"Channel_{i}" for i in range(8)]
    assert cap.timebase.tick_ns == 10
    # written by the ChronoVu LA-8 software: timestamps are samples, one 10 ns tick (issue 12:
    # it was read as exact, resolution 0)
    assert cap.samplerate_hz is None and cap.resolution_ticks == 1
    assert any("ChronoVu" in n and "logic analyzer" in n for n in cap.notes)
    # count the toggles of Channel_3 (id "3") with a plain text scan, independent of both readers
    level, edges = None, 0
    for line in shared_capture(CORPUS[0]).read_text().split("$enddefinitions $end")[1].split():
        if line.endswith("3") and line[0] in "01" and len(line) == 2:
            if level is not None and line[0] != level:
                edges += 1
            level = line[0]
    assert len(cap.channel("Channel_3").edges) == edges > 0


def test_sigrok_comment_gives_samplerate_and_reals_are_skipped() -> None:
    cap = read_vcd(shared_capture(CORPUS[1]))
    assert cap.samplerate_hz == 200_000
    assert cap.resolution_ticks == 5  # 5 us at a 1 us timescale
    assert [c.name for c in cap.channels] == [f"D{i}" for i in range(8)]
    assert cap.skipped["A0"] == "a real"
    with pytest.raises(UsageError, match="'A0' is a real"):
        cap.channel("A0")


def test_vectors_skipped_and_findable() -> None:
    cap = read_vcd(shared_capture(CORPUS[2]))
    assert {c.name for c in cap.channels} == {"bit_i", "clk_i", "rst_i"}
    assert any("skipped" in n for n in cap.notes)
    with pytest.raises(UsageError, match="is a 6-bit vector"):
        cap.channel("period_count")
    with pytest.raises(UsageError, match="32-bit integer"):
        cap.channel("tb_uwam_psf2.i[31:0]")


@pytest.mark.parametrize(
    ("body", "a_init", "a_edges", "b_edges"),
    [
        ('#0 0! 0"\n#5 1!\n#5 0!\n#7 1!\n#9\n', 0, [7], []),  # zero-width glitch: last wins
        ('#0 0! 0"\n#5 1! 1!\n#6 1!\n#8 0!\n#9\n', 0, [5, 8], []),  # same-value changes
        ('#0 0! 0"\n#3 1!\n#3 1"\n#3 0"\n#4\n', 0, [3], []),  # repeated timestamp lines
        ('$dumpvars 1! 0" $end\n#2 0!\n#4 1"\n', 1, [2], [4]),  # values before the first #
        ('#0 1! 0"\n$comment b 0! #1 $end\n#2 0!\n', 1, [2], []),  # body comment
        ('#0 0! 0"\n#1 b1 !\n#2 b0 !\n', 0, [1, 2], []),  # 'b' value of a 1-bit wire
        ('#0 0! 0"\n#1 1!\r\n#2 0!\r\n', 0, [1, 2], []),  # CRLF
        ('#0 0! 0"\n#1 H!\n#2 L!\n', 0, [1, 2], []),  # 9-state strengths
    ],
)
@pytest.mark.parametrize("chunk", [1 << 20, 5, 2])
def test_semantics_table(
    tmp_path: Path, body: str, a_init: int, a_edges: list[int], b_edges: list[int], chunk: int
) -> None:
    path = write(tmp_path, HEAD + body)
    for cap in (read_vcd(path, chunk_bytes=chunk), read_vcd_reference(path)):
        a, b = cap.channel("a"), cap.channel("b")
        assert a.initial == a_init
        assert a.edges.tolist() == a_edges
        assert b.edges.tolist() == b_edges


def test_xz_values_are_reported(tmp_path: Path) -> None:
    path = write(tmp_path, HEAD + '#0 x! z"\n#4 1!\n#6 x!\n#7 z!\n#8 0!\n#9 0"\n#10\n')
    for cap in (read_vcd(path, chunk_bytes=3), read_vcd_reference(path)):
        a, b = cap.channel("a"), cap.channel("b")
        assert (a.known_from, a.initial, a.edges.tolist(), a.xz_times.tolist()) == (4, 1, [8], [6])
        assert (b.known_from, b.initial, b.edges.tolist(), b.xz_times.tolist()) == (9, 0, [], [])


@pytest.mark.parametrize(
    ("timescale", "tick"),
    [
        ("1 fs", Fraction(1, 10**15)),
        ("10ps", Fraction(1, 10**11)),
        ("100 s", Fraction(100)),
        ("1 us", Fraction(1, 10**6)),
        ("1\n ms", Fraction(1, 1000)),
    ],
)
def test_timescales(tmp_path: Path, timescale: str, tick: Fraction) -> None:
    path = write_vcd(tmp_path / "t.vcd", {"STEP": (0, [10, 20])}, timescale="1 s")
    # the writer only writes the canonical "1 s" form: the spellings under test are put in by hand
    text = path.read_text().replace("$timescale 1 s $end", f"$timescale {timescale} $end")
    assert timescale in text
    path.write_text(text)
    cap = read_vcd(path)
    assert cap.timebase.tick_s == tick
    assert cap.channel("STEP").edges.tolist() == [10, 20]


def test_scopes_collide_use_full_names(tmp_path: Path) -> None:
    text = (
        "$timescale 1 ns $end\n$scope module top $end\n$scope module x $end\n$var wire 1 ! step $end\n"
        '$upscope $end\n$scope module y $end\n$var wire 1 " step $end\n$var wire 1 # dir $end\n'
        '$upscope $end\n$upscope $end\n$enddefinitions $end\n#0 0! 0" 0#\n#5 1"\n#6\n'
    )
    cap = read_vcd(write(tmp_path, text))
    assert [c.name for c in cap.channels] == ["top.x.step", "top.y.step", "dir"]
    assert cap.channel("top.y.step").edges.tolist() == [5]


def test_multichar_ids(tmp_path: Path) -> None:
    names = {f"s{i}": (i % 2, [10 + i, 200 + i]) for i in range(120)}  # ids run past one byte
    ids = [chr(33 + (i % 94)) + ("" if i < 94 else chr(33 + i // 94)) for i in range(120)]
    lines = ["$timescale 1 ns $end", "$scope module top $end"]
    lines += [f"$var wire 1 {ids[i]} s{i} $end" for i in range(120)]
    lines += ["$upscope $end", "$enddefinitions $end", "#0"]
    lines += [f"{names[f's{i}'][0]}{ids[i]}" for i in range(120)]
    for t in range(10, 330):
        ev = [f"#{t}"] + [
            f"{(i % 2) ^ 1 if t < 200 + i else i % 2}{ids[i]}"
            for i in range(120)
            if t in (10 + i, 200 + i)
        ]
        if len(ev) > 1:
            lines += ev
    lines.append("#400")
    path = write(tmp_path, "\n".join(lines) + "\n")
    for chunk in (1 << 20, 11):
        cap = read_vcd(path, chunk_bytes=chunk)
        for i in (0, 93, 94, 119):
            ch = cap.channel(f"s{i}")
            assert (ch.initial, ch.edges.tolist()) == (i % 2, [10 + i, 200 + i])
        assert_same(cap, read_vcd_reference(path))


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "empty"),
        ("hello world\n", "unexpected 'hello' in the header"),
        (HEAD.replace("1 ns", "1 xs"), r"line 1: bad \$timescale"),
        (HEAD.replace("1 ns", "ns"), "bad \\$timescale"),
        (HEAD.replace("1 ns", "1000 s"), "outside"),
        (HEAD[:70], "cut off in its header|without \\$end"),
        (HEAD + '#0 0! 0"\n#100 1!\n#50 0!\n', r"line 9 .*time goes backwards: #50 after #100"),
        (HEAD + '#0 0! 0"\n0?\n', "line 8 .*unknown id code"),
        (HEAD + '#0 0! 0"\ngarbage line\n', "line 8 .*unexpected 'garbage'"),
        (HEAD + '#0 0! 0"\nhello\n', "line 8 .*unknown id code in 'hello'"),
        (HEAD + '#0 0! 0"\n#10 1', "without an id code"),
        (HEAD + '#0 0! 0"\n#10 1!\n' + "\0" * 4096, "NUL"),
        (HEAD + '#0 0! 0"\n#1x\n', "bad timestamp"),
        (HEAD + '#0 0! 0"\n#-5\n', "bad timestamp"),
        (HEAD, "no timestamps"),
        (HEAD + '#0 0! 0"\n$comment never closed\n', "without \\$end"),
        (HEAD + '#0 0! 0"\n$var wire 1 % c $end\n', "unexpected '\\$var'"),
    ],
)
@pytest.mark.parametrize("chunk", [1 << 20, 4])
def test_bad_input_is_one_line_capture_error(
    tmp_path: Path, text: str, match: str, chunk: int
) -> None:
    path = write(tmp_path, text)
    with pytest.raises(CaptureError, match=match) as info:
        read_vcd(path, chunk_bytes=chunk)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(CaptureError, match="no such file"):
        read_vcd(tmp_path / "nope.vcd")
    with pytest.raises(CaptureError, match="folder"):
        read_vcd(tmp_path)


def test_user_resolution_and_samplerate(tmp_path: Path) -> None:
    path = write_vcd(tmp_path / "t.vcd", {"STEP": (0, [10, 20])}, timescale="1 ns")
    assert read_vcd(path, samplerate=Fraction(8_000_000)).resolution_ticks == 125
    cap = read_vcd(path, samplerate=Fraction(3_000_000))
    # timestamps rounded to 1 ns add up to one tick to an interval: 333.3 ns + 1 → 335
    assert cap.resolution_ticks == 335 and any("rounded" in n for n in cap.notes)
    assert read_vcd(path, resolution_s=Fraction(1, 10**6)).resolution_ticks == 1000


@st.composite
def _waveforms(draw: st.DrawFn) -> tuple[dict[str, tuple[int, list[int]]], bool, int]:
    n = draw(st.integers(1, 4))
    sigs = {}
    for i in range(n):
        times = draw(st.lists(st.integers(1, 300), max_size=25, unique=True))
        sigs[f"s{i}"] = (draw(st.integers(0, 1)), sorted(times))
    return sigs, draw(st.booleans()), draw(st.integers(1, 40))


def _write_layout(path: Path, sigs: dict[str, tuple[int, list[int]]], sigrok: bool) -> Path:
    """Simulator layout (one change per line) or sigrok's (changes on the #t line), with a
    redundant same-value change and a zero-width glitch thrown in at some timestamps."""
    ids = {n: chr(33 + i) for i, n in enumerate(sigs)}
    ev: dict[int, list[str]] = {0: [f"{init}{ids[n]}" for n, (init, _) in sigs.items()]}
    for n, (init, edges) in sigs.items():
        level = init
        for k, t in enumerate(edges):
            level ^= 1
            extra = [f"{level ^ 1}{ids[n]}"] if k % 3 == 1 else []  # glitch: last value wins
            ev.setdefault(t, []).extend([*extra, f"{level}{ids[n]}"])
            if k % 4 == 2:
                ev[t].append(f"{level}{ids[n]}")  # same value again: no edge
    lines = ["$timescale 1 ns $end", "$scope module top $end"]
    lines += [f"$var wire 1 {ids[n]} {n} $end" for n in sigs]
    lines += ["$upscope $end", "$enddefinitions $end"]
    for t in sorted(ev):
        lines += [f"#{t} " + " ".join(ev[t])] if sigrok else [f"#{t}", *ev[t]]
    lines.append("#400")
    path.write_text("\n".join(lines) + "\n")
    return path


@settings(max_examples=50, deadline=None)
@given(case=_waveforms())
def test_random_waveforms_fast_equals_truth_and_simple(
    tmp_path_factory: pytest.TempPathFactory,
    case: tuple[dict[str, tuple[int, list[int]]], bool, int],
) -> None:
    sigs, sigrok, chunk = case
    path = _write_layout(tmp_path_factory.mktemp("v") / "r.vcd", sigs, sigrok)
    fast = read_vcd(path, chunk_bytes=chunk)
    for name, (init, edges) in sigs.items():
        ch = fast.channel(name)
        assert (ch.initial, ch.edges.tolist()) == (init, edges)
    assert_same(fast, read_vcd_reference(path))


_IDS = ["!", '"', "#", "b", "ab", "%%", "zz9", "$x", "#1", "bb"]


@st.composite
def _adversarial_vcd(draw: st.DrawFn) -> str:
    """Layouts that stress the fast tokenizer: ids that look like timestamps, keywords or vector
    markers, multi-character ids, $dumpvars/$dumpoff/$dumpon/$dumpall blocks and $comment in
    the body, x/z, 'b' values of 1-bit wires, a vector, CRLF/tab/space separators, changes
    before the first timestamp and a last line without a newline."""
    ids = draw(st.lists(st.sampled_from(_IDS), min_size=1, max_size=4, unique=True))
    vec = draw(st.sampled_from(["v", "bv", None]))
    head = ["$timescale", draw(st.sampled_from(["1ns", "10 ps", "1\n fs", "100 s"])), "$end"]
    head += ["$scope module top $end", *[f"$var wire 1 {c} s{i} $end" for i, c in enumerate(ids)]]
    head += [f"$var wire 4 {vec} vv $end"] if vec else []
    head += ["$upscope $end", "$enddefinitions $end"]
    scalar = st.tuples(st.sampled_from("0101xzXZhl"), st.sampled_from(ids)).map("".join)
    block = st.tuples(
        st.sampled_from(["$dumpvars", "$dumpon", "$dumpoff", "$dumpall"]),
        st.lists(scalar, max_size=4),
    ).map(lambda kv: [kv[0], *kv[1], "$end"])
    token = st.one_of(
        st.integers(0, 3).map(lambda d: [("#", d)]),
        scalar.map(lambda s: [s]),
        st.tuples(st.sampled_from(["b0", "b1", "bx", "b01", "bz"]), st.sampled_from(ids)).map(list),
        st.sampled_from(["hi", "#5 1!", "b1 !", ""]).map(lambda c: ["$comment", c, "$end"]),
        block,
        *([st.text("01xz", min_size=4, max_size=4).map(lambda b: ["b" + b, vec])] if vec else []),
    )
    t, body = 0, []
    for group in draw(st.lists(token, max_size=30)):
        for tok in group:
            if isinstance(tok, tuple):
                t += (0, 1, 5, 123456)[tok[1]]
                tok = f"#{t}"
            body.append(tok + draw(st.sampled_from([" ", "\n", "\r\n", "\t", "  "])))
    body.append(f"#{t + 1}" + draw(st.sampled_from(["", "\n"])))
    return "\n".join(head) + "\n" + "".join(body)


@settings(max_examples=200, deadline=None)
@given(text=_adversarial_vcd(), chunk=st.sampled_from([1, 2, 3, 5, 8, 64]))
def test_adversarial_layouts_fast_equals_simple(
    tmp_path_factory: pytest.TempPathFactory, text: str, chunk: int
) -> None:
    path = tmp_path_factory.mktemp("v") / "a.vcd"
    path.write_bytes(text.encode())
    assert_same(read_vcd(path, chunk_bytes=chunk), read_vcd_reference(path))


def test_aliased_id_is_found_by_every_name(tmp_path: Path) -> None:
    """Two declarations with one id code are one signal: mapping either name must find it."""
    text = (
        "$timescale 1 ns $end\n$scope module tb $end\n$var wire 1 ! step_out $end\n"
        "$scope module dut $end\n$var wire 1 ! STEP $end\n$upscope $end\n$upscope $end\n"
        "$enddefinitions $end\n#0 0!\n#5 1!\n#9\n"
    )
    cap = read_vcd(write(tmp_path, text))
    assert [c.name for c in cap.channels] == ["step_out"]
    for ref in ("step_out", "STEP", "tb.dut.STEP"):
        assert cap.channel(ref).edges.tolist() == [5]


# --- issue 12: hostile and unusual input -------------------------------------------------------


@pytest.mark.parametrize("end", [9_000_000_000_000_000_000, (1 << 63) - 1, 10**18])
def test_19_digit_timestamps_are_read(tmp_path: Path, end: int) -> None:
    """A valid timestamp below 2^63 is a time like any other (it was "bad timestamp")."""
    path = write(tmp_path, HEAD + f'#0\n0!\n1"\n#5\n1!\n#{end}\n')
    for chunk in (1 << 20, 7):
        cap = read_vcd(path, chunk_bytes=chunk)
        assert cap.end == end and cap.channel("a").edges.tolist() == [5]
    assert_same(read_vcd(path), read_vcd_reference(path))


@pytest.mark.parametrize(
    ("stamp", "match"),
    [
        (str(1 << 63), r"larger than 2\^63−1 \(9223372036854775807\)"),
        ("9" * 21, "has 21 digits; times up to 2\\^63−1 ticks"),
        ("12a4", "not a whole number"),
    ],
)
def test_too_large_timestamp_says_why(tmp_path: Path, stamp: str, match: str) -> None:
    path = write(tmp_path, HEAD + f"#0\n0!\n#{stamp}\n")
    with pytest.raises(CaptureError, match=match) as exc:
        read_vcd(path)
    assert "line 9 (byte 127)" in str(exc.value)


def test_body_without_whitespace_is_refused_within_bounded_memory(tmp_path: Path) -> None:
    """64 MiB of NUL bytes after the header (a sparse file): refused at the token cap with the
    byte offset, holding at most about two caps (it was read whole: 2 GB took 8.2 GB)."""
    import tracemalloc

    from wavecheck.capture.vcd.reader import MAX_TOKEN_BYTES

    path = tmp_path / "sparse.vcd"
    head = (HEAD + "#0\n0!\n").encode()
    with open(path, "wb") as f:
        f.write(head)
        f.truncate(len(head) + (64 << 20))
    tracemalloc.start()
    try:
        with pytest.raises(CaptureError, match=f"byte {len(head)}\\).*longer than") as exc:
            read_vcd(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert "\n" not in str(exc.value)
    assert peak < 3 * MAX_TOKEN_BYTES, f"peak {peak / 2**20:.0f} MiB"


def test_long_tokens_below_the_cap_are_fine(tmp_path: Path) -> None:
    """A wide vector value longer than a chunk is still read (skipped as a vector)."""
    head = HEAD.replace("$upscope", "$var wire 5000 # v $end\n$upscope")
    path = write(tmp_path, head + "#0\n0!\nb" + "1" * 5000 + " #\n#10\n1!\n#20\n")
    cap = read_vcd(path, chunk_bytes=64, max_token_bytes=8000)
    assert cap.channel("a").edges.tolist() == [10]
    with pytest.raises(CaptureError, match="longer than 4000 bytes"):
        read_vcd(path, chunk_bytes=64, max_token_bytes=4000)


def test_utf8_names_are_decoded(tmp_path: Path) -> None:
    """Names are UTF-8 (as sigrok-cli writes ``STÉP``); a name that is not UTF-8 is read as
    latin-1 with a note, not dropped. (pyvcd's tokenizer, under the reference reader, takes
    ASCII names only, so there is no fast = simple comparison here.)"""
    text = HEAD.replace(" a $end", " STÉP $end").replace("module top", "module tôp")
    path = tmp_path / "u.vcd"
    path.write_bytes((text + "#0\n0!\n#5\n1!\n#9\n").encode("utf-8"))
    cap = read_vcd(path)
    assert cap.channel("STÉP").edges.tolist() == [5]
    assert not any("latin-1" in n for n in cap.notes)
    path.write_bytes((HEAD.replace(" a $end", " caf\xe9 $end") + "#0\n#9\n").encode("latin-1"))
    cap = read_vcd(path)
    assert cap.channel("caf\xe9").name == "café"
    assert any("not valid UTF-8" in n and "café" in n for n in cap.notes), cap.notes


def test_header_parsing_is_linear(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The old parser recounted lines from the start for each ``$var`` (quadratic: 200,000 of
    them took ~7 min). Work counted (tests/bounds.py): the line counter scans each byte of the
    header at most once, and 10× the ``$var`` lines run about 10× the lines of Python."""
    from tests.bounds import lines_run
    from tests.reliability.corpus import vcd_many_vars
    from wavecheck.capture.vcd import header

    scanned = 0
    count_lines = header._Lines.at

    def at(self: header._Lines, offset: int) -> int:
        nonlocal scanned
        scanned += offset - self.pos if offset >= self.pos else offset
        return count_lines(self, offset)

    monkeypatch.setattr(header._Lines, "at", at)
    small, big = vcd_many_vars(1_000), vcd_many_vars(10_000)
    _, work_small = lines_run(lambda: header.parse_header(tmp_path, small))
    scanned_small, scanned = scanned, 0
    parsed, work_big = lines_run(lambda: header.parse_header(tmp_path, big))
    assert len(parsed.vars) == 10_002
    assert 0 < scanned_small <= len(small) and 0 < scanned <= len(big)
    assert work_big < 15 * work_small, (work_small, work_big)  # quadratic: ~100x


@pytest.mark.parametrize(
    ("head", "res", "says"),
    [
        ("$version ChronoVu LA-8 Version 4.00 $end", 1, "ChronoVu"),
        ("$version Saleae Logic 1.2.18 $end", 1, "Saleae"),
        ("$version DSView v1.3.1 $end", 1, "DSView"),
        ("$version libsigrok 0.5.2 $end", 1, "sigrok"),
        ("$comment exported from my logic analyser $end", 1, "a logic analyzer"),
        # a stated rate wins: 1 MHz on a 1 ns timescale is 1000 ticks
        ("$version Saleae Logic $end $comment sample rate: 1 MHz $end", 1000, "1 MHz"),
        ("$comment Acquisition with 2/2 channels at 1 MHz $end", 1000, "1 MHz"),
        ("$comment samplerate=250kHz $end", 4000, "250kHz"),
        # simulators stay exact
        ("$version Icarus Verilog $end", 0, None),
        ("$version GHDL v0 $end", 0, None),
        ("$version Generated by VerilatedVcd $end", 0, None),
        ("$comment a clock at 50 MHz drives the design $end", 0, None),
        ("", 0, None),
    ],
)
def test_analyzer_vcds_get_a_resolution(
    tmp_path: Path, head: str, res: int, says: str | None
) -> None:
    """A VCD from a logic analyzer's software (by its $version/$comment) or stating a sample rate
    is not exact: one tick, or the stated period; a simulator's VCD stays exact (0)."""
    path = write(tmp_path, head + "\n" + HEAD + "#0\n0!\n#5000\n1!\n#9000\n")
    cap = read_vcd(path)
    assert cap.resolution_ticks == res
    if says is None:
        assert not any("logic analyzer" in n or "sample rate" in n for n in cap.notes), cap.notes
    else:
        assert any(says in n for n in cap.notes), cap.notes
    assert_same(cap, read_vcd_reference(path))


# The fast reader's own shortcuts, each against the simple way of doing the same thing:
# whitespace tokens (two comparisons per byte), timestamps decoded 8 digits at a time in a uint64
# (SWAR), change times counted instead of searched when a chunk holds only timestamps and
# changes, and line numbers counted only when an error is raised.


@settings(max_examples=300, deadline=None)
@given(
    data=st.binary(max_size=200)
    | st.text(" \t\n\r\x0b\x0c\x00\x1f#01!ab", max_size=60).map(str.encode)
)
def test_token_bounds_equal_bytes_split(data: bytes) -> None:
    starts, ends = _token_bounds(np.frombuffer(data, dtype=np.uint8))
    assert [data[a:b] for a, b in zip(starts.tolist(), ends.tolist(), strict=True)] == data.split()


@settings(max_examples=300, deadline=None)
@given(
    numbers=st.lists(
        st.text("0123456789", min_size=1, max_size=16)
        | st.text("0123456789#x/:\x00\xff", min_size=1, max_size=16),
        min_size=1,
        max_size=20,
    ),
    lead=st.integers(0, 20),
)
def test_swar_timestamps_equal_int(numbers: list[str], lead: int) -> None:
    """Digits anywhere in a buffer (also its first bytes) read as int() reads them; any other
    character makes the whole batch fall back (None) to the column-by-column path."""
    text = ("x" * lead + " " if lead else "") + " ".join("#" + n for n in numbers)
    a = np.frombuffer(text.encode("latin-1"), dtype=np.uint8)
    starts, ends = _token_bounds(a)
    starts, ends = starts[-len(numbers) :], ends[-len(numbers) :]
    got = _timestamps_swar(a, ends, ends - starts - 1)
    if all(n.isdigit() for n in numbers):
        assert got is not None and got.tolist() == [int(n) for n in numbers]
    else:
        assert got is None


@st.composite
def _stamped_vcd(draw: st.DrawFn) -> tuple[str, int]:
    """Timestamps of 1 … 19 digits (leading zeros too), the simulator's or sigrok's layout, now
    and then a $dumpvars block or a vector change (the chunk then takes the searching path)."""
    t = draw(st.integers(0, 9))
    lines = ["#0", "0!", '1"']
    level = 0
    for _ in range(draw(st.integers(0, 40))):
        t += draw(st.sampled_from([0, 1, 7, 99_999_999, 12_345_678_901, 10**15, 10**17]))
        if t >= 1 << 63:
            break
        stamp = "#" + "0" * draw(st.integers(0, 2)) + str(t) if len(str(t)) < 17 else f"#{t}"
        level ^= 1
        extra = draw(st.sampled_from(["", "", '0"', "$dumpvars 1! $end", "b101 v"]))
        change = [f"{level}!", *([extra] if extra else [])]
        if draw(st.booleans()):
            lines.append(" ".join([stamp[:20], *change]))
        else:
            lines += [stamp[:20], *change]
    head = HEAD.replace("$upscope", "$var wire 3 v vec $end\n$upscope")
    return head + "\n".join(lines) + "\n", draw(st.sampled_from([3, 16, 61, 1 << 20]))


@settings(max_examples=150, deadline=None)
@given(case=_stamped_vcd())
def test_timestamps_of_every_length_fast_equals_simple(
    tmp_path_factory: pytest.TempPathFactory, case: tuple[str, int]
) -> None:
    text, chunk = case
    path = tmp_path_factory.mktemp("v") / "t.vcd"
    path.write_text(text)
    assert_same(read_vcd(path, chunk_bytes=chunk), read_vcd_reference(path))


@pytest.mark.parametrize("chunk", [5, 64, 4096, 1 << 20])
@pytest.mark.parametrize("piped", [False, True])
@pytest.mark.parametrize(("bad", "what"), [("#12x", "bad timestamp"), ("0?", "unknown id code")])
def test_error_line_counted_when_raised(
    tmp_path: Path, chunk: int, piped: bool, bad: str, what: str
) -> None:
    """The line of an error far into the body is exact whether the newlines before it are
    counted when it is raised (a file) or as the chunks go by (a stream)."""
    body = "".join(f"#{t}\n{t & 1}!\n" for t in range(1, 700))
    path = write(tmp_path, HEAD + '#0 0! 0"\n' + body + bad + "\n")
    line = HEAD.count("\n") + 2 + 2 * 699
    with pytest.raises(CaptureError, match=rf"line {line} .*{what}"):
        if piped:
            with path.open("rb") as fh:
                read_vcd(path, chunk_bytes=chunk, source=fh)
        else:
            read_vcd(path, chunk_bytes=chunk)
