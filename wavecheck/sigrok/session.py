"""PulseView session files with the ``wavecheck`` decoder stacked: ``wavecheck check --pulseview``.

``pulseview -s FILE.pvs -i CAPTURE`` opens the capture with the decoder already on it, one
decode signal per axis, its channels assigned and its options set as ``check`` ran. The file is
the setup PulseView 0.4.2 writes and reads (``-s``; File → Save/Restore session setup): a Qt
``QSettings`` INI file with ``[General] decode_signals=N`` and a ``[decode_signalI]`` group per
decode signal — ``decoders``, ``decoder0\\id``, ``decoder0\\options`` and
``decoder0\\optionK\\{name,type,value}`` (the value a serialised GLib ``GVariant``: a string is
its UTF-8 bytes and a NUL, type ``s``), ``channels`` and ``channelK\\{name,initial_pin_state,
assigned_signal_name}`` with K the decoder's channel index (required, then optional channels).
Signals are named as PulseView names them: a ``.sr`` channel by its name, a VCD variable by its
reference name (libsigrok's VCD input drops the scopes).
"""

from __future__ import annotations

import argparse
import string
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from wavecheck.engine import Report

__all__ = [
    "Stacked",
    "pvs_text",
    "stacked_from_report",
    "write_pulseview",
]

#: libsigrokdecode's SRD_INITIAL_PIN_SAME_AS_SAMPLE0: a channel's level before sample 0.
_SAME_AS_SAMPLE0 = 2
#: The decode signal's colour (ARGB): the green PulseView gives its first decoder, on which the
#: decoder's annotation classes are coloured (a violation red; ``pd.py``'s ANNOTATIONS).
_GREEN = 0xFF32AA32
#: Formats PulseView 0.4.2 opens itself (``-I`` for the others is not offered).
_OPENED = {"sr": [], "vcd": ["-I", "vcd"]}


@dataclass(frozen=True)
class Stacked:
    """One PulseView decode signal: the decoder's channels and options."""

    name: str
    channels: Mapping[str, str]
    """Decoder channel id (``step``, ``dir``, …) → PulseView signal name."""
    options: Mapping[str, str]
    """Decoder option id → value (every option of the decoder is a string)."""


def _escaped(text: str) -> str:
    """A QSettings INI string value: quoted, ``\\`` and ``"`` escaped, other characters outside
    printable ASCII as ``\\xHHHH`` (a hex digit after such an escape is escaped too, as Qt does:
    its reader takes every hex digit that follows ``\\x``)."""
    out = ['"']
    after_hex = False
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
            after_hex = False
        elif not " " <= ch <= "~" or (after_hex and ch in string.hexdigits):
            data = ch.encode("utf-16-be")
            out += [f"\\x{unit:x}" for (unit,) in struct.iter_unpack(">H", data)]
            after_hex = True
        else:
            out.append(ch)
            after_hex = False
    out.append('"')
    return "".join(out)


def _gvariant_string(text: str) -> str:
    """A GVariant ``s`` serialised (UTF-8, then NUL) as a QSettings ``@ByteArray``: every byte
    as ``\\xHH`` (a byte array is read with the same hex escapes)."""
    return "@ByteArray(" + "".join(f"\\x{b:02x}" for b in text.encode() + b"\0") + ")"


def pvs_text(stacked: Sequence[Stacked], decoder_channels: Sequence[str]) -> str:
    """The session file for ``stacked`` decode signals; ``decoder_channels`` lists the decoder's
    channel ids in PulseView's order (required, then optional)."""
    lines = ["[General]", f"decode_signals={len(stacked)}", ""]
    for i, s in enumerate(stacked):
        lines += [f"[decode_signal{i}]", f"name={_escaped(s.name)}", "enabled=true"]
        lines.append(f"color={_GREEN}")
        lines += ["decoders=1", "decoder0\\id=wavecheck", "decoder0\\visible=true"]
        opts = [(k, v) for k, v in s.options.items() if v != ""]
        lines.append(f"decoder0\\options={len(opts)}")
        for k, (key, value) in enumerate(opts):
            lines += [
                f"decoder0\\option{k}\\name={key}",
                f"decoder0\\option{k}\\type=s",
                f"decoder0\\option{k}\\value={_gvariant_string(value)}",
            ]
        lines.append(f"channels={len(decoder_channels)}")
        for k, ch in enumerate(decoder_channels):
            lines += [
                f"channel{k}\\name={ch}",
                f"channel{k}\\initial_pin_state={_SAME_AS_SAMPLE0}",
            ]
            if ch in s.channels:
                lines.append(f"channel{k}\\assigned_signal_name={_escaped(s.channels[ch])}")
        lines.append("")
    return "\n".join(lines)


def _signal_name(report: Report, channel: str) -> str:
    """The name PulseView gives capture channel ``channel``."""
    if report.capture.format == "vcd":
        return channel.rsplit(".", 1)[-1]
    return channel


def _drive_option(report: Report) -> str:
    """The drive's id when the library resolves it to the same file, else its path."""
    from wavecheck.drives.library import load_drive
    from wavecheck.errors import WavecheckError

    drive = report.drive
    try:
        same = load_drive(drive.id).path.resolve() == drive.path.resolve()
    except (WavecheckError, OSError):
        same = False
    return drive.id if same else str(drive.path.resolve())


def _resolution(report: Report, args: argparse.Namespace) -> str:
    """The ``resolution`` option: empty when ``check`` used one sample (the decoder's default),
    else what it used (``0`` for exact edges: a simulator's VCD, a ``.sr`` stepgen wrote)."""
    given = getattr(args, "resolution", None)
    if given:
        return str(given)
    ns = report.resolution_ns
    if ns == report.capture.timebase.tick_ns:
        return ""
    if ns == 0:
        return "0"
    return f"{ns.numerator}ns" if ns.denominator == 1 else f"{float(ns)!r}ns"


def stacked_from_report(report: Report, args: argparse.Namespace, ids: Sequence[str]) -> Stacked:
    """The decoder as ``check`` ran for one axis of ``report`` (``ids``: the decoder's channel
    ids in order)."""
    from wavecheck.sigrok.adapter import CHANNEL_ROLES

    st = report.step_type
    roles = CHANNEL_ROLES[st.kind]
    channels = {
        ids[roles.index(role)]: _signal_name(report, sig.channel)
        for role, sig in report.interface.signals.items()
        if role in roles
    }
    options = {
        "drive": _drive_option(report),
        "type": str(st.number),
        "user_table": "+".join(map(str, st.states)) if st.number == 15 else "",
        "active_edge": report.active_edge,
        "invert": " ".join(report.inverted),
        "dir_forward": "high" if report.forward_level else "low",
        "pulse_level": getattr(args, "pulse_level", None) or "high",
        "limit": " ".join(getattr(args, "limit", None) or []),
        "margin": getattr(args, "margin", None) or "",
        "resolution": _resolution(report, args),
    }
    name = "wavecheck" if report.axis is None else f"wavecheck {report.axis}"
    return Stacked(name, channels, options)


def write_pulseview(args: argparse.Namespace, reports: Sequence[Report]) -> list[str]:
    """Write ``args.pulseview`` for ``reports`` (the axes of one capture); returns the command
    that opens it, and a note when the decoder is not installed where libsigrokdecode looks.

    Raises:
        UsageError: a capture PulseView cannot open itself (convert it to .sr first).
    """
    from wavecheck.errors import UsageError
    from wavecheck.output import atomic_write
    from wavecheck.sigrok.decoder.pd import CHANNELS, OPTIONAL_CHANNELS
    from wavecheck.sigrok.install import DECODER_ID, searched_dirs

    capture = reports[0].capture
    fmt = capture.format
    if fmt not in _OPENED:
        raise UsageError(
            f"--pulseview: PulseView opens .sr and VCD files, not {fmt}: convert "
            f"{capture.path} to .sr first (sigrok-cli -I FORMAT -i FILE -o capture.sr)"
        )
    ids = [c["id"] for c in (*CHANNELS, *OPTIONAL_CHANNELS)]
    atomic_write(
        args.pulseview, pvs_text([stacked_from_report(r, args, ids) for r in reports], ids)
    )
    import shlex

    cmd = ["pulseview", "-s", args.pulseview, *_OPENED[fmt], "-i", capture.path]
    notes = [f"PulseView session {args.pulseview}: {shlex.join(cmd)}"]
    if not any((d / DECODER_ID / "pd.py").is_file() for d in searched_dirs()):
        notes.append("the wavecheck decoder is not installed yet: wavecheck sigrok install")
    return notes
