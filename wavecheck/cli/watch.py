"""``wavecheck watch --driver DRIVER --drive ID --map …``: check a running machine live.

sigrok-cli is started on the logic analyzer (``wavecheck.live.acquisition``), its raw samples are
checked as they arrive (``wavecheck.live.watch``), a status line shows the figures so far, and
the end (``--time``, Ctrl-C, ``--stop-on-fail``) prints the same report as ``check`` with the same
exit codes. A failed acquisition (no device, sigrok-cli dying or stopping early) still prints the
report of what arrived, then a one-line error, exit 2.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any

from wavecheck.capture.edges import Capture
from wavecheck.cli._axis_args import add_axis_arguments, check_options
from wavecheck.cli._formats import FORMATS
from wavecheck.cli._reports import finish_report, write_outputs
from wavecheck.cli._stepgen_args import add_stepgen_arguments
from wavecheck.cli._tuning_args import add_tuning_arguments
from wavecheck.errors import DeviceError, UsageError
from wavecheck.live import START_GRACE
from wavecheck.output import output_file, resolve_output, same_file
from wavecheck.units import SAMPLE_RATE, format_frequency, parse_option

if TYPE_CHECKING:
    from wavecheck.engine import MachineCheck
    from wavecheck.live.learn import RoleLearner

__all__ = ["register", "run"]

#: Snippets written at most, unless --max-snippets says otherwise.
DEFAULT_MAX_SNIPPETS = 100
#: Bytes of samples kept at most while the roles are told from the waveforms (--learn).
MAX_LEARN_BYTES = 256 << 20
#: Edges a live check gathers at most before checking them (it also checks every 0.25 s).
LIVE_BLOCK_EDGES = 1 << 16
#: Time kept before and after each violation in a snippet, unless --snippet-window says.
DEFAULT_SNIPPET_WINDOW = "5ms"


def register(sub: Any) -> None:
    """Add the ``watch`` subcommand."""
    p = sub.add_parser(
        "watch",
        description="Start sigrok-cli on a logic analyzer and check every STEP/DIR edge as the "
        "samples arrive. Ctrl-C or --time ends it with the full report. Exit 0 pass, 1 a rule "
        "failed, 3 only indeterminate, 4 a rule --require asks for was not decided, 2 unusable "
        "input or a failed acquisition.",
    )
    dev = p.add_argument_group("analyzer")
    dev.add_argument(
        "--driver",
        required=True,
        metavar="DRIVER[:conn=…]",
        help="sigrok driver and its options, as sigrok-cli -d takes them (fx2lafw, "
        "demo:analog_channels=0, fx2lafw:conn=1.5)",
    )
    dev.add_argument(
        "--samplerate",
        metavar="RATE",
        help="sample rate with its unit (24MHz); default: the device's current rate",
    )
    dev.add_argument(
        "--channels",
        metavar="NAMES",
        help="logic channels to acquire, comma-separated (default: every logic channel); "
        "bit 0 of the data is the first",
    )
    dev.add_argument(
        "--config",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a device option passed to sigrok-cli --config (repeatable)",
    )
    dev.add_argument(
        "--channel-group",
        metavar="GROUP",
        help="sigrok-cli -g: every --config applies to this channel group (then the sample rate "
        "cannot be set in the same run; sigrok-cli 0.7.2)",
    )
    dev.add_argument("--sigrok-cli", metavar="PATH", help="the sigrok-cli program to run")
    p.add_argument(
        "--drive",
        action="append",
        required=True,
        metavar="ID|FILE|AXIS=ID",
        help="drive id or TOML file; AXIS=ID gives one axis its own drive (repeatable)",
    )
    add_axis_arguments(p)
    add_tuning_arguments(p)
    add_stepgen_arguments(p)
    p.add_argument(
        "--resolution",
        metavar="TIME",
        help="time resolution the verdicts assume, with its unit (default: one sample period)",
    )
    p.add_argument(
        "--learn",
        default="5s",
        metavar="TIME",
        help="without --map (and no channel named after a role): tell the roles from at most "
        "this much of the first samples, then check them and go on live (default 5s; at most "
        "256 MiB of samples are kept)",
    )
    end = p.add_argument_group("when to stop")
    end.add_argument(
        "--time",
        metavar="TIME",
        help="watch this long (10m, 30s), exactly that many samples; if they have not all "
        f"arrived {START_GRACE:g} s after that (a stalled analyzer), the watch ends, exit 2",
    )
    end.add_argument(
        "--stop-on-fail", action="store_true", help="stop at the first violation found"
    )
    keep = p.add_argument_group("what to keep")
    keep.add_argument(
        "--snippets",
        metavar="DIR",
        help="write a short .sr around each violation into DIR (PulseView opens them)",
    )
    keep.add_argument(
        "--snippet-window",
        metavar="TIME",
        help="samples kept before and after each violation in a snippet (at least this long, "
        f"whole samples; default {DEFAULT_SNIPPET_WINDOW})",
    )
    keep.add_argument(
        "--max-snippets",
        type=int,
        default=DEFAULT_MAX_SNIPPETS,
        metavar="N",
        help=f"snippet files written at most (default {DEFAULT_MAX_SNIPPETS}; the rest counted)",
    )
    keep.add_argument(
        "--save",
        type=output_file,
        metavar="FILE.sr",
        help="keep the whole stream as a .sr file, written as it arrives",
    )
    p.add_argument("--format", choices=sorted(FORMATS), default="text", help="report format")
    p.add_argument(
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    p.add_argument(
        "--max-violations", type=int, default=None, metavar="N", help="violations listed"
    )
    p.add_argument(
        "--status",
        choices=("auto", "always", "never"),
        default="auto",
        help="the live status line: on a terminal (auto), always (a line each update), never",
    )
    p.set_defaults(func=run)


def _time_samples(
    text: str | None, rate: Fraction, option: str, *, round_up: bool = False
) -> int | None:
    """``option``'s time as a number of samples at ``rate``: exact, or (``round_up``) the
    smallest whole number of samples that long."""
    if text is None:
        return None
    seconds = parse_option(text, option, "time")
    if seconds <= 0:
        raise UsageError(f"{option} {text}: must be positive")
    n = seconds * rate
    if round_up:
        return -(-n.numerator // n.denominator)
    if n.denominator != 1:
        raise UsageError(
            f"{option} {text}: not a whole number of samples at {format_frequency(rate)} "
            f"({float(n):.3f})"
        )
    return int(n)


def _status(mode: str) -> Any:
    if mode == "never" or (mode == "auto" and not sys.stderr.isatty()):
        return None
    if mode == "always" and not sys.stderr.isatty():
        return lambda line: print(line, file=sys.stderr, flush=True)

    def redraw(line: str) -> None:
        sys.stderr.write("\r\x1b[2K" + line)
        sys.stderr.flush()

    return redraw


def _refuse_shared_save(save: str, output: str | None) -> None:
    """Refuse ``--save`` onto the file or stream the report goes to: a zip and a report in one
    file are neither (``--save /dev/stdout > rec.sr`` with the report on standard output)."""
    target = resolve_output(save)
    report = output if output is not None else 1
    report_fd = resolve_output(output).fd if output is not None else 1
    if (target.fd is not None and target.fd == report_fd) or same_file(save, report):
        where = f"-o {output}" if output is not None else "standard output"
        raise UsageError(
            f"--save {save}: the report goes there too ({where}); give the report its own "
            "file (-o FILE) or --save a file"
        )


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck watch``; returns the exit code."""
    # the live machinery is imported here, not at start-up (wavecheck --help stays quick)
    from wavecheck.capture.binary import SampleBlocks
    from wavecheck.capture.srzip import sr_metadata
    from wavecheck.live.acquisition import (
        Acquisition,
        acquisition_command,
        probe_device,
        sigrok_cli,
    )
    from wavecheck.live.learn import RoleLearner
    from wavecheck.live.record import CHECKPOINT_SECONDS, SrRecorder
    from wavecheck.live.snippets import SampleRing, Snippets, replay_arguments
    from wavecheck.live.watch import Watch

    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    if args.max_snippets < 0:
        raise UsageError(f"--max-snippets must be 0 or more, got {args.max_snippets}")
    if args.save:
        _refuse_shared_save(args.save, args.output)
    program = sigrok_cli(args.sigrok_cli)
    rate = None
    if args.samplerate is not None:
        rate = parse_option(args.samplerate, "--samplerate", "frequency", SAMPLE_RATE)
        if rate.denominator != 1 or rate <= 0:
            raise UsageError(f"--samplerate {args.samplerate}: must be a whole number of Hz")
    info = probe_device(program, args.driver, rate=rate is None)
    rate = rate if rate is not None else info.samplerate
    if rate is None:
        raise DeviceError(f"{args.driver}: the device states no sample rate (give --samplerate)")
    names = info.logic
    if args.channels:
        wanted = [c.strip() for c in args.channels.split(",") if c.strip()]
        unknown = [c for c in wanted if c not in names]
        if unknown:
            raise UsageError(
                f"--channels: {', '.join(unknown)} not among {args.driver}'s logic channels "
                f"({' '.join(names)})"
            )
        names = wanted
    limit = _time_samples(args.time, rate, "--time")
    window = (
        _time_samples(
            args.snippet_window or DEFAULT_SNIPPET_WINDOW, rate, "--snippet-window", round_up=True
        )
        or 0
    )
    label = f"sigrok-cli -d {args.driver} at {format_frequency(rate)} (live)"
    scanner = SampleBlocks(label, len(names), rate, names)
    found: list[str] = []
    snippets = None

    from wavecheck.engine import axes_for, machine_for, needs_waveforms

    options = replace(check_options(args), block_edges=LIVE_BLOCK_EDGES)

    def start(capture: Capture) -> MachineCheck:
        """The live check of ``args``' axes (roles resolved against ``capture``)."""
        axes, found[:] = axes_for(options, capture)
        read = capture if capture is not scanner.skeleton else None  # names judged on it
        machine = machine_for(scanner.skeleton, options, axes, found, waveforms=read)
        if snippets is not None:  # each snippet says how to check it again
            snippets.check = replay_arguments(args, [a.plan for a in machine.axes], names)
        return machine

    def decide(capture: Capture, final: bool) -> MachineCheck | None:
        """The check once the roles can be told from ``capture`` (the first samples)."""
        try:
            machine = start(capture)
        except UsageError:
            if final:
                raise
            return None
        print(f"wavecheck: {found[0]}", file=sys.stderr, flush=True)
        return machine

    if args.snippets:
        ring = SampleRing(scanner.unitsize, 2 * window + int(rate) * 2)
        snippets = Snippets(Path(args.snippets), ring, names, rate, window, args.max_snippets)
    checker: MachineCheck | RoleLearner
    if needs_waveforms(options, scanner.skeleton):
        learn = _time_samples(args.learn, rate, "--learn", round_up=True) or 1
        checker = RoleLearner(scanner, decide, min(learn, MAX_LEARN_BYTES // scanner.unitsize))
    else:
        checker = start(scanner.skeleton)
    meta = sr_metadata(names, samplerate=int(rate), unitsize=scanner.unitsize, total_analog=0)
    command = acquisition_command(
        program,
        args.driver,
        names,
        samplerate=None if args.channel_group else rate,
        samples=limit,
        configs=args.config,
        group=args.channel_group,
    )
    recorder = SrRecorder(args.save, meta, scanner.unitsize) if args.save else None
    if recorder is not None and recorder.replaces is not None:
        print(
            f"wavecheck: recording to {recorder.path} (complete every {CHECKPOINT_SECONDS:g} s; "
            f"it replaces {recorder.replaces} when the watch ends)",
            file=sys.stderr,
            flush=True,
        )
    status = _status(args.status)
    watch = Watch(
        Acquisition(command, continuous=limit is None),
        scanner,
        checker,
        limit=limit,
        stop_on_fail=args.stop_on_fail,
        snippets=snippets,
        recorder=recorder,
        status=status,
    )
    try:
        result = watch.run()
    except BaseException:
        if recorder is not None:
            recorder.discard()
        raise
    if status is not None and sys.stderr.isatty():
        sys.stderr.write("\n")
    if recorder is not None:  # what arrived is kept, also when the acquisition then failed
        (recorder.close if result.samples else recorder.discard)()
    if result.failure is not None and result.samples == 0:
        raise DeviceError(f"{label}: {result.failure}; no samples arrived (nothing was checked)")
    report = finish_report(args, result.report)
    write_outputs(args, report)
    print(
        f"watched {result.samples:,} samples in {result.wall_s:.1f} s ({result.ended}); "
        f"wavecheck used {result.cpu_s:.2f} s of processor time "
        f"({100 * result.cpu_s / max(result.wall_s, 1e-9):.0f} % of one core)"
        + (f"; {result.snippet_summary}" if result.snippet_summary else ""),
        file=sys.stderr,
    )
    if result.failure is not None:
        raise DeviceError(f"{label}: {result.failure}; the report covers the samples before it")
    from wavecheck.report.claims import exit_code

    return exit_code(report, options.require)
