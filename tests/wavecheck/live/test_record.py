"""``watch --save``'s recorder (issue 27): a complete ``.sr`` on disk at every checkpoint, so a
crash loses at most the samples since the last one; an existing file is replaced only at the
end, whole; nothing of ours is left by a discarded recording."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import pytest

from wavecheck.capture.srzip import sr_metadata
from wavecheck.live import record
from wavecheck.live.record import SrRecorder

META = sr_metadata(["A", "B", "C", "D", "E", "F", "G", "H", "I"], samplerate=1_000_000)


def _samples(path: Path) -> bytes:
    """The logic bytes of an .sr as zipfile reads it (the disk's file as it is)."""
    with zipfile.ZipFile(io.BytesIO(path.read_bytes())) as z:
        assert z.testzip() is None
        assert z.read("version") == b"2" and z.read("metadata").decode() == META
        names = sorted((n for n in z.namelist() if n.startswith("logic-1-")),
                       key=lambda n: int(n.rsplit("-", 1)[1]))  # fmt: skip
        return b"".join(z.read(n) for n in names)


def test_every_checkpoint_leaves_a_complete_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A checkpoint after each piece: after every one the file on disk (as a kill would leave
    it) is a complete zip of every whole sample so far; pieces split samples (unit 2 bytes)."""
    monkeypatch.setattr(record, "CHECKPOINT_SECONDS", 0.0)
    target = tmp_path / "kept.sr"
    rec = SrRecorder(target, META, unitsize=2)
    assert _samples(target) == b""  # complete from the start
    stream = bytes(range(256)) * 40
    sent = 0
    for size in (1, 3, 250, 999, 2, 4001, 5, 4979):
        rec.add(stream[sent : sent + size])
        sent += size
        whole = sent - sent % 2
        assert _samples(target) == stream[:whole]
    assert rec.close() == target and _samples(target) == stream[: sent - sent % 2]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.sr"]


def test_an_existing_file_is_replaced_only_at_the_end(tmp_path: Path) -> None:
    target = tmp_path / "kept.sr"
    target.write_bytes(b"someone's earlier capture")
    target.chmod(0o640)
    rec = SrRecorder(target, META, unitsize=2)
    assert rec.path == tmp_path / "kept.recording.sr" and rec.replaces == target
    rec.add(b"\x01\x00" * 100)
    assert target.read_bytes() == b"someone's earlier capture"
    assert rec.close() == target
    assert _samples(target) == b"\x01\x00" * 100 and (target.stat().st_mode & 0o777) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.sr"]
    # a discarded recording leaves the existing file as it was, and nothing of its own
    rec = SrRecorder(target, META, unitsize=2)
    rec.add(b"\x02\x00" * 10)
    rec.discard()
    assert _samples(target) == b"\x01\x00" * 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.sr"]


def test_a_discarded_new_recording_leaves_nothing(tmp_path: Path) -> None:
    rec = SrRecorder(tmp_path / "new.sr", META, unitsize=2)
    rec.add(b"\x00\x01" * 10)
    rec.discard()
    assert list(tmp_path.iterdir()) == []


def test_member_size_is_bounded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(record, "MAX_MEMBER_BYTES", 64)
    rec = SrRecorder(tmp_path / "k.sr", META, unitsize=2)
    for _ in range(10):
        rec.add(bytes(40))
    rec.close()
    with zipfile.ZipFile(tmp_path / "k.sr") as z:
        sizes = [i.file_size for i in z.infolist() if i.filename.startswith("logic-1-")]
    assert sum(sizes) == 400 and max(sizes) <= 64 + 40


def test_what_arrived_reads_back_edge_for_edge(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import numpy as np

    from wavecheck.capture.sr import read_sr

    monkeypatch.setattr(record, "MAX_MEMBER_BYTES", 4096)
    rng = np.random.default_rng(5)
    raw = np.bitwise_xor.accumulate((rng.random(10_000) < 0.05).astype(np.uint8) * 0x05)
    target = tmp_path / "live.sr"
    rec = SrRecorder(target, sr_metadata(["STEP", "DIR", "EN"], samplerate=1000000), 1)
    data = raw.tobytes()
    for a in range(0, len(data), 777):
        rec.add(data[a : a + 777])
    rec.close()
    members = [n for n in zipfile.ZipFile(target).namelist() if n.startswith("logic-1-")]
    assert len(members) == 3  # two of 4,662 bytes (whole pieces past 4096), the rest
    got = read_sr(target)
    bit0 = (raw & 1).astype(np.int8)
    assert got.end == 10_000
    assert got.channels[0].edges.tolist() == (np.flatnonzero(np.diff(bit0)) + 1).tolist()


def test_a_fast_stream_to_dev_null_records_without_error() -> None:
    """Issue 34: ``watch --save /dev/null`` ended in ``struct.error: argument out of range``:
    zipfile seeked back on /dev/null, whose position is always 0. A stream is never seeked."""
    rec = SrRecorder("/dev/null", META, unitsize=2)
    piece = bytes(range(256)) * 4096
    for _ in range(64):  # 64 MiB, members of several MiB
        rec.add(piece)
        rec._end_member()  # noqa: SLF001 - a member boundary, as a checkpoint makes
    rec.close()
    assert rec.bytes == 64 * len(piece)


_SCRIPT = """
import sys
from wavecheck.capture.srzip import sr_metadata
from wavecheck.live.record import SrRecorder
print("report line before", flush=True)
rec = SrRecorder("/dev/stdout", sr_metadata(["A"], samplerate=1000), unitsize=1)
rec.add(bytes([0, 1, 1, 0]) * 1000)
rec.close()
"""


def test_dev_stdout_is_written_at_its_offset(tmp_path: Path) -> None:
    """Issue 34: ``--save /dev/stdout > rec.sr`` reopened /dev/stdout at offset 0, over what
    standard output held. The zip now follows it in the same open stream, and reads back."""
    import subprocess
    import sys

    out = tmp_path / "rec.bin"
    with open(out, "wb") as f:
        subprocess.run([sys.executable, "-c", _SCRIPT], stdout=f, check=True)
    data = out.read_bytes()
    head = b"report line before\n"
    assert data.startswith(head)
    with zipfile.ZipFile(io.BytesIO(data[len(head) :])) as z:
        assert z.testzip() is None and z.read("logic-1-1") == bytes([0, 1, 1, 0]) * 1000
