"""``stepgen simulate --pid``: the servo thread's pid closing the loop around the plant.

The motion options give the joint's position command (``--move``, ``--command``,
``--position``); pid's output drives stepgen's velocity-cmd (``--plant stepgen``, the stepgen
running as ever in the base thread under the latency model) or a servo amplifier (``--plant
servo``: motor, load, encoder; its A/B quadrature goes to the VCD). Prints the following error
(max and where), LinuxCNC's FERROR/MIN_FERROR verdict (exit 1 when it trips, or when the loop
diverges and the run stops) and, for a constant command (a step), the step response figures;
``--plot`` draws them. ``-o`` takes ``.vcd`` or ``.sr`` (the encoder's ``phase-A``/``phase-B``
for the servo plant). With ``--ini``/``--hal``, the gains and limits the files set fill the
options not given (:mod:`stepgen.cli.linuxcnc_options`); the pins they leave unset keep the pid
component's defaults, while a run without files assumes pncconf's P = 1/servo period, FF1 = 1.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import fields, replace

import numpy as np

from stepgen.cli.pid_options import add_servo_loop_arguments
from stepgen.cli.tune import pid_gains, servo_params
from stepgen.lateness import catchup_for, parse_latency
from stepgen.loop import LoopResult, ferror_check, run_loop, step_metrics
from stepgen.motion import Motion
from stepgen.pid import PidGains
from stepgen.plant import (
    MAX_COUNT_CHANGES,
    QUADRATURE_PINS,
    ServoPlant,
    StepgenPlant,
    quadrature_edges,
)
from stepgen.reference import StepgenConfig
from stepgen.simulate import Trace, trace_from_run
from stepgen.vcdout import write_sr, write_vcd
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.capture.vcd.writer import VcdVector, VcdWire
from wavecheck.capture.vcd.writer import write_vcd as write_vcd_file
from wavecheck.errors import ConfigError
from wavecheck.output import atomic_path, figure_format
from wavecheck.verdict import EXIT_FAIL, EXIT_PASS

__all__ = ["add_servo_loop_arguments", "run_servo_loop"]


def _trace(cfg: StepgenConfig, plant: StepgenPlant, n: int, args: argparse.Namespace) -> Trace:
    """The recorded base periods as a :class:`Trace`, timed by the latency model as
    :func:`stepgen.simulate.simulate` times them."""
    model = parse_latency(args.latency)
    catchup, _ = catchup_for(model, cfg.base_period_ns, None)
    return trace_from_run(
        plant.invocation_run(n),
        model,
        seed=args.seed,
        active_edge=args.active_edge,
        catchup_ns=catchup,
    )


def _limits(args: argparse.Namespace) -> tuple[float, float | None, float | None]:
    """(FERROR, MIN_FERROR, MAX_VELOCITY) from the options (or the INI), checked before any
    work: FERROR and MAX_VELOCITY > 0, MIN_FERROR >= 0, all finite."""
    ferror = 1.0 if args.ferror is None else args.ferror  # LinuxCNC's default (pid reference §4.4)
    checks = (
        ("--ferror", ferror, False),
        ("--min-ferror", args.min_ferror, True),
        ("--joint-max-velocity", args.joint_max_velocity, False),
    )
    for option, value, zero_ok in checks:
        if value is None:
            continue
        if not (math.isfinite(value) and (value >= 0 if zero_ok else value > 0)):
            raise ConfigError(f"{option} {value!r} must be a number {'>= 0' if zero_ok else '> 0'}")
    return ferror, args.min_ferror, args.joint_max_velocity


def _write_encoder(out: str, plant: ServoPlant, end_ns: int, max_samples: int) -> None:
    """The encoder's A/B quadrature (and its count in a VCD) as ``out`` (.vcd or .sr)."""
    t, counts = plant.count_changes()
    edges, init = quadrature_edges(t, counts)
    if out.lower().endswith(".vcd"):
        write_vcd_file(
            out,
            [VcdWire(p, init[p], edges[p]) for p in QUADRATURE_PINS],
            vectors=[VcdVector("counts", t, counts, size=32)],
            timescale="1 ns",
            end=end_ns,
            scope="encoder",
            comment="stepgen servo plant: encoder A/B quadrature (stepgen type 2 table)",
        )
        return
    g = math.gcd(end_ns, 10**9)
    for p in QUADRATURE_PINS:
        if len(edges[p]):
            g = math.gcd(g, int(np.gcd.reduce(edges[p])))
    n_samples = end_ns // g
    if n_samples > max_samples:
        raise ConfigError(
            f"{out}: a .sr of this run needs {n_samples} samples (edges on a {g} ns grid), more "
            f"than --max-samples {max_samples} (write a .vcd instead, or shorten the run)"
        )
    write_sr_edges(
        out,
        list(QUADRATURE_PINS),
        [edges[p][edges[p] < end_ns] // g for p in QUADRATURE_PINS],
        [init[p] for p in QUADRATURE_PINS],
        int(n_samples),
        samplerate=10**9 // g,
        exact_source=ENCODER_SOURCE,
    )


#: How a servo-plant .sr names the simulation its exact edges come from.
ENCODER_SOURCE = "stepgen servo plant, a model (encoder A/B quadrature)"
#: A closed loop whose |command − feedback| passes this many times the command's reach has
#: diverged: the run stops there (and fails) instead of running into inf/NaN.
DIVERGED_FACTOR = 1e3


def run_servo_loop(args: argparse.Namespace, cfg: StepgenConfig, motion: Motion, n: int) -> int:
    """Run the closed loop for ``n`` base periods, write the output, print the report."""
    limits = _limits(args)
    servo_ns = cfg.servo_ns
    n_servo = -(-n // cfg.servo_multiple)
    cmds = motion.commands(n_servo, servo_ns, "position")
    reach = float(np.max(np.abs(cmds))) if len(cmds) else 0.0
    stop = DIVERGED_FACTOR * max(reach, 1.0)
    out = str(args.output)
    from_files = getattr(args, "_pid_from_files", False)
    for line in getattr(args, "_linuxcnc_ignored", []):
        print(f"stepgen: {line}", file=sys.stderr)
    if args.plant == "stepgen":
        vcfg = replace(cfg, mode="velocity")
        # pncconf's gains for a stepgen joint, unless the files set pid's pins (then the rest
        # keep the component's own defaults, as in LinuxCNC)
        defaults = PidGains() if from_files else PidGains(Pgain=round(1e9 / servo_ns, 9), FF1=1.0)
        gains = pid_gains(args, defaults)
        plant_s = StepgenPlant(vcfg, record=True)
        result = run_loop(plant_s, gains, cmds, stop_if_diverged=stop)
        trace = _trace(vcfg, plant_s, n, args)
        if out.lower().endswith(".vcd"):
            write_vcd(trace, out)
        else:
            write_sr(trace, out, max_samples=args.max_samples)
    else:
        params = servo_params(args)
        gains = pid_gains(args, PidGains())
        plant_v = ServoPlant(params, servo_ns, record=True)
        result = run_loop(plant_v, gains, cmds, stop_if_diverged=stop)
        if plant_v.truncated_at_ns is not None:
            if not result.diverged:
                raise ConfigError(
                    f"servo plant: the encoder makes more than {MAX_COUNT_CHANGES:.0e} count "
                    "changes in this run (give fewer --encoder-counts per unit or a shorter run)"
                )
            print(
                f"stepgen: note: the encoder's A/B stop at {plant_v.truncated_at_ns * 1e-9:.6g} s "
                f"({MAX_COUNT_CHANGES:.0e} count changes): the loop diverged",
                file=sys.stderr,
            )
        _write_encoder(out, plant_v, n_servo * servo_ns, args.max_samples)
    return report(args, result, gains, limits)


def gains_text(g: PidGains) -> str:
    """pid's pins that differ from the component's defaults (``Pgain 1000, FF1 1``)."""
    d = PidGains()
    parts = [
        f"{f.name.replace('_', '-')} {getattr(g, f.name):g}"
        if not isinstance(getattr(g, f.name), bool)
        else f"{f.name.replace('_', '-')} {str(getattr(g, f.name)).lower()}"
        for f in fields(g)
        if getattr(g, f.name) != getattr(d, f.name) or f.name == "Pgain"
    ]
    return ", ".join(parts)


def report(
    args: argparse.Namespace,
    r: LoopResult,
    gains: PidGains,
    limits: tuple[float, float | None, float | None],
) -> int:
    """Print the gains, following error, the FERROR verdict and step figures; draw the plot."""
    worst, at = r.max_ferror()
    check = ferror_check(r, *limits)
    ok = check.ok and not r.diverged
    verdict = "pass" if ok else "FAIL"
    if not args.quiet:
        pc = getattr(args, "_pid_config", None)
        origin = ""
        if pc is not None and pc.name is not None:
            origin = (
                f" ({pc.name}, joint {pc.joint}: {pc.chosen})" if pc.chosen else f" ({pc.name})"
            )
        elif getattr(args, "_pid_from_files", False):
            origin = f" ([JOINT_{pc.joint}] of the INI)" if pc is not None else ""
        print(f"pid: {gains_text(gains)}{origin}")
        if r.diverged:
            print(f"the loop diverged: stopped after {r.n} servo periods ({r.t_s[-1]:.6g} s)")
        run = f"{r.n * r.servo_ns * 1e-9:.6g} s ({r.n} servo periods of {r.servo_ns * 1e-6:g} ms)"
        print(f"following error: max {worst:.6g} units at {at:.6g} s, in a run of {run}")
        print(
            f"following-error check {verdict}: limit max(FERROR {check.ferror_limit:g}·|v|/"
            f"{check.max_velocity:g}, MIN_FERROR {check.min_ferror:g}); worst |ferror|/limit "
            f"{check.worst_ratio:.3g} at {check.worst_t_s:.6g} s"
            + (
                ""
                if check.first_fail_t_s is None
                else f"; trips first at {check.first_fail_t_s:.6g} s"
            )
        )
        for note in check.notes:
            print(f"stepgen: note: {note}", file=sys.stderr)
        c = r.command
        if len(c) > 2 and np.all(c == c[0]) and c[0] != 0:  # a step from rest at 0
            m = step_metrics(r.t_s, r.feedback, 0.0, float(c[0]))
            rise = "-" if m.rise_s is None else f"{m.rise_s:.6g} s"
            settle = "not within the run" if m.settling_s is None else f"{m.settling_s:.6g} s"
            print(
                f"step response: rise {rise}, overshoot {m.overshoot:.1%}, settling "
                f"({m.band:.0%}) {settle}, steady-state error {m.steady_state_error:.3g}"
            )
    if args.plot:
        _plot(r, args.plot)
    return EXIT_PASS if ok else EXIT_FAIL


def _plot(r: LoopResult, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    t = r.t_s * 1e3
    a1.plot(t, r.command, label="command", lw=1)
    a1.plot(t, r.feedback, label="feedback", lw=1)
    a1.set_ylabel("position")
    a1.legend(fontsize=7)
    a2.plot(t, r.ferror, lw=1, color="C3")
    a2.set_ylabel("following error")
    a2.set_xlabel("time (ms)")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=figure_format(path), dpi=100)
    plt.close(fig)
