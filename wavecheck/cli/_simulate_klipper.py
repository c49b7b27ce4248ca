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

#: The runner sends nothing before this fraction of a second: Klipper enables its UART's
#: receiver during start-up (src/avr/serial.c, serial_init), and a byte before it is lost.
_START_S = 100


def _read(path: str, option: str) -> bytes:
    try:
        return Path(path).read_bytes()
    except OSError as err:
        raise UsageError(f"{path}: cannot read it ({option}): {err.strerror}") from None


def run_klipper(args: argparse.Namespace) -> int:
    """Build, batch, simulate, record, check; returns ``check``'s exit code."""
    from wavecheck.mcu import klipper, klipper_kconfig
    from wavecheck.mcu.build import build_firmware, build_klippy, build_runner
    from wavecheck.mcu.klipper_msg import Dictionary
    from wavecheck.mcu.run import check_elf, simulate

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
        kconfig = _read(args.kconfig, "--kconfig") if args.kconfig else klipper.DEFAULT_KCONFIG
        replace = {
            ".config": kconfig,
            "lib/kconfiglib/genconfig.py": klipper_kconfig.GENCONFIG,
            "lib/kconfiglib/olddefconfig.py": klipper_kconfig.OLDDEFCONFIG,
        }
        python = f"PYTHON={sys.executable}"
        elf = build_firmware(
            src,
            "src/stepper.c",
            replace,
            [python],
            "out/klipper.elf",
            before=[[python, "olddefconfig"]],
            also=["out/klipper.dict"],
        )
        dict_path = elf.parent / "klipper.dict"
    dictionary = Dictionary.load(dict_path)
    mcu, clock = klipper.mcu_of(dictionary, dict_path)
    check_elf(elf, mcu)
    host = build_klippy(src or source(args, "klipper_src"), sys.executable)
    serial = klipper.batch(host, config, gcode, dict_path)
    sent = klipper.job(serial, dictionary, f"{gcode} (klippy's batch output)")
    pins: dict[str, str] = {}
    for s in steppers:
        pins[f"{s.name}_STEP"] = s.step
        pins[f"{s.name}_DIR"] = s.dir
        if s.enable:
            pins[f"{s.name}_ENABLE"] = s.enable
    options = [f"--blocks={klipper.free_list_address(elf)}", f"--start={clock // _START_S}"]
    options += [f"--until={sent.last_event}"] + [f"--stop={p.hex()}" for p in sent.stop_prefixes]
    simulate(
        runner,
        elf,
        mcu,
        clock,
        args.vcd,
        pins,
        "",
        sent.lines(),
        int(max_s * clock),
        int(tail_s * clock),
        float(wall_s),
        lambda r: klipper.outcome(r, dictionary),
        options,
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
