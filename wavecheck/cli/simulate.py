"""``wavecheck simulate grbl --gcode JOB.nc --vcd OUT.vcd --drive ID`` (and ``simulate klipper
--config printer.cfg --gcode JOB.gcode ...``): run the real firmware on a simulated MCU, record its
STEP/DIR/ENABLE pins, and check them like a capture.

grbl is built from its source (``--grbl-src``, with the user's ``--config-h``) or taken as
an ELF (``--elf``), run on simavr with wavecheck's timing fixes (``wavecheck/mcu/simavr``, a
separate GPL-3.0-or-later program), fed ``--settings`` and the G-code over its UART, and its pins
written to ``--vcd`` with the cycle of every change. Then the VCD is checked by ``check``'s engine
with every option ``check`` has, and against the ``$$`` settings grbl printed back. Klipper is
built from ``--klipper-src`` with the user's ``--kconfig`` (or taken as ``--elf`` and ``--dict``);
klippy turns the G-code into the MCU's messages in batch mode, and the simulated MCU gets them as
its move queue makes room (``wavecheck/mcu/klipper.py``).

Exit codes as ``check``: 0 pass, 1 a rule failed, 3 indeterminate, 2 unusable input (a firmware
without the banner, rejected G-code, an ELF for another MCU, a run over its simulated or wall
time).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

from wavecheck.cli._axis_args import add_axis_arguments, add_engine_arguments
from wavecheck.cli._capture_args import add_capture_arguments
from wavecheck.cli._check_flow import run_check
from wavecheck.cli._firmware_args import add_firmware_arguments
from wavecheck.cli._formats import FORMATS
from wavecheck.cli._pulseview_args import add_pulseview_argument
from wavecheck.cli._reports import add_report_arguments
from wavecheck.cli._simulate_args import seconds as _seconds
from wavecheck.cli._simulate_args import source as _source
from wavecheck.cli._steps_args import add_steps_arguments
from wavecheck.cli._tuning_args import add_tuning_arguments
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.units import parse_frequency

__all__ = ["register", "run"]

#: Options of one firmware only.
_ONLY = {
    "grbl": ("settings", "config_h", "settings_out", "check_settings", "grbl_src"),
    "klipper": ("config", "kconfig", "dict", "klipper_src"),
}


def register(sub: Any) -> None:
    """Add the ``simulate`` subcommand."""
    p = sub.add_parser(
        "simulate",
        description="Run grbl (ATmega328P) or Klipper (ATmega644P/2560) on a simulated MCU "
        "(simavr with exact cycle timing), feed it the job over its UART, record its "
        "STEP/DIR/ENABLE pins to a VCD and check them against a drive like a capture. Exit 0 "
        "pass, 1 a rule failed, 3 indeterminate, 2 unusable input.",
    )
    p.add_argument(
        "firmware_name", metavar="FIRMWARE", choices=["grbl", "klipper"], help="grbl or klipper"
    )
    p.add_argument("--gcode", required=True, metavar="FILE", help="the G-code job")
    p.add_argument(
        "--config", metavar="FILE", help="klipper: the printer.cfg klippy runs the job with"
    )
    p.add_argument(
        "--kconfig",
        metavar="FILE",
        help="klipper: build with this .config (make menuconfig's; default: an ATmega644P at 16 MHz)",
    )
    p.add_argument(
        "--dict",
        metavar="FILE",
        help="klipper: the klipper.dict of the --elf build (out/klipper.dict)",
    )
    p.add_argument(
        "--klipper-src",
        metavar="DIR",
        help="klipper: its source tree (default $WAVECHECK_KLIPPER_SRC, else "
        "../shared/firmware-src/klipper)",
    )
    p.add_argument(
        "--settings", metavar="FILE", help="$N=V lines sent before the job (grbl's $$ format)"
    )
    build = p.add_mutually_exclusive_group()
    build.add_argument(
        "--config-h", metavar="FILE", help="build grbl with this config.h instead of its own"
    )
    build.add_argument(
        "--elf",
        metavar="FILE",
        help="run this ELF as it is (grbl: ATmega328P; klipper: with --dict)",
    )
    p.add_argument(
        "--grbl-src",
        metavar="DIR",
        help="grbl's source tree (default $WAVECHECK_GRBL_SRC, else ../shared/firmware-src/grbl-1.1h)",
    )
    p.add_argument(
        "--simavr-src",
        metavar="DIR",
        help="simavr's source tree (default $WAVECHECK_SIMAVR_SRC, else "
        "../shared/firmware-src/simavr)",
    )
    p.add_argument(
        "--clock",
        default="16MHz",
        help="grbl: the MCU clock (default 16MHz; Klipper's is its build's)",
    )
    p.add_argument(
        "--vcd", required=True, type=output_file, metavar="FILE", help="the pin waveform (VCD)"
    )
    p.add_argument(
        "--settings-out",
        type=output_file,
        metavar="FILE",
        help="also write the $$ dump grbl printed back (its settings as it runs them)",
    )
    p.add_argument(
        "--check-settings",
        action="store_true",
        help="also compare the pins with the $$ dump grbl printed back (as check --firmware "
        "does: the pulse against $0, the rate against $100 x $110 / 60)",
    )
    p.add_argument(
        "--max-time",
        default="60s",
        help="simulated time limit of the run (default 60s); a job not done by then is an error",
    )
    p.add_argument(
        "--timeout", default="600s", help="wall-time limit of the simulation (default 600s)"
    )
    p.add_argument(
        "--tail",
        default="50ms",
        help="simulated time recorded after the last step (default 50ms: grbl's $1 idle delay "
        "then releases ENABLE)",
    )
    p.add_argument(
        "--drive",
        action="append",
        required=True,
        metavar="ID|FILE|AXIS=ID",
        help="drive id from rules/ or a TOML file; AXIS=ID gives one axis its own drive",
    )
    p.add_argument(
        "--axes",
        default="x",
        help="the axes checked when no --map is given (default x; e.g. xyz; klipper: also e)",
    )
    add_axis_arguments(p)
    add_tuning_arguments(p)
    add_firmware_arguments(p)
    add_capture_arguments(p)
    p.add_argument("--format", choices=sorted(FORMATS), default="text")
    p.add_argument(
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    p.add_argument("--max-violations", type=int, default=None, metavar="N")
    add_report_arguments(p)
    add_pulseview_argument(p)
    add_steps_arguments(p)
    add_engine_arguments(p)
    p.set_defaults(func=run)


def _firmware_options(args: argparse.Namespace) -> None:
    for firmware, names in _ONLY.items():
        for name in names:
            if firmware != args.firmware_name and getattr(args, name, None):
                option = "--" + name.replace("_", "-")
                raise UsageError(f"{option} is an option of simulate {firmware} only")


def run(args: argparse.Namespace) -> int:
    """Build, simulate, record, check; returns ``check``'s exit code."""
    _firmware_options(args)
    if args.firmware_name == "klipper":
        from wavecheck.cli._simulate_klipper import run_klipper

        return run_klipper(args)
    from wavecheck.mcu import grbl
    from wavecheck.mcu.build import build_firmware, build_runner
    from wavecheck.mcu.run import check_elf, simulate

    clock = parse_frequency(args.clock)
    if clock.denominator != 1 or clock <= 0:
        raise UsageError(f"--clock {args.clock}: a whole number of hertz is expected")
    max_s = _seconds(args.max_time, "--max-time")
    tail_s = _seconds(args.tail, "--tail")
    wall_s = _seconds(args.timeout, "--timeout")
    for name in ("gcode", "settings", "config_h", "elf"):
        path = getattr(args, name)
        if path is not None and not Path(path).is_file():
            raise UsageError(f"{path}: no such file (--{name.replace('_', '-')})")
    if not args.map and (not args.axes or set(args.axes.lower()) - set("xyz")):
        raise UsageError(f"--axes {args.axes}: grbl's axes are x, y and z (e.g. --axes xy)")
    sent = grbl.job(Path(args.settings) if args.settings else None, Path(args.gcode))

    runner = build_runner(_source(args, "simavr_src"))
    grbl_src = None if args.elf else _source(args, "grbl_src")
    if args.elf:
        elf = Path(args.elf)
    else:
        assert grbl_src is not None
        replace = {}
        if args.config_h:
            try:
                replace["grbl/config.h"] = Path(args.config_h).read_bytes()
            except OSError as err:
                raise UsageError(f"{args.config_h}: cannot read it: {err.strerror}") from None
        target = ["build/main.elf", f"CLOCK={int(clock)}"]
        elf = build_firmware(grbl_src, "grbl/stepper.c", replace, target, "build/main.elf")
    check_elf(elf, grbl.MCU)
    names, alarms = grbl.status_names(grbl_src or (Path(args.grbl_src) if args.grbl_src else None))
    outcome = simulate(
        runner,
        elf,
        grbl.MCU,
        int(clock),
        args.vcd,
        grbl.PINS,
        grbl.BANNER,
        [ln.text for ln in sent.lines],
        int(max_s * clock),
        int(tail_s * clock),
        float(wall_s),
        lambda r: grbl.replies(r, sent, names, alarms),
    )
    dump = grbl.settings_dump(outcome, sent)
    dump_text = "".join(f"{ln}\n" for ln in dump)
    if args.settings_out:
        atomic_write(args.settings_out, dump_text)
    return _check(args, dump_text)


def _check(args: argparse.Namespace, dump_text: str) -> int:
    """``check`` on the VCD: grbl's pins mapped unless ``--map`` says otherwise, its
    STEPPERS_DISABLE pin as an active-low enable (``$4=0``), its ``$$`` as ``--firmware`` with
    ``--check-settings``."""
    from wavecheck.mcu import grbl

    args.capture = [args.vcd]
    invert_enable = "$4=1" not in dump_text.split()
    if not args.map:
        axes = list(dict.fromkeys(args.axes.lower()))
        maps = [f"{a}.step={a.upper()}_STEP,{a}.dir={a.upper()}_DIR" for a in axes]
        if len(axes) == 1:
            maps = [f"step={axes[0].upper()}_STEP,dir={axes[0].upper()}_DIR"]
        args.map = [*maps, f"enable={grbl.ENABLE_PIN}"]
        if invert_enable and not args.invert:
            args.invert = ["enable"]
    if args.firmware or not args.check_settings:
        return run_check(args)
    if args.settings_out:  # the report names a file that stays
        args.firmware = args.settings_out
        return run_check(args)
    with tempfile.TemporaryDirectory(prefix="wavecheck-grbl-") as tmp:
        dump_path = Path(tmp) / "grbl-settings.txt"
        dump_path.write_text(dump_text, encoding="utf-8")
        args.firmware = str(dump_path)
        return run_check(args)
