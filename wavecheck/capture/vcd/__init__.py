"""VCD: the header (:mod:`.header`), the fast reader (:mod:`.reader`), the simple reference
reader the tests compare it with (:mod:`.reference`) and the one writer (:mod:`.writer`)."""

from wavecheck.capture.vcd.header import VarDecl, VcdHeader, parse_header
from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES, read_vcd
from wavecheck.capture.vcd.reference import read_vcd_reference
from wavecheck.capture.vcd.writer import VcdVector, VcdWire, write_vcd

__all__ = [
    "DEFAULT_CHUNK_BYTES",
    "VarDecl",
    "VcdHeader",
    "VcdVector",
    "VcdWire",
    "parse_header",
    "read_vcd",
    "read_vcd_reference",
    "write_vcd",
]
