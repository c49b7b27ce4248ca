"""LinuxCNC's software stepgen: the INI (``[EMCMOT] BASE_PERIOD``) and its HAL files, read by
:mod:`wavecheck.linuxcnc.config`; the n·P − J arithmetic of :mod:`wavecheck.linuxcnc.timing`.

stepgen rounds each parameter up to whole base periods ``P``, and any base-thread run may be up to
``J`` (the worst latency) late, so an interval of ``n`` periods is only ``n·P − J`` on the wire:
that is the guarantee (``stepgen plan``'s latency-aware answer; ``J`` = 0 when not given, with a
note). Across a reversal the space between pulses is only dirhold + dirsetup periods; LinuxCNC's
dirhold counts from the end of the pulse, so the hold from the leading edge is steplen + dirhold.
"""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._linuxcnc_files import files_of
from wavecheck.firmware._text import read_text
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role
from wavecheck.linuxcnc.config import LinuxCNCConfig, read_config
from wavecheck.linuxcnc.timing import periods_needed, step_rate_hz

__all__ = ["looks_like", "read"]

_MAX_CHANNELS = 16


def looks_like(text: str) -> bool:
    """A LinuxCNC INI (``[EMCMOT]``) or a HAL file with software stepgen."""
    return bool(
        re.search(r"^\s*\[EMCMOT\]", text, re.M)
        or re.search(r"^\s*loadrt\s+stepgen\b|\bstepgen\.\d+\.", text, re.M)
    )


def read(path: str | os.PathLike[str], latency_ns: Fraction | None = None) -> FirmwareConfig:
    """Read every software stepgen channel of a LinuxCNC configuration (an INI or a HAL file)."""
    text = read_text(path)
    ini, hals, notes = files_of(path, text)
    ini_path = path if ini is not None else None
    configs: list[LinuxCNCConfig] = []
    for channel in range(_MAX_CHANNELS):
        try:
            cfg = read_config(ini_path, [str(h) for h in hals], channel)
        except ConfigError as err:
            if configs and "is not loaded" in str(err):
                break
            raise
        configs.append(cfg)
        if not cfg.stepgen_loaded:
            break
    j = Fraction(latency_ns) if latency_ns is not None else Fraction(0)
    axes = tuple(_axis(cfg, j) for cfg in configs)
    jnote = (
        f"every interval is n x BASE_PERIOD - J with J = {float(j):g} ns"
        if latency_ns is not None
        else "J = 0 assumed (give --latency for the latency-aware figures, as stepgen plan does)"
    )
    ignored = tuple(i for cfg in configs for i in cfg.ignored)
    return FirmwareConfig(
        firmware="linuxcnc",
        path=str(path),
        axes=axes,
        files=(str(path), *map(str, hals)),
        unsupported=tuple(dict.fromkeys(ignored)),
        notes=(jnote, *notes),
        fixer=_fixer(j),
    )


def _axis(cfg: LinuxCNCConfig, j: Fraction) -> GeneratorGuarantee:
    p = cfg.require_base_period()
    n = cfg.periods()
    src = cfg.sources

    def fig(names: tuple[str, ...], setting: str, note: str = "") -> Guaranteed:
        periods = sum(n[x] for x in names)
        value = max(periods * p - j, Fraction(0))
        at = src.get(names[-1], "stepgen default (1 ns = one period)")
        return Guaranteed(
            value,
            setting,
            at,
            "ns",
            "derived",
            f"{periods} x {p} ns - J" + (f"; {note}" if note else ""),
        )

    same = n["stepspace"]
    reversal = n["dirhold"] + n["dirsetup"]
    idle = (
        fig(("stepspace",), "stepspace")
        if same <= reversal
        else fig(("dirhold", "dirsetup"), "dirhold + dirsetup", "across a reversal")
    )
    info = {
        "base period": f"{p} ns ({src.get('BASE_PERIOD', '')})",
        **{k: f"{v} base periods" for k, v in n.items()},
    }
    notes: tuple[str, ...] = ()
    if cfg.step_type not in (None, 0):
        notes = (f"step_type {cfg.step_type}: only step/dir (0) is modelled here",)
    return GeneratorGuarantee(
        axis=f"stepgen.{cfg.channel}",
        pulse=fig(("steplen",), "steplen"),
        idle=idle,
        dir_setup=fig(("dirsetup",), "dirsetup"),
        dir_hold=fig(
            ("steplen", "dirhold"), "steplen + dirhold", "dirhold counts from the end of the pulse"
        ),
        max_rate=Guaranteed(
            step_rate_hz(p, n["steplen"] + n["stepspace"]),
            "1 / ((steplen + stepspace) x P)",
            src.get("stepspace", src.get("BASE_PERIOD", "")),
            "ns",
            "derived",
            "stepgen's own clamp",
        ),
        dir_hold_trailing=fig(("dirhold",), "dirhold"),
        info=info,
        notes=notes,
    )


def _fixer(j: Fraction):  # type: ignore[no-untyped-def]
    def fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
        p = int(axis.info.get("base period", "0 ns").split(" ")[0])
        name = {
            "pulse": "steplen",
            "idle": "stepspace",
            "dir_setup": "dirsetup",
            "dir_hold": "dirhold",
        }.get(role)
        if name is None or p <= 0:
            return f"lower the joint's MAX_VELOCITY so that {axis.axis} steps at most {float(need):.6g} steps/s"
        if role == "dir_hold":
            need -= int(axis.info.get("steplen", "0").split(" ")[0]) * p
        periods = periods_needed(max(need, Fraction(0)), j, p)
        return f"set {axis.axis}.{name} to at least {periods * p} ns ({periods} base periods of {p} ns at J = {float(j):g} ns)"

    return fix
