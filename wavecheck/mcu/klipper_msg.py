"""Klipper's serial protocol as data: message blocks, their integers, and the data dictionary.

Facts from Klipper's source (Klipper3d/klipper 84104bb), written anew here:
- a block is ``LEN SEQ PAYLOAD CRC_HI CRC_LO 0x7E``, 5 to 64 bytes (``src/command.c:283-297``,
  ``klippy/msgproto.py:13-22``); SEQ is ``0x10 | n`` with n the block's number modulo 16
  (``src/command.c:287,301-305``); the MCU answers a block it took with an empty block carrying
  the next number, and one out of sequence with an empty block carrying the number it still
  expects (``command.c:301-303,330-331,363-372``);
- the CRC is CRC-16/CCITT reflected with initial value 0xFFFF and no final XOR (the catalogue's
  CRC-16/MCRF4XX), high byte first (``command.c:293-296``);
- each integer, the message id included, is a variable-length quantity of 7-bit groups, most
  significant first, each byte but the last with bit 7 set; the first byte's bits 5-6 both set
  mean a negative number (``klippy/msgproto.py:40-58``); a ``%*s``/``%.*s``/``%s`` argument is a
  length byte and the bytes;
- the data dictionary (``out/klipper.dict``, JSON) maps each command and response format to its
  id, each enumeration (``pin``: ``"PA0": [0, 8]`` is PA0..PA7 → 0..7) to its values, and holds
  the build's constants (``config``: ``CLOCK_FREQ``, ``MCU``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from crc import Calculator, Configuration

from wavecheck.errors import UsageError

__all__ = [
    "BLOCK_MAX",
    "Dictionary",
    "Message",
    "block_crc",
    "decode_block",
    "pack",
    "renumber",
    "split_blocks",
    "vlq",
]

BLOCK_MIN = 5
BLOCK_MAX = 64
SYNC = 0x7E
_CRC = Calculator(
    Configuration(
        width=16,
        polynomial=0x1021,
        init_value=0xFFFF,
        final_xor_value=0,
        reverse_input=True,
        reverse_output=True,
    )
)


def block_crc(head_and_payload: bytes) -> bytes:
    """The two CRC bytes of a block (high byte first)."""
    return _CRC.checksum(head_and_payload).to_bytes(2, "big")


def split_blocks(data: bytes, where: str) -> list[bytes]:
    """The blocks of a serial stream (klippy's batch output), each checked.

    Raises:
        UsageError: a block that is cut short, too long, or whose CRC or trailer is wrong.
    """
    out, pos = [], 0
    while pos < len(data):
        n = data[pos]
        block = data[pos : pos + n]
        if n < BLOCK_MIN or n > BLOCK_MAX or len(block) < n or block[-1] != SYNC:
            raise UsageError(
                f"{where}: byte {pos}: not a Klipper message block (length byte {n}, "
                f"{len(data) - pos} bytes left): not klippy's batch output"
            )
        if block_crc(block[:-3]) != block[-3:-1]:
            raise UsageError(f"{where}: byte {pos}: the block's CRC is wrong")
        out.append(block)
        pos += n
    return out


def renumber(block: bytes, number: int) -> bytes:
    """The block with sequence ``number`` (mod 16) and its CRC made anew."""
    head = bytes([block[0], 0x10 | (number & 0x0F)]) + block[2:-3]
    return head + block_crc(head) + bytes([SYNC])


def _vlq(data: bytes, pos: int) -> tuple[int, int]:
    c = data[pos]
    value = c & 0x7F
    if c & 0x60 == 0x60:
        value -= 0x80
    while c & 0x80:
        pos += 1
        c = data[pos]
        value = (value << 7) | (c & 0x7F)
    return value, pos + 1


def vlq(value: int) -> bytes:
    """An integer as the protocol sends it: k groups carry -2**(7k-2) .. 3*2**(7k-2)-1."""
    k = 1
    while not -(1 << (7 * k - 2)) <= value < 3 << (7 * k - 2):
        k += 1
    return bytes(((value >> (7 * i)) & 0x7F) | (0x80 if i else 0) for i in reversed(range(k)))


@dataclass(frozen=True)
class Message:
    """A command or response: its name, its arguments (integers, or bytes for strings) and the
    bytes it is sent as."""

    name: str
    args: dict[str, int | bytes]
    raw: bytes


@dataclass(frozen=True)
class Dictionary:
    """A Klipper build's data dictionary: message formats by id, enumerations, constants."""

    formats: dict[int, str]
    enumerations: dict[str, dict[str, int]]
    constants: dict[str, str | int]
    version: str

    @classmethod
    def load(cls, path: Path) -> Dictionary:
        """Read ``klipper.dict``.

        Raises:
            UsageError: not readable, not JSON, or without commands.
        """
        try:
            data = json.loads(path.read_bytes())
            formats = {int(i): f for f, i in {**data["commands"], **data["responses"]}.items()}
            enums: dict[str, dict[str, int]] = {}
            for name, values in data.get("enumerations", {}).items():
                flat: dict[str, int] = {}
                for key, value in values.items():
                    if isinstance(value, list):  # a range: "PA0": [0, 8] is PA0..PA7
                        stem = key.rstrip("0123456789")
                        first = int(key[len(stem) :])
                        for k in range(value[1]):
                            flat[f"{stem}{first + k}"] = value[0] + k
                    else:
                        flat[key] = int(value)
                enums[name] = flat
            return cls(formats, enums, dict(data.get("config", {})), str(data.get("version")))
        except OSError as err:
            raise UsageError(f"{path}: cannot read the data dictionary: {err.strerror}") from None
        except (ValueError, KeyError, TypeError, AttributeError) as err:
            raise UsageError(
                f"{path}: not a Klipper data dictionary (out/klipper.dict of the build): {err}"
            ) from None

    def id_of(self, name: str) -> int:
        """The id of the message whose format starts with ``name``."""
        for ident, fmt in self.formats.items():
            if fmt.split(" ", 1)[0] == name:
                return ident
        raise KeyError(name)

    def encode_id(self, name: str) -> bytes:
        """The bytes a message's id is sent as (the start of its payload)."""
        return vlq(self.id_of(name))

    def names(self, enumeration: str) -> dict[int, str]:
        """Value → name of an enumeration (``pin``, ``static_string_id``)."""
        return {v: k for k, v in self.enumerations.get(enumeration, {}).items()}


def decode_block(block: bytes, d: Dictionary) -> list[Message]:
    """The messages of one block.

    Raises:
        ValueError: an id the dictionary lacks or a payload cut short.
    """
    payload, pos, out = block[2:-3], 0, []
    while pos < len(payload):
        start = pos
        ident, pos = _vlq(payload, pos)
        fmt = d.formats.get(ident)
        if fmt is None:
            raise ValueError(f"message id {ident} is not in the data dictionary")
        name, *params = fmt.split(" ")
        args: dict[str, int | bytes] = {}
        for param in params:
            key, _, kind = param.partition("=")
            if kind.endswith("s"):
                n = payload[pos]
                args[key] = bytes(payload[pos + 1 : pos + 1 + n])
                pos += 1 + n
            else:
                args[key], pos = _vlq(payload, pos)
        if pos > len(payload):
            raise ValueError(f"{name}: the block ends inside its arguments")
        out.append(Message(name, args, bytes(payload[start:pos])))
    return out


def pack(commands: list[bytes]) -> list[bytes]:
    """Commands (their bytes, in order) in as few blocks as fit, numbered from 0: each block
    takes the next commands while its payload stays within 59 bytes (64 - 5)."""
    payloads: list[bytes] = []
    for cmd in commands:
        if payloads and len(payloads[-1]) + len(cmd) <= BLOCK_MAX - BLOCK_MIN:
            payloads[-1] += cmd
        else:
            payloads.append(cmd)
    return [
        renumber(bytes([len(p) + BLOCK_MIN, 0]) + p + bytes(3), k) for k, p in enumerate(payloads)
    ]
