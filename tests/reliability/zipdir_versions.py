"""capture/zipdir.py's read_directory against the zipfile of the interpreter that runs this
(standard library only, so any CPython >= 3.11 runs it): random zips zipfile writes (stored or
deflated, streamed with data descriptors, forced ZIP64, extra fields, comments, prepended
bytes, half with ZIP64 end records), 3 in 4 of them damaged; every directory zipdir reads must
equal zipfile's. Prints the counts; exits 1 on any disagreement.

    /root/.pyenv/versions/3.13.0/bin/python tests/reliability/zipdir_versions.py SEED N
"""
# ruff: noqa

import collections
import importlib.util
import io
import random
import struct
import sys
import warnings
import zipfile
from pathlib import Path

spec = importlib.util.spec_from_file_location(
    "zipdir", Path(__file__).resolve().parents[2] / "wavecheck/capture/zipdir.py"
)
zd = importlib.util.module_from_spec(spec)
spec.loader.exec_module(zd)
F = ("filename", "header_offset", "compress_size", "file_size", "CRC", "compress_type", "flag_bits")


class U(io.RawIOBase):
    def __init__(s):
        s.buf = io.BytesIO()

    def writable(s):
        return True

    def write(s, b):
        return s.buf.write(b)


def make(r):
    out = U() if r.random() < 0.5 else io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with zipfile.ZipFile(out, "w") as zf:
            for _ in range(r.randint(0, 5)):
                name = r.choice(
                    ["version", "metadata", "logic-1-1", "é/ü", "a b", "x" * r.randint(1, 9)]
                )
                info = zipfile.ZipInfo(name)
                info.compress_type = r.choice([0, 8])
                p = r.randbytes(r.randint(0, 10))
                info.extra = struct.pack("<HH", 0xCAFE, len(p)) + p
                data = r.randbytes(r.randint(0, 300)) * r.randint(1, 3)
                if r.random() < 0.5:
                    with zf.open(info, "w", force_zip64=r.random() < 0.5) as fh:
                        fh.write(data)
                else:
                    zf.writestr(info, data)
            comment = r.choice([b"", r.randbytes(r.randint(0, 60)), b"PK\x05\x06" * 2])
            zf.comment = comment
    data = (out.buf if isinstance(out, U) else out).getvalue()
    if r.random() < 0.5:
        at = len(data) - 22 - len(comment)
        _, _, _, _, n, size, off, _ = zd._EOCD.unpack_from(data, at)
        data = (
            data[:at]
            + zd._EOCD64.pack(b"PK\x06\x06", 44, 45, 45, 0, 0, n, n, size, off)
            + zd._LOCATOR64.pack(b"PK\x06\x07", 0, at, 1)
            + zd._EOCD.pack(
                b"PK\x05\x06", 0, 0, 0xFFFF, 0xFFFF, 0xFFFFFFFF, 0xFFFFFFFF, len(comment)
            )
            + data[at + 22 :]
        )
    return r.randbytes(r.randint(0, 20)) + data


def damage(r, d):
    d = bytearray(d)
    for _ in range(r.randint(1, 3)):
        if not d:
            break
        at = r.randrange(len(d))
        k = r.random()
        if k < 0.3:
            del d[at:]
        elif k < 0.6:
            d[at] ^= r.randint(1, 255)
        else:
            p = r.randbytes(r.randint(1, 8))
            d[at : at + len(p)] = p
    return bytes(d)


c = collections.Counter()
bad = 0
r = random.Random(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
for i in range(int(sys.argv[2]) if len(sys.argv) > 2 else 3000):
    d = make(r)
    if i % 4:
        d = damage(r, d)
    try:
        with zipfile.ZipFile(io.BytesIO(d)) as zf:
            theirs = ([tuple(getattr(x, f) for f in F) for x in zf.infolist()], zf.start_dir)
    except Exception as e:
        theirs = type(e).__name__
    ours = zd.read_directory(io.BytesIO(d))
    if ours is not None:
        ours = ([tuple(getattr(x, f) for f in F) for x in ours[0]], ours[1])
        if ours != theirs:
            bad += 1
            if bad < 4:
                print(
                    "DIFF",
                    i,
                    theirs if isinstance(theirs, str) else "",
                    ours[0][:2],
                    file=sys.stderr,
                )
    c[(ours is not None, isinstance(theirs, tuple), "clean" if i % 4 == 0 else "damaged")] += 1
print(sys.version.split()[0], dict(c), "disagreements:", bad)
sys.exit(1 if bad else 0)
