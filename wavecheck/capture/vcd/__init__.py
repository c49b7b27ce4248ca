"""VCD: the header (:mod:`.header`), the fast reader (:mod:`.reader`), the simple reference
reader the tests compare it with (:mod:`.reference`) and the one writer (:mod:`.writer`).

The names below are imported from their module on first use (PEP 562): a program that only
writes VCD (``stepgen simulate``) does not load the reader and its header parser at start."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.capture.vcd.header import VarDecl, VcdHeader, parse_header
    from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES, read_vcd
    from wavecheck.capture.vcd.reference import read_vcd_reference
    from wavecheck.capture.vcd.writer import VcdVector, VcdWire, write_vcd

#: public name → the module that defines it
_WHERE = {
    "DEFAULT_CHUNK_BYTES": "reader",
    "VarDecl": "header",
    "VcdHeader": "header",
    "VcdVector": "writer",
    "VcdWire": "writer",
    "parse_header": "header",
    "read_vcd": "reader",
    "read_vcd_reference": "reference",
    "write_vcd": "writer",
}

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


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
