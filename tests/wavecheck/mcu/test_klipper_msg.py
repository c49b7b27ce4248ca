"""Klipper's serial protocol as wavecheck reads and writes it (wavecheck/mcu/klipper_msg.py),
held to blocks klippy itself wrote and to the encoding rules of ``klippy/msgproto.py:40-58``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from wavecheck.errors import UsageError
from wavecheck.mcu.klipper_msg import (
    Dictionary,
    block_crc,
    decode_block,
    renumber,
    split_blocks,
    vlq,
)

#: klippy's first two blocks of a batch run (klippy.py -o, this project's 644P build): sequence
#: 1 and 2 (batch mode numbers from 1), "allocate_oids count=11" and "config_endstop oid=0
#: pin=18 pull_up=1" (parsedump.py's reading).
KLIPPY_BLOCKS = bytes.fromhex("0711080bfb5a7e09121a001201276c7e")


@pytest.fixture
def dictionary(tmp_path: Path) -> Dictionary:
    data = {
        "commands": {
            "allocate_oids count=%c": 8,
            "config_endstop oid=%c pin=%c pull_up=%c": 26,
            "get_config": 100,
        },
        "responses": {
            "shutdown clock=%u static_string_id=%hu": -13,
            "is_shutdown static_string_id=%hu": 114,
        },
        "enumerations": {"pin": {"PA0": [0, 8], "PC0": [16, 8]}, "static_string_id": {"Hi": 3}},
        "config": {"MCU": "atmega644p", "CLOCK_FREQ": 16000000},
        "version": "v",
    }
    path = tmp_path / "klipper.dict"
    path.write_text(json.dumps(data))
    return Dictionary.load(path)


def test_the_crc_is_the_one_klippy_wrote():
    blocks = split_blocks(KLIPPY_BLOCKS, "job.serial")
    assert [b[1] for b in blocks] == [0x11, 0x12]
    assert [block_crc(b[:-3]) for b in blocks] == [b[-3:-1] for b in blocks]


def test_renumbering_keeps_the_payload_and_makes_a_valid_crc():
    first = split_blocks(KLIPPY_BLOCKS, "job.serial")[0]
    zero = renumber(first, 0)
    assert zero[1] == 0x10 and zero[2:-3] == first[2:-3] and zero[-1] == 0x7E
    assert split_blocks(zero, "x") == [zero]  # the CRC checks
    assert renumber(first, 17)[1] == 0x11  # the number is 4 bits


def test_blocks_decode_with_the_dictionary(dictionary):
    blocks = split_blocks(KLIPPY_BLOCKS, "job.serial")
    assert [(m.name, m.args) for b in blocks for m in decode_block(b, dictionary)] == [
        ("allocate_oids", {"count": 11}),
        ("config_endstop", {"oid": 0, "pin": 18, "pull_up": 1}),
    ]
    assert dictionary.names("pin")[18] == "PC2"
    assert dictionary.encode_id("shutdown") == bytes([0x73])  # -13: one byte, bits 5-6 set


@pytest.mark.parametrize(
    "data, says",
    [
        (KLIPPY_BLOCKS[:-1], "byte 7: not a Klipper message block"),
        (b"\x03\x10\x7e", "byte 0: not a Klipper message block"),
        (KLIPPY_BLOCKS[:4] + b"\x00" + KLIPPY_BLOCKS[5:], "byte 0: the block's CRC is wrong"),
    ],
)
def test_a_broken_stream_is_refused_with_the_byte(data, says):
    with pytest.raises(UsageError, match=f"job.serial: {says}"):
        split_blocks(data, "job.serial")


def test_a_file_that_is_not_a_dictionary_is_refused(tmp_path):
    path = tmp_path / "klipper.dict"
    path.write_text("[1, 2]")
    with pytest.raises(UsageError, match="not a Klipper data dictionary"):
        Dictionary.load(path)


#: klippy/msgproto.py:40-47's thresholds: the value ranges of 1..5 bytes.
@pytest.mark.parametrize(
    "value, size",
    [(0x5F, 1), (0x60, 2), (-0x20, 1), (-0x21, 2), (0x2FFF, 2), (0x3000, 3), (-0x1000, 2)]
    + [(-0x1001, 3), (0x17FFFF, 3), (0x180000, 4), (0xBFFFFFF, 4), (0xC000000, 5)],
)
def test_integer_sizes(value, size):
    assert len(vlq(value)) == size


@given(st.integers(-(2**31), 2**32 - 1))
def test_integers_round_trip(value):
    payload = bytes([8]) + vlq(value)
    head = bytes([len(payload) + 5, 0x10]) + payload
    block = head + block_crc(head) + b"\x7e"
    (msg,) = decode_block(block, Dictionary({8: "x a=%u"}, {}, {}, "v"))
    assert msg.args == {"a": value}
