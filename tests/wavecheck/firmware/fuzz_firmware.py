"""Fuzz the firmware readers (issue 27), following ``tests/reliability/fuzz.py``:

    .venv/bin/python -m tests.wavecheck.firmware.fuzz_firmware                 # every format
    .venv/bin/python -m tests.wavecheck.firmware.fuzz_firmware --reader marlin -n 5000 --seed 3

Each format gets its seeds (small real files of ``../shared/firmware-corpus`` where one is small,
and a compact file of the same shape), every truncation of each seed and ``-n`` mutants: byte
flips, cuts, repeats, splices, and tokens of the format and of hostile numbers (``1e999999999``,
``nan``, 5,000 digits) inserted. The contract: a configuration read, or a
:class:`~wavecheck.errors.WavecheckError` whose message is one line naming the file; any other
exception, or a case over ``--max-seconds``, is a failure printed with a reproducer. Memory is
bounded by whoever runs it (``test_fuzz_firmware`` sets RLIMIT_AS). Exit 1 if anything failed.
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
import time
import traceback
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from wavecheck.errors import WavecheckError

CORPUS = Path(__file__).resolve().parents[4] / "shared" / "firmware-corpus"

_NUMBERS = [b"1e999999999", b"1e400", b"-1e400", b"nan", b"inf", b"-inf", b"9" * 5000,
            b"12345678901234567890", b"0", b"-0", b"0x7fffffff", b"1e-400", b"."]  # fmt: skip
_COMMON = [b"\x00", b"\n", b"\r\n", b"=", b":", b" ", b"\\\n", b"\xff\xfe", b"#", b";", b"{", b"}"]


def _grbl_seed() -> bytes:
    return b"$0=10\n$1=25\n$2=0\n$3=5\n$29=2.5\n$100=80.000\n$101=80\n$110=5000.000\n$111=3000\n"


def _klipper_seed() -> bytes:
    return (b"# STM32F103\n[include other.cfg]\n[printer]\nkinematics: corexy\nmax_velocity: 300\n"
            b"max_z_velocity: 5\n[stepper_x]\nstep_pin: !PB13\ndir_pin: z:PB12\nmicrosteps: 16\n"
            b"rotation_distance: 40\ngear_ratio: 50:17, 2:1\nstep_pulse_duration: 0.000002\n"
            b"[tmc2209 stepper_x]\nuart_pin: PC11\n[stepper_z1]\nstep_pin: PA1\ndir_pin: PA2\n"
            b"microsteps: 16\nrotation_distance: 8\n[extruder_stepper e1]\nstep_pin: ar54\n")  # fmt: skip


def _marlin_seed() -> bytes:
    return (b"#define CONFIGURATION_H_VERSION 02000905\n#define MOTHERBOARD BOARD_RAMPS_14_EFB\n"
            b"#define EXTRUDERS 2\n#define X_DRIVER_TYPE A4988\n#define Y_DRIVER_TYPE X_DRIVER_TYPE\n"
            b"#if MOTHERBOARD == BOARD_X\n  #define Z_DRIVER_TYPE TMC2209\n#elif ENABLED(FOO)\n"
            b"  #define Z_DRIVER_TYPE DRV8825\n#else\n  #define Z_DRIVER_TYPE TB6600\n#endif\n"
            b"#define E0_DRIVER_TYPE TERN(BAR, TMC2208, LV8729)\n/* block\n#define X x */\n"
            b"#define MINIMUM_STEPPER_PULSE 0 // us\n#define MAXIMUM_STEPPER_RATE (250000*2)\n"
            b"#define MINIMUM_STEPPER_POST_DIR_DELAY 650\n#define SQUARE_WAVE_STEPPING\n"
            b"#define DEFAULT_AXIS_STEPS_PER_UNIT { 80, 4000/3, 78.7402*2, double(93) }\n"
            b"#define DEFAULT_MAX_FEEDRATE { 500, 500, 5, 25 }\n#define INVERT_X_DIR true\n"
            b"#define STEP_STATE_X LOW\n#define COREXY\n")  # fmt: skip


def _rrf_seed() -> bytes:
    return (b"; Duet 3 MB6XD\nM584 X0 Y1:0.2 Z2 E3:4\nM569 P0 S1 T2.5:2.5:10:5\nM569 P1.0 T4\n"
            b"M350 X16 Y16 Z16 E16:16 I1\nM92 X80 Y80 Z400 E420:420 S16\nM203 X6000 Y{1+1} Z180\n"
            b"M667 S1\nM98 P\"missing.g\"\n")  # fmt: skip


def _smoothie_seed() -> bytes:
    return (b"microseconds_per_step_pulse 1 # c\nbase_stepping_frequency 100000\narm_solution "
            b"cartesian\nalpha_steps_per_mm 80\nalpha_step_pin 2.0!\nalpha_dir_pin 0.5!\n"
            b"alpha_max_rate 30000.0\nbeta_steps_per_mm 333.3333\ngamma_step_pin 2.2\n")  # fmt: skip


def _fluidnc_seed() -> bytes:
    return (b"board: 6 Pack\nstepping:\n  engine: I2S_STREAM\n  pulse_us: 4\n  dir_delay_us: 1\n"
            b"i2so:\n  min_pulse_us: 2\naxes:\n  x:\n    steps_per_mm: 800.000\n"
            b"    max_rate_mm_per_min: 5000.000\n    motor0:\n      tmc_2130:\n"
            b"        step_pin: I2SO.2:low\n        direction_pin: I2SO.1\n    motor1:\n"
            b"      rc_servo:\n        pwm_pin: gpio.2\n  y:\n    steps_per_mm:800\n")  # fmt: skip


def _ini_seed() -> bytes:
    return (b"#INCLUDE base.inc\n[EMCMOT]\nBASE_PERIOD = 25000\nSERVO_PERIOD = 1000000\n[KINS]\n"
            b"KINEMATICS = trivkins coordinates=XYZ\n[HAL]\nHALFILE = m.hal\nHALFILE = LIB:x.tcl\n"
            b"HALCMD = setp stepgen.0.dirhold 40000\n[JOINT_0]\nSTEPLEN = 5000\nAPP = a \\\n  b\n")  # fmt: skip


def _hal_seed() -> bytes:
    return (b"loadrt [KINS]KINEMATICS\nloadrt motmod base_period_nsec=25000 "
            b"servo_period_nsec=1000000\nloadrt hal_parport cfg=\"0 out\"\nsetp parport.0.reset-time "
            b"5000\nloadrt stepgen step_type=0,0\naddf stepgen.make-pulses base-thread\n"
            b"addf parport.0.reset base-thread\naddf stepgen.update-freq servo-thread\n"
            b"net xstep stepgen.0.step => parport.0.pin-02-out\nsetp parport.0.pin-02-out-reset 1\n"
            b"setp stepgen.0.steplen 5000\nsetp stepgen.0.stepspace 0\n"
            b"net xpos joint.0.motor-pos-cmd => stepgen.0.position-cmd\n"
            b"setp hm2_5i20.0.stepgen.00.steplen 1250\n")  # fmt: skip


def _corpus(*rels: str) -> list[bytes]:
    return [(CORPUS / r).read_bytes() for r in rels if (CORPUS / r).is_file()]


@dataclass(frozen=True)
class Format:
    """A format to fuzz: its file name, the format name for read_firmware, seeds and tokens."""

    filename: str
    fmt: str | None
    seeds: Callable[[], list[bytes]]
    tokens: list[bytes]
    beside: dict[str, bytes] = field(default_factory=dict)


FORMATS: dict[str, Format] = {
    "grbl": Format("dump.txt", "grbl", lambda: [_grbl_seed(), *_corpus(
        "grbl/tiago-rorke+wandering-gaze/grbl_settings.txt")], [b"$0=", b"$110=", b"$2=", b" ("]),
    "klipper": Format("printer.cfg", "klipper", lambda: [_klipper_seed(), *_corpus(
        "klipper/example-cartesian.cfg")], [b"[stepper_y]\n", b"step_pin: ", b"[tmc2130 ",
        b"rotation_distance: ", b"microsteps:", b"!", b"^"]),
    "marlin": Format("Configuration.h", "marlin", lambda: [_marlin_seed()], [b"#if ", b"#ifdef ",
        b"#else\n", b"#elif ", b"#endif\n", b"#define ", b"#undef X_DRIVER_TYPE\n", b"ENABLED(",
        b"defined(", b"(", b")", b"/*", b"*/", b"//", b"<<", b"/0", b"X_DRIVER_TYPE"]),
    "rrf": Format("config.g", "reprapfirmware", lambda: [_rrf_seed(), *_corpus(
        "rrf/idx_63423577542/config.g")], [b"M569 P", b" T", b":", b"M92 X", b"M350 X",
        b"M98 P\"config.g\"\n", b"M669 K"]),
    "smoothie": Format("config", "smoothieware", lambda: [_smoothie_seed()],
        [b"alpha_", b"_steps_per_mm ", b"_max_rate ", b"!", b"delta_step_pin 1.1\n"]),
    "fluidnc": Format("config.yaml", "fluidnc", lambda: [_fluidnc_seed(), *_corpus(
        "fluidnc/contributed/pen_2209/V2/2x_2209_V2_default.yaml")], [b"&a ", b"*a", b"[", b"]",
        b"  ", b"\t", b"- ", b"engine: ", b"pulse_us: ", b"!!python/object:x ", b"'", b'"']),
    "linuxcnc-ini": Format("m.ini", "linuxcnc", lambda: [_ini_seed()], [b"[HAL]\n",
        b"HALFILE = ", b"#INCLUDE ", b"BASE_PERIOD = ", b"[", b"]"],
        beside={"m.hal": _hal_seed(), "base.inc": b"[TRAJ]\nCOORDINATES = X Y Z\n"}),
    "linuxcnc-hal": Format("m.hal", "linuxcnc", lambda: [_hal_seed()], [b"loadrt ", b"setp ",
        b"net ", b"addf ", b"stepgen.0.", b"step_type=", b"[EMCMOT]", b'"', b"hostmot2",
        b"parport.0.", b"-reset 1\n"]),
}  # fmt: skip


def mutate(rng: random.Random, data: bytes, tokens: list[bytes], others: list[bytes]) -> bytes:
    """A few random edits of ``data``."""
    b = bytearray(data)
    for _ in range(rng.randint(1, 5)):
        op = rng.randrange(7)
        pos = rng.randrange(len(b) + 1) if b else 0
        if op == 0 and b:
            b[min(pos, len(b) - 1)] ^= rng.randint(1, 255)
        elif op == 1:
            del b[pos : pos + rng.randint(1, 32)]
        elif op in (2, 3):
            b[pos:pos] = rng.choice(tokens if op == 2 else _NUMBERS + _COMMON)
        elif op == 4 and b:
            end = min(len(b), pos + rng.randint(1, 80))
            b[pos:pos] = b[pos:end] * rng.randint(1, 50)
        elif op == 5:
            other = rng.choice(others)
            j = rng.randrange(len(other) + 1)
            b[pos:] = other[j:]
        else:
            del b[pos:]
    return bytes(b)


@dataclass
class Tally:
    """What one format's cases gave."""

    name: str
    cases: int = 0
    read: int = 0
    refused: int = 0
    slowest: float = 0.0
    failures: Counter[str] = field(default_factory=Counter)
    examples: dict[str, bytes] = field(default_factory=dict)

    def report(self, out: Path) -> str:
        lines = [f"{self.name}: {self.cases} cases, {self.read} read, {self.refused} refused, "
                 f"{sum(self.failures.values())} failures, slowest {self.slowest:.2f} s"]  # fmt: skip
        for i, (key, n) in enumerate(self.failures.most_common()):
            repro = out / f"{self.name}-failure-{i}-{FORMATS[self.name].filename}"
            repro.write_bytes(self.examples[key])
            lines.append(f"  {n:5d} x {key}  (reproducer: {repro})")
        return "\n".join(lines)


def _one(tally: Tally, form: Format, path: Path, data: bytes, max_seconds: float) -> None:
    from wavecheck.firmware import read_firmware

    path.write_bytes(data)
    tally.cases += 1
    start = time.monotonic()
    try:
        read_firmware(path, form.fmt)
        tally.read += 1
    except WavecheckError as err:
        tally.refused += 1
        text = str(err)
        if "\n" in text or str(path.parent) not in text:
            key = f"contract: not one line naming the file: {text[:100]!r}"
            tally.failures[key] += 1
            tally.examples.setdefault(key, data)
    except Exception as exc:  # noqa: BLE001 - every other exception is a finding
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        key = f"{type(exc).__name__}: {str(exc)[:80]} at {Path(tb.filename).name}:{tb.lineno}"
        tally.failures[key] += 1
        tally.examples.setdefault(key, data)
    took = time.monotonic() - start
    tally.slowest = max(tally.slowest, took)
    if took > max_seconds:
        key = f"bound: {took:.1f} s > {max_seconds} s on a {len(data)}-byte input"
        tally.failures[key] += 1
        tally.examples.setdefault(key, data)


def run(name: str, n: int, seed: int, max_seconds: float = 10.0) -> Tally:
    """Every truncation of each seed and ``n`` mutants of format ``name``."""
    form = FORMATS[name]
    seeds = form.seeds()
    tally = Tally(name)
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory(prefix=f"fuzz-{name}-") as tmp:
        path = Path(tmp) / form.filename
        for other, data in form.beside.items():
            (Path(tmp) / other).write_bytes(data)
        for s in seeds:
            for cut in range(0, len(s), max(1, len(s) // 200)):
                _one(tally, form, path, s[:cut], max_seconds)
        for _ in range(n):
            _one(tally, form, path, mutate(rng, rng.choice(seeds), form.tokens, seeds),
                 max_seconds)  # fmt: skip
    return tally


def main(argv: list[str] | None = None) -> int:
    """Run the fuzzer (see the module doc)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reader", choices=[*FORMATS, "all"], default="all")
    p.add_argument("-n", type=int, default=2000, help="random mutants per format")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--max-seconds", type=float, default=10.0, help="bound on one case")
    p.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "wavecheck-fuzz")
    args = p.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    failed = 0
    for name in FORMATS if args.reader == "all" else [args.reader]:
        tally = run(name, args.n, args.seed, args.max_seconds)
        print(tally.report(args.out), flush=True)
        failed += sum(tally.failures.values())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
