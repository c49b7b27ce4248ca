"""``stepgen tune``: the integrator's manual PID tuning method, run on a model plant.

I = D = 0, raise P until the loop oscillates (ultimate gain Ku, period Pu), P = Ku/2,
raise I until the offset is corrected within --settle (stopping before instability), then D
while it reduces the overshoot. Prints each stage's step response and the final gains as
[JOINT_n] INI lines and the setp lines that read them; for a velocity-mode stepgen also the
feed-forward LinuxCNC configurations use (P = 1/servo period, FF1 = 1) and the following error
at cruise with each. Exit 0, or 2 with one line on bad settings.
"""

from __future__ import annotations

import argparse
import base64
import html
import io
import json
import math
from collections.abc import Callable
from typing import Any

from stepgen.cli.pid_options import (
    GAIN_OPTIONS,
    SERVO_OPTIONS,
    add_pid_arguments,
    add_servo_arguments,
)
from stepgen.pid import PidGains
from stepgen.plant import Plant, ServoParams, ServoPlant, StepgenPlant
from stepgen.reference import StepgenConfig
from stepgen.tune import Stage, TuneResult, feedforward_comparison, hal_lines, ini_lines, tune
from wavecheck.errors import ConfigError, UnitError
from wavecheck.output import atomic_path, atomic_write, figure_file, figure_format, output_file
from wavecheck.units import number_option, time_ns

__all__ = [
    "add_pid_arguments",
    "add_servo_arguments",
    "pid_gains",
    "register",
    "run",
    "servo_params",
    "time_s",
]


def time_s(text: str, option: str) -> float:
    """A time option with a unit (``200ms``) in seconds, > 0."""
    try:
        value = time_ns(str(text))
    except UnitError as err:
        raise ConfigError(f"{option} {text!r}: {err}") from None
    if value <= 0:
        raise ConfigError(f"{option} {text!r} must be > 0")
    return float(value) * 1e-9


def pid_gains(args: argparse.Namespace, defaults: PidGains) -> PidGains:
    """``defaults`` with every gain option given on the command line applied."""
    values: dict[str, Any] = {}
    for dest, name in GAIN_OPTIONS.items():
        v = getattr(args, dest, None)
        if v is not None:
            if not math.isfinite(v):
                raise ConfigError(f"--{dest.replace('_', '-')} {v} is not finite")
            values[name] = float(v)
    if not getattr(args, "error_previous_target", True):
        values["error_previous_target"] = False
    return PidGains(**{**defaults.__dict__, **values})


def servo_params(args: argparse.Namespace) -> ServoParams:
    """The :class:`ServoParams` from the options (validated)."""
    v = {f: float(getattr(args, d)) for d, f in SERVO_OPTIONS.items()}
    p = ServoParams(
        inertia=v["inertia"],
        viscous=v["viscous"],
        torque_constant=v["torque_constant"],
        coulomb=v["coulomb"],
        load=v["load"],
        counts_per_unit=v["counts_per_unit"],
        amp_limit=v["amp_limit"],
    )
    p.validate()
    return p


def register(sub: Any) -> None:
    """Add the ``tune`` subcommand."""
    p = sub.add_parser(
        "tune",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    g = p.add_argument_group("plant")
    g.add_argument(
        "--plant",
        choices=("stepgen", "servo"),
        default="servo",
        help="servo: a motor and load (options below); stepgen: LinuxCNC's stepgen in velocity mode",
    )
    g.add_argument("--servo-period", default="1ms", help="servo thread period (default 1ms)")
    g.add_argument("--base-period", default="25us", help="base thread period (stepgen plant)")
    g.add_argument(
        "--position-scale", type=number_option, default=200.0, help="steps per unit (stepgen)"
    )
    g.add_argument("--maxvel", type=number_option, default=0.0, help="stepgen maxvel, units/s")
    g.add_argument("--maxaccel", type=number_option, default=0.0, help="stepgen maxaccel, units/s²")
    add_servo_arguments(p.add_argument_group("servo plant (--plant servo)"))
    t = p.add_argument_group("method")
    t.add_argument(
        "--step", type=number_option, default=0.01, help="step size, position units (0.01)"
    )
    t.add_argument("--settle", default="200ms", help="the offset must go within this (200ms)")
    t.add_argument(
        "--band", type=number_option, default=0.02, help="settling band, fraction of the step"
    )
    t.add_argument("--window", default="1s", help="length of each step response (1s)")
    t.add_argument("--p-start", type=number_option, default=1.0, help="first P tried (1)")
    t.add_argument("--joint", type=int, default=0, help="joint number of the INI/HAL lines")
    t.add_argument(
        "--ff-velocity", type=number_option, help="cruise speed of the FF comparison (stepgen)"
    )
    o = p.add_argument_group("output")
    o.add_argument("--format", choices=("text", "json"), default="text")
    o.add_argument(
        "--plot",
        type=figure_file,
        help="every stage's step response (PNG; .jpg, .svg or .pdf by the file's name)",
    )
    o.add_argument(
        "--html",
        type=output_file,
        help="self-contained page: every stage's figures and response plot, the INI/HAL lines",
    )
    p.set_defaults(func=run)


def _check_method(args: argparse.Namespace) -> None:
    """The method's numbers, before any response is run (one line each)."""
    if not (math.isfinite(args.p_start) and args.p_start > 0):
        raise ConfigError(f"--p-start {args.p_start!r} must be a number > 0 (the first P tried)")
    if args.joint < 0:
        raise ConfigError(f"--joint {args.joint} must be 0 or more")
    v = args.ff_velocity
    if v is not None and not (math.isfinite(v) and v > 0):
        raise ConfigError(f"--ff-velocity {v!r} must be a speed > 0 (units/s)")
    for dest in ("position_scale", "maxvel", "maxaccel"):
        value = getattr(args, dest)
        if not math.isfinite(value):
            raise ConfigError(f"--{dest.replace('_', '-')} {value!r} is not finite")


def _plant_factory(
    args: argparse.Namespace,
) -> tuple[Callable[[], Plant], int, StepgenConfig | None]:
    _check_method(args)
    servo = round(time_s(args.servo_period, "--servo-period") * 1e9)
    if servo < 1000:
        raise ConfigError(f"--servo-period {args.servo_period}: below 1 us is not a servo thread")
    if args.plant == "stepgen":
        cfg = StepgenConfig(
            base_period_ns=round(time_s(args.base_period, "--base-period") * 1e9),
            servo_period_ns=servo,
            mode="velocity",
            position_scale=args.position_scale,
            maxvel=args.maxvel,
            maxaccel=args.maxaccel,
            thread_order="pulses-first",
        )
        cfg.validate()
        return (lambda: StepgenPlant(cfg)), cfg.servo_ns, cfg
    params = servo_params(args)
    return (lambda: ServoPlant(params, servo)), servo, None


def _fmt(x: float | None, unit: str = "s") -> str:
    return "-" if x is None else f"{x:.4g} {unit}"


def report_text(res: TuneResult, args: argparse.Namespace, ff_lines: list[str]) -> str:
    """The human-readable report."""
    lines = [
        f"ultimate gain Ku = {res.ku:.6g}, oscillation period Pu = {res.pu:.6g} s ({res.tries} responses)"
    ]
    for s in res.stages:
        m = s.metrics
        lines.append(
            f"  {s.name:<14} P {s.gains.Pgain:<10.6g} I {s.gains.Igain:<10.6g} D {s.gains.Dgain:<10.6g} "
            f"rise {_fmt(m.rise_s)}, overshoot {m.overshoot:.1%}, settling ({m.band:.0%}) "
            f"{_fmt(m.settling_s)}, steady-state error {m.steady_state_error:.3g} — {s.note}"
        )
    lines += [f"note: {n}" for n in res.notes]
    lines.append("")
    lines += ini_lines(res.final, args.joint)
    lines.append("")
    lines += hal_lines(args.joint)
    lines += ff_lines
    return "\n".join(lines) + "\n"


def write_plot(res: TuneResult, path: str) -> None:
    """One panel per stage kind: position vs time of each response."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    for s in res.stages:
        r = s.result
        ax.plot(
            r.t_s * 1e3,
            r.feedback,
            lw=1.0,
            label=f"{s.name}: P {s.gains.Pgain:.4g} I {s.gains.Igain:.4g} D {s.gains.Dgain:.4g}",
        )
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("position (units)")
    ax.set_title(f"step responses (Ku = {res.ku:.4g}, Pu = {res.pu * 1e3:.4g} ms)")
    ax.legend(fontsize=6)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=figure_format(path), dpi=100)
    plt.close(fig)


def stage_png(stage: Stage, step: float) -> bytes:
    """One stage's step response (command and feedback against time) as PNG bytes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = stage.result
    fig, ax = plt.subplots(figsize=(8, 2.6))
    t = r.t_s * 1e3
    ax.plot(t, r.command, lw=1.0, color="0.5", label="command")
    ax.plot(t, r.feedback, lw=1.0, color="C0", label="feedback")
    m = stage.metrics
    if m.band > 0:
        ax.axhspan(step * (1 - m.band), step * (1 + m.band), color="C2", alpha=0.12, lw=0)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("position (units)")
    ax.set_title(
        f"{stage.name}: P {stage.gains.Pgain:.4g}, I {stage.gains.Igain:.4g}, "
        f"D {stage.gains.Dgain:.4g}",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()


_CSS = """
body{font-family:system-ui,sans-serif;margin:2rem auto;max-width:1100px;padding:0 1rem;color:#222}
h1{font-size:1.4rem}h2{font-size:1.1rem;margin-top:1.6rem;border-bottom:1px solid #ddd}
table{border-collapse:collapse;font-size:.9rem}th,td{border:1px solid #ddd;padding:.2rem .5rem}
th{background:#f4f4f4}td.num{text-align:right;font-variant-numeric:tabular-nums}
pre{background:#f7f7f7;padding:.5rem;font-size:.85rem}img{max-width:100%;border:1px solid #eee}
.note{color:#555;font-size:.9rem}
"""


def render_html(res: TuneResult, args: argparse.Namespace, ff_lines: list[str]) -> str:
    """The self-contained ``--html`` page: every stage's figures and its response plot as an
    inline PNG, the notes, the INI/HAL lines and the feed-forward comparison (no external
    request of any kind)."""
    e = html.escape
    rows = []
    figures = []
    for k, s in enumerate(res.stages, 1):
        m = s.metrics
        rows.append(
            f'<tr><td><a href="#stage-{k}">{e(s.name)}</a></td>'
            + "".join(
                f'<td class="num">{v}</td>'
                for v in (
                    f"{s.gains.Pgain:.6g}",
                    f"{s.gains.Igain:.6g}",
                    f"{s.gains.Dgain:.6g}",
                    e(_fmt(m.rise_s)),
                    f"{m.overshoot:.1%}",
                    e(_fmt(m.settling_s)),
                    f"{m.steady_state_error:.3g}",
                )
            )
            + f"<td>{e(s.note)}</td></tr>"
        )
        png = base64.b64encode(stage_png(s, args.step)).decode("ascii")
        figures.append(
            f'<h3 id="stage-{k}">{e(s.name)}</h3><p class="note">{e(s.note)}</p>'
            f'<img alt="step response, {e(s.name)}" src="data:image/png;base64,{png}">'
        )
    notes = "".join(f"<li>{e(n)}</li>" for n in res.notes)
    lines = ini_lines(res.final, args.joint) + [""] + hal_lines(args.joint)
    ff = "\n".join(line for line in ff_lines if line)
    body = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        "<title>stepgen tune</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>stepgen tune: the integrator's manual method</h1>",
        f'<p id="ultimate">Ultimate gain Ku = {res.ku:.6g}, oscillation period Pu = '
        f"{res.pu:.6g} s ({res.tries} responses; plant {e(args.plant)}, step {args.step:g} "
        f"units, settling band {args.band:.0%}, --settle {e(str(args.settle))}).</p>",
        '<h2>Stages</h2><table class="stages"><tr><th>stage</th><th>P</th><th>I</th><th>D</th>'
        "<th>rise</th><th>overshoot</th><th>settling</th><th>steady-state error</th>"
        f"<th>decision</th></tr>{''.join(rows)}</table>",
        f'<ul class="notes">{notes}</ul>' if notes else "",
        f'<h2>Final gains</h2><pre class="ini">{e(chr(10).join(lines))}</pre>',
        f'<p class="feedforward">{e(ff)}</p>' if ff else "",
        "<h2>Step responses</h2>",
        *figures,
        '<p class="note">Made by stepgen tune (a model; times in s).</p></body></html>',
    ]
    return "\n".join(b for b in body if b) + "\n"


def _finite(x: Any) -> Any:
    """JSON has no inf/NaN: they become null."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def run(args: argparse.Namespace) -> int:
    """Run ``stepgen tune``; returns the exit code."""
    make, servo_ns, cfg = _plant_factory(args)
    res = tune(
        make,
        step=args.step,
        settle_s=time_s(args.settle, "--settle"),
        window_s=time_s(args.window, "--window"),
        band=args.band,
        p_start=args.p_start,
    )
    gains = (res.ku, res.final.Pgain, res.final.Igain, res.final.Dgain)
    if not all(math.isfinite(g) for g in gains):
        raise ConfigError(
            "the model gives no finite gains for these plant figures (check --inertia, "
            "--viscous, --torque-constant and their units)"
        )
    ff_lines: list[str] = []
    ff = None
    if cfg is not None:
        v = args.ff_velocity if args.ff_velocity is not None else (0.5 * cfg.maxvel or 1.0)
        ff = feedforward_comparison(make, res.final, v, servo_ns)
        ff_lines = [
            "",
            f"velocity-mode stepgen: LinuxCNC configurations use P = 1/servo period = "
            f"{ff.configured.Pgain:g} and FF1 = 1 (pncconf); following error at {v:g} units/s cruise: "
            f"tuned {ff.tuned_ferror:.4g}, configured {ff.configured_ferror:.4g} units",
        ]
    if args.plot:
        write_plot(res, args.plot)
    if args.html:
        atomic_write(args.html, render_html(res, args, ff_lines))
    if args.format == "json":
        doc = {
            "ku": res.ku,
            "pu_s": res.pu,
            "responses": res.tries,
            "stages": [
                {
                    "name": s.name,
                    "gains": {"P": s.gains.Pgain, "I": s.gains.Igain, "D": s.gains.Dgain},
                    "rise_s": s.metrics.rise_s,
                    "overshoot": s.metrics.overshoot,
                    "settling_s": s.metrics.settling_s,
                    "steady_state_error": s.metrics.steady_state_error,
                    "note": s.note,
                }
                for s in res.stages
            ],
            "final": {"P": res.final.Pgain, "I": res.final.Igain, "D": res.final.Dgain},
            "ini": ini_lines(res.final, args.joint),
            "hal": hal_lines(args.joint),
            "notes": res.notes,
        }
        if ff is not None:
            doc["feedforward"] = {
                "velocity": ff.velocity,
                "configured": {"P": ff.configured.Pgain, "FF1": ff.configured.FF1},
                "tuned_ferror": ff.tuned_ferror,
                "configured_ferror": ff.configured_ferror,
            }
        print(json.dumps(_finite(doc), indent=2, allow_nan=False))
    else:
        print(report_text(res, args, ff_lines), end="")
    return 0
