"""Which firmware axis made which capture axis (``check --firmware``, ``measure --firmware``).

A capture axis is paired with the firmware axis the user names (``--firmware-axis y=beta``), else
with the firmware axis of the same name or alias (``y`` ↔ Klipper's ``stepper_y``, a LinuxCNC
joint's letter ↔ its ``stepgen.N``), else — for the one unnamed axis of a single-axis run —
``--axis NAME``, the configuration's only axis, or its first axis. The pairing and how it was
made are stated in every report; a named capture axis without a match is refused (one line
naming the axes and the option to give), never compared with another axis's settings.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from wavecheck.errors import UsageError
from wavecheck.firmware.guarantee import FirmwareConfig, GeneratorGuarantee

__all__ = ["Pairing", "pair_axis", "parse_pairs"]


@dataclass(frozen=True)
class Pairing:
    """A capture axis, the firmware axis it is compared with, and how they were paired."""

    capture_axis: str | None
    axis: GeneratorGuarantee
    how: str

    def __str__(self) -> str:
        cap = "the capture" if self.capture_axis is None else f"capture axis {self.capture_axis}"
        return f"{cap} ↔ firmware axis {self.axis.axis} ({self.how})"


def parse_pairs(texts: Sequence[str]) -> dict[str, str]:
    """``--firmware-axis CAPTURE=FIRMWARE`` options as a mapping (capture names lower-cased)."""
    out: dict[str, str] = {}
    for text in texts:
        cap, sep, fw = text.partition("=")
        if not sep or not cap.strip() or not fw.strip():
            raise UsageError(
                f"--firmware-axis {text!r}: give CAPTURE_AXIS=FIRMWARE_AXIS (e.g. y=beta)"
            )
        out[cap.strip().lower()] = fw.strip()
    return out


def pair_axis(
    cfg: FirmwareConfig,
    capture_axis: str | None,
    explicit: dict[str, str],
    default: str | None = None,
) -> Pairing:
    """The firmware axis of ``capture_axis`` (None: the one unnamed axis of a single-axis run).

    Args:
        cfg: the configuration read.
        capture_axis: the capture axis's name, None when it has none.
        explicit: ``--firmware-axis`` pairs (:func:`parse_pairs`).
        default: ``--axis NAME`` for an unnamed capture axis.

    Raises:
        UsageError: a named firmware axis that does not exist, or a named capture axis with no
            firmware axis of its name (the message lists both and names the option).
    """
    names = ", ".join(cfg.axis_names)
    key = (capture_axis or "").lower()
    if key and key in explicit:
        found = cfg.find(explicit[key])
        if found is None:
            raise UsageError(f"--firmware-axis {capture_axis}={explicit[key]}: no axis "
                             f"{explicit[key]!r} in {cfg.path} (axes: {names})")  # fmt: skip
        return Pairing(capture_axis, found, f"--firmware-axis {capture_axis}={explicit[key]}")
    if capture_axis is not None:
        found = cfg.find(capture_axis)
        if found is None:
            raise UsageError(
                f"capture axis {capture_axis!r} has no firmware axis of that name in {cfg.path} "
                f"(axes: {names}); give --firmware-axis {capture_axis}=NAME"
            )
        how = (
            "same name"
            if found.axis.lower() == key
            else f"{found.axis} is also called {capture_axis}"
        )
        return Pairing(capture_axis, found, how)
    if default:
        found = cfg.find(default)
        if found is None:
            raise UsageError(f"--axis: no axis {default!r} in {cfg.path} (axes: {names})")
        return Pairing(None, found, f"--axis {default}")
    if len(cfg.axes) == 1:
        return Pairing(None, cfg.axes[0], "the configuration's only axis")
    return Pairing(None, cfg.axes[0], f"the first of {names}: the capture's axis has no name; "
                   "give --axis NAME to choose")  # fmt: skip
