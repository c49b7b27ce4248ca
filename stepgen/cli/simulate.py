"""``stepgen simulate``: run the LinuxCNC stepgen model under a latency model, write VCD or .sr.

Options are named after LinuxCNC's parameters; every time carries its unit (``25us``, ``5000ns``;
a bare number other than 0 is refused, docs/reference.md "Numbers and units"), while the numbers in
``--ini``/``--hal`` files stay LinuxCNC's bare ns. A base period below 1 us is refused as a unit
slip. Exit 0 on success, 2 with a one-line message on bad settings (nothing is written).

What a worst-case run proves: with --latency worst:J:RULE and the worst-case motion (--motion
worst, the default when no other motion is given), every interval of RULE that make-pulses can
make with these parameters (the pulse, the gap and the step period at the full step rate, and the
DIR hold, DIR setup, gap and step period across a reversal requested at the earliest moment after
a pulse) occurs at least once at its worst-case length n·P − J, with n its fewest base periods;
so if `wavecheck check` passes RULE on the output, every such interval meets the drive under any
latency up to J (J < P). Not covered: the corner cases of a reversal requested after the DIR hold
has run out (LinuxCNC issue #2332: DIR setup shorter than dirsetup, even 0), which no latency
causes; simulate them with --move or --command.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from stepgen.cli.linuxcnc_options import add_simulate_arguments, apply_to_simulate_args
from stepgen.cli.pid_options import add_servo_loop_arguments
from stepgen.lateness import DEFAULT_CATCHUP_NS, parse_latency
from stepgen.motion import Motion, parse_command_csv, parse_moves, worst_motion
from stepgen.reference import StepgenConfig, update_schedule
from stepgen.simulate import MAX_PERIODS, n_periods_for, simulate
from stepgen.vcdout import DEFAULT_MAX_SAMPLES, write_sr, write_vcd
from wavecheck.cli._main import keep_freed_memory
from wavecheck.errors import ConfigError, UnitError
from wavecheck.output import atomic_write, output_file
from wavecheck.progress import QUIET_HELP, activate
from wavecheck.units import BASE_PERIOD, Plausible, number_option, option_ns, shorten

__all__ = ["build_config", "build_motion", "register", "run"]


def register(sub: Any) -> None:
    """Add the ``simulate`` subcommand."""
    p = sub.add_parser(
        "simulate",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    g = p.add_argument_group("stepgen (LinuxCNC names)")
    g.add_argument("--type", type=int, default=0, help="step_type 0..15 (default 0 = step/dir)")
    g.add_argument("--user-step-type", default="", help="type 15 table, e.g. 1,3,2,0")
    g.add_argument(
        "--base-period",
        default="25us",
        help="base thread period with its unit (default 25us; below 1 us is refused)",
    )
    g.add_argument(
        "--servo-period",
        default="1ms",
        help="servo thread period with its unit, rounded by HAL to n·base (default 1ms)",
    )
    g.add_argument(
        "--mode",
        choices=("position", "velocity"),
        default="position",
        help="ctrl_type (default position)",
    )
    g.add_argument(
        "--position-scale", type=number_option, default=1.0, help="steps per position unit"
    )
    g.add_argument(
        "--maxvel", type=number_option, default=0.0, help="units/s (0 = only the step-rate limit)"
    )
    g.add_argument(
        "--maxaccel",
        type=number_option,
        default=0.0,
        help="units/s² (0 = full speed in one servo period)",
    )
    for name in ("steplen", "stepspace", "dirsetup", "dirhold", "dirdelay"):
        g.add_argument(
            f"--{name}", default="1ns", help=f"{name} with its unit (default 1ns → 1 period)"
        )
    g.add_argument(
        "--thread-order",
        choices=("auto", "update-first", "pulses-first"),
        default="auto",
        help="which function runs first at a common tick; auto = update-first for a single thread "
        "(servo = base, as tests/stepgen.0), pulses-first for two threads (the base thread usually "
        "ticks first); update-first shows the start-up quirk",
    )
    m = p.add_argument_group("motion")
    m.add_argument("--position", type=number_option, help="constant position-cmd (units)")
    m.add_argument("--velocity", type=number_option, help="constant velocity-cmd (units/s)")
    m.add_argument(
        "--command", metavar="FILE.csv", help="time_s,value rows, each held until the next"
    )
    m.add_argument(
        "--move", metavar="SPEC", help="trapezoid moves: 'X, X@V, pause 10ms, ...' from 0"
    )
    m.add_argument(
        "--motion",
        choices=("worst",),
        help="worst: full-rate runs and reversals at the earliest moment after a pulse, so every "
        "interval make-pulses can make occurs at its fewest periods (velocity mode; the default "
        "with --latency worst:J:RULE and no other motion)",
    )
    m.add_argument(
        "--move-vel", type=number_option, help="peak velocity of --move (default --maxvel)"
    )
    m.add_argument(
        "--move-accel", type=number_option, help="acceleration of --move (default --maxaccel)"
    )
    m.add_argument("--duration", help="simulated time with its unit (e.g. 2s, 500ms)")
    m.add_argument("--periods", type=int, help="simulated base periods")
    lat = p.add_argument_group("latency")
    lat.add_argument(
        "--latency",
        default="none",
        help="none | uniform:J | normal:SIGMA,MAX | spike:J@EVERY | histogram:FILE | worst:J:RULE "
        "(times with their unit, e.g. worst:11us:dir_hold; every interval of RULE the motion "
        "makes is n·P − J long; see above for what a pass proves; below 100 ns warns)",
    )
    lat.add_argument(
        "--seed", type=int, default=0, help="seed of the random latency models (default 0)"
    )
    lat.add_argument(
        "--active-edge",
        choices=("rising", "falling"),
        default="rising",
        help="drive's active STEP edge (worst-case events)",
    )
    lat.add_argument(
        "--catchup",
        default=_CATCHUP_DEFAULT,
        help=f"run time of an invocation, with its unit: the next cannot start before it ends "
        f"(default {DEFAULT_CATCHUP_NS}ns; P − J under worst:J:RULE when that is shorter, so the "
        "bound n·P − J is reached)",
    )
    o = p.add_argument_group("output")
    o.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", required=True, type=output_file, help="OUT.vcd or OUT.sr"
    )
    o.add_argument(
        "--max-samples", type=int, default=DEFAULT_MAX_SAMPLES, help=".sr size limit in samples"
    )
    o.add_argument(  # read by wavecheck follow --command
        "--command-out",
        type=output_file,
        metavar="FILE.csv",
        help="also write the commanded trajectory: time_s,position (units; velocity mode: the "
        "integral of velocity-cmd) and steps (× position-scale; --plant servo: counts × "
        "--encoder-counts) at each servo update",
    )
    o.add_argument(
        "--engine",
        choices=("fast", "reference"),
        default="fast",
        help="fast (default) or the plain per-period loop",
    )
    o.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    add_servo_loop_arguments(p)  # --pid: the closed loop (stepgen.cli.servo)
    add_simulate_arguments(p)  # --ini/--hal/--channel fill the options left at their defaults
    p.set_defaults(func=run)


class _DefaultText(str):
    """An option's default left untouched (tells "not given" from the same value typed)."""

    __slots__ = ()


_CATCHUP_DEFAULT = _DefaultText(f"{DEFAULT_CATCHUP_NS}ns")


def _ns(text: str, option: str, allow_zero: bool = True, plausible: Plausible | None = None) -> int:
    """An option's time in whole ns; its unit is required (:func:`parse_option`)."""
    try:
        value = option_ns(str(text), option, plausible)
    except UnitError as err:
        raise ConfigError(str(err)) from None
    if value.denominator != 1:
        raise ConfigError(f"{option} {shorten(text)}: not a whole number of ns")
    if value < 0 or (value == 0 and not allow_zero):
        raise ConfigError(f"{option} {shorten(text)}: must be {'>= 0' if allow_zero else '> 0'}")
    return int(value)


def build_config(args: argparse.Namespace) -> StepgenConfig:
    """The :class:`StepgenConfig` from parsed options (raises ConfigError)."""
    apply_to_simulate_args(args)
    table: tuple[int, ...] = ()
    if args.user_step_type:
        try:
            table = tuple(int(x, 0) for x in args.user_step_type.split(","))
        except ValueError:
            raise ConfigError(
                f"--user-step-type {args.user_step_type!r} is not a list of integers (e.g. 1,3,2,0)"
            ) from None
    base = _ns(args.base_period, "--base-period", allow_zero=False, plausible=BASE_PERIOD)
    servo = _ns(args.servo_period, "--servo-period", allow_zero=False)
    order = args.thread_order
    if order == "auto":
        order = "update-first" if servo == base else "pulses-first"
    cfg = StepgenConfig(
        step_type=args.type,
        user_step_type=table,
        base_period_ns=base,
        servo_period_ns=servo,
        mode=args.mode,
        position_scale=args.position_scale,
        maxvel=args.maxvel,
        maxaccel=args.maxaccel,
        steplen=_ns(args.steplen, "--steplen"),
        stepspace=_ns(args.stepspace, "--stepspace"),
        dirsetup=_ns(args.dirsetup, "--dirsetup"),
        dirhold=_ns(args.dirhold, "--dirhold"),
        dirdelay=_ns(args.dirdelay, "--dirdelay"),
        thread_order=order,
        enable=getattr(args, "enable", True),
    )
    cfg.validate()
    return cfg


MOTIONS = ("position", "velocity", "command", "move", "motion")


def build_motion(
    args: argparse.Namespace, cfg: StepgenConfig, n_updates: int | None = None
) -> Motion:
    """The :class:`Motion` from ``--position/--velocity/--command/--move/--motion`` (exactly
    one; ``--motion worst`` when none is given under ``--latency worst:J:RULE``).
    ``n_updates``: servo updates the worst-case motion is designed for (None: its own length)."""
    given = [n for n in MOTIONS if getattr(args, n, None) is not None]
    if not given and parse_latency(args.latency).kind == "worst":
        given = ["motion"]
        args.motion = "worst"
    if len(given) != 1:
        raise ConfigError(
            f"give exactly one of --position, --velocity, --command, --move, --motion worst (got {', '.join('--' + g for g in given) or 'none'})"
        )
    kind = given[0]
    if kind == "motion":
        if cfg.mode != "velocity":
            raise ConfigError(
                "the worst-case motion drives velocity-cmd: run with --mode velocity "
                "(make-pulses, which makes every interval, is the same in both modes)"
            )
        return worst_motion(cfg, n_updates=n_updates)
    if kind == "position" or kind == "velocity":
        if kind != cfg.mode:
            raise ConfigError(f"--{kind} needs --mode {kind} (the stepgen is in {cfg.mode} mode)")
        value = float(getattr(args, kind))
        if not math.isfinite(value):
            raise ConfigError(f"--{kind} {value} is not finite")
        return Motion(kind, value)
    if kind == "command":
        times, values = parse_command_csv(args.command)
        return Motion("csv", csv_times=times, csv_values=values)
    vel = args.move_vel if args.move_vel is not None else cfg.maxvel
    acc = args.move_accel if args.move_accel is not None else cfg.maxaccel
    return Motion("moves", segments=parse_moves(args.move, vel, acc))


def run(args: argparse.Namespace) -> int:
    """Run ``stepgen simulate``; returns the exit code."""
    # its engine and writer make many short-lived arrays of a few MB: 20 k page faults for the
    # 20 s run of ``make bench``'s ``stepgen`` row, 13 k with this (bench/README.md, Round 5)
    keep_freed_memory(top_pad=64 << 20)
    out = Path(args.output)
    suffix = out.suffix.lower()
    if suffix not in (".vcd", ".sr"):
        raise ConfigError(f"-o {args.output!r}: write a .vcd or a .sr file")
    cfg = build_config(args)
    warnings: list[str] = list(getattr(args, "_linuxcnc_ignored", []))
    latency = parse_latency(args.latency)
    worst = args.motion == "worst" or (
        latency.kind == "worst" and all(getattr(args, k) is None for k in MOTIONS)
    )
    if worst and cfg.mode != "velocity":
        cfg = replace(cfg, mode="velocity")
        warnings.append(
            "the worst-case motion drives velocity-cmd: the channel runs in velocity mode "
            "(make-pulses, which makes every interval, is the same in both modes)"
        )
    if args.periods is not None and args.duration is not None:
        raise ConfigError("give --periods or --duration, not both")
    n: int | None = None
    if args.periods is not None:
        n = args.periods
    elif args.duration is not None:
        n = n_periods_for(cfg, _ns(args.duration, "--duration", allow_zero=False))
    if n is not None and n < 1:
        raise ConfigError(f"--periods {n} must be >= 1")
    updates = None  # the worst-case motion is designed for the run's servo updates
    if worst and n is not None and n <= MAX_PERIODS:  # (simulate refuses longer runs)
        updates = len(update_schedule(cfg, n))
    motion = build_motion(
        args, replace(cfg, mode="position") if args.pid else cfg, n_updates=updates
    )
    if n is None:
        if motion.natural_duration_s is None:
            raise ConfigError("give --duration (e.g. 1s) or --periods N")
        n = n_periods_for(cfg, round(motion.natural_duration_s * 1e9))
    if args.pid:  # the closed loop: pid between the position command and the plant
        from stepgen.cli.servo import run_servo_loop

        if args.command_out:
            _write_command(args, cfg, motion, n)
        return run_servo_loop(args, cfg, motion, n)
    catchup_given = not isinstance(args.catchup, _DefaultText)
    catchup_ns = _ns(args.catchup, "--catchup", allow_zero=False)
    with activate("simulating", quiet=args.quiet, unit="periods"):
        trace = simulate(
            cfg,
            motion,
            latency,
            n_periods=n,
            seed=args.seed,
            active_edge=args.active_edge,
            catchup_ns=catchup_ns if catchup_given else None,
            engine=args.engine,
        )
    for line in warnings + [t for t in trace.notes if t.startswith("warning:")]:
        print(f"stepgen: {line}", file=sys.stderr)
    if args.command_out:
        _write_command(args, cfg, motion, n)
    t0 = time.perf_counter()
    with activate(f"writing {out}", quiet=args.quiet, unit="changes"):
        if suffix == ".vcd":
            changes = write_vcd(trace, out)
            what = f"{changes} value changes, 1 ns timescale"
        else:
            rate, samples = write_sr(trace, out, max_samples=args.max_samples)
            what = f"{samples} samples at {rate} Hz"
    t_write = time.perf_counter() - t0
    if not args.quiet:
        sim_s = trace.n_periods * cfg.base_period_ns * 1e-9
        print(
            f"{out}: {trace.steps} steps, final counts {trace.final_counts}, {trace.n_periods} periods "
            f"({sim_s:g} s) of type {cfg.step_type} at P = {cfg.base_period_ns} ns, servo {cfg.servo_ns} ns; "
            f"latency {latency.text}; simulated in {trace.seconds:.3f} s, written in {t_write:.3f} s ({what})"
        )
        for note in trace.notes:
            if not note.startswith("warning:"):
                print(f"stepgen: note: {note}", file=sys.stderr)
    return 0


def _write_command(args: argparse.Namespace, cfg: StepgenConfig, motion: Motion, n: int) -> None:
    """``--command-out``: the command at each servo update u (u·servo period), and a last row at
    the end of the run (n·base period) holding the last position."""
    n_servo = -(-n // cfg.servo_multiple)
    mode = "position" if args.pid else cfg.mode
    values = motion.commands(n_servo, cfg.servo_ns, mode)
    if mode == "velocity":  # held from one update to the next: the position is its integral
        pos = np.concatenate([[0.0], np.cumsum(values) * (cfg.servo_ns * 1e-9)])
    else:
        pos = np.concatenate([values, values[-1:]])
    ns = [u * cfg.servo_ns for u in range(n_servo)] + [
        max(n * cfg.base_period_ns, n_servo * cfg.servo_ns)
    ]
    servo = args.pid and args.plant == "servo"
    scale = float(args.encoder_counts) if servo else cfg.position_scale
    name = "counts" if servo else "steps"
    rows = [f"time_s,position{',' + name if scale else ''}\n"]
    for t, x in zip(ns, pos, strict=True):
        rows.append(
            f"{t // 10**9}.{t % 10**9:09d},{float(x)!r}"
            + (f",{float(x) * scale!r}\n" if scale else "\n")
        )
    atomic_write(args.command_out, "".join(rows))
