"""``wavecheck simulate klipper``: build Klipper (or take its ELF and dictionary), run klippy's batch
mode on the job, feed the MCU's messages to the simulated MCU as its move queue makes room, record
the steppers' pins, check them like a capture."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wavecheck.cli._check_flow import run_check
from wavecheck.cli._simulate_args import seconds, source
from wavecheck.errors import UsageError

__all__ = ["run_klipper"]


def _read(path: str, option: str) -> bytes:
    try:
        return Path(path).read_bytes()
    except OSError as err:
        raise UsageError(f"{path}: cannot read it ({option}): {err.strerror}") from None


def run_klipper(args: argparse.Namespace) -> int:
    """Build, batch, simulate, record, check; returns ``check``'s exit code."""
    from wavecheck.mcu import klipper
    from wavecheck.mcu.build import build_klippy, build_runner
    from wavecheck.mcu.klipper_msg import Dictionary
    from wavecheck.mcu.run import check_elf

    if args.config is None:
        raise UsageError("simulate klipper needs --config printer.cfg (klippy's configuration)")
    for name in ("gcode", "config", "kconfig", "elf", "dict"):
        path = getattr(args, name)
        if path is not None and not Path(path).is_file():
            raise UsageError(f"{path}: no such file (--{name})")
    if bool(args.elf) != bool(args.dict):
        raise UsageError("--elf and --dict go together: the ELF and the klipper.dict of its build")
    if args.elf and args.kconfig:
        raise UsageError("--kconfig builds Klipper; --elf runs a build as it is: give one")
    max_s = seconds(args.max_time, "--max-time")
    tail_s = seconds(args.tail, "--tail")
    wall_s = seconds(args.timeout, "--timeout")
    config, gcode = Path(args.config), Path(args.gcode)
    steppers = klipper.steppers(config)
    axes = {s.name.lower(): s for s in steppers}
    if not args.map and (not args.axes or set(args.axes.lower()) - set(axes)):
        raise UsageError(
            f"--axes {args.axes}: {config} has the steppers {', '.join(sorted(axes))} (e.g. --axes x)"
        )

    runner = build_runner(source(args, "simavr_src"))
    src = None if args.elf else source(args, "klipper_src")
    if args.elf:
        elf, dict_path = Path(args.elf), Path(args.dict)
    else:
        assert src is not None
        kconfig = _read(args.kconfig, "--kconfig") if args.kconfig else None
        elf, dict_path = klipper.build(src, kconfig)
    dictionary = Dictionary.load(dict_path)
    mcu, _ = klipper.mcu_of(dictionary, dict_path)
    check_elf(elf, mcu)
    host = build_klippy(src or source(args, "klipper_src"), sys.executable)
    serial = klipper.batch(host, config, gcode, dict_path, float(wall_s), dictionary)
    sent = klipper.job(serial, dictionary, f"{gcode} (klippy's batch output)")
    limits = (float(max_s), float(tail_s), float(wall_s))
    signals = klipper.pins(steppers)
    done = klipper.run(
        runner,
        elf,
        dictionary,
        sent,
        args.vcd,
        signals,
        limits,
        lambda r: klipper.outcome(r, dictionary),
    )
    steps = sum(sent.steps.values())
    print(
        f"simulate klipper: {mcu}, {len(sent.blocks)} message blocks, {steps} steps commanded; "
        f"the MCU has {klipper.outcome(done, dictionary)} move-queue slots (klippy's batch mode "
        f"assumes {klipper.BATCH_MOVE_SLOTS})",
        file=sys.stderr,
    )
    args.capture = [args.vcd]
    if not args.map:
        chosen = [axes[a] for a in dict.fromkeys(args.axes.lower())]
        maps = [
            f"{s.name.lower()}.step={s.name}_STEP,{s.name.lower()}.dir={s.name}_DIR" for s in chosen
        ]
        if len(chosen) == 1:
            maps = [f"step={chosen[0].name}_STEP,dir={chosen[0].name}_DIR"]
        if chosen[0].enable:
            maps.append(f"enable={chosen[0].name}_ENABLE")
            if chosen[0].enable_active_low and not args.invert:
                args.invert = ["enable"]
        args.map = maps
    return run_check(args)
