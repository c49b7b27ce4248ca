"""Start-up stays light (issues 18 and 29): the heavy or rarely needed layers are imported only by
the command that uses them, so ``wavecheck --help``, ``wavecheck drives`` and a check of a small
VCD load none of them; ``--help``, ``--version`` and ``drives`` load no numpy and no subcommand's
module but the one run. (Timings are in ``make bench``, not here: this checks what is imported.)"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from stepgen.cli import COMMANDS as STEPGEN_COMMANDS
from wavecheck.cli import COMMANDS

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "captures/golden/g202-p16-dirhold2-worst.vcd"

#: Imported only where used: plotting, HTML/XML, pyvcd (the writer's header, the reference
#: reader), the sigrok-cli layer, firmware readers, latency analysis, cross-checks, reports
#: other than text/JSON, the live watch, cocotb.
LAZY = (
    "matplotlib",
    "lxml",
    "vcd",
    "wavecheck.capture.sigrokcli",
    "wavecheck.crosscheck",
    "wavecheck.firmware.grbl",
    "wavecheck.firmware.marlin",
    "wavecheck.firmware.capture",
    "wavecheck.lattice",
    "wavecheck.live.watch",
    "wavecheck.live.acquisition",
    "wavecheck.live.record",
    "cocotb",
    "wavecheck.report.html",
    "wavecheck.report.plot",
    "wavecheck.report.junit",
    "wavecheck.report.gtkw",
)


def _loaded_after(argv: list[str], tool: str = "wavecheck") -> set[str]:
    code = (
        "import sys\n"
        f"from {tool}.cli import main\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        "print('--- modules ---', *sys.modules)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    return set(run.stdout.rpartition("--- modules ---")[2].split())


@pytest.mark.parametrize(
    "argv",
    [[], ["--help"], ["drives"], ["check", str(TINY), "--drive", "gecko-g202"]],
    ids=["import", "help", "drives", "check-tiny-vcd"],
)
def test_start_up_does_not_import_heavy_layers(argv: list[str]) -> None:
    if not argv:  # just the import of the command's module
        code = "import sys, wavecheck.cli; print('\\n'.join(sys.modules))"
        loaded = set(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                    text=True, check=True).stdout.split())  # fmt: skip
    else:
        loaded = _loaded_after(argv)
    assert "wavecheck.cli" in loaded  # the probe sees what it should
    assert sorted(m for m in LAZY if m in loaded) == []


def test_the_probe_sees_a_lazy_import_when_it_happens() -> None:
    loaded = _loaded_after(["check", str(TINY), "--drive", "gecko-g202", "--format", "junit"])
    assert "wavecheck.report.junit" in loaded


#: The subcommand modules (every ``wavecheck.cli.NAME`` and ``stepgen.cli.NAME`` that is one).
SUBCOMMAND_MODULES = {c.module for c in (*COMMANDS.values(), *STEPGEN_COMMANDS.values())}


@pytest.mark.parametrize(
    ("tool", "argv", "module"),
    [
        ("wavecheck", ["--help"], None),
        ("wavecheck", ["--version"], None),
        ("wavecheck", [], None),  # the usage error
        ("wavecheck", ["no-such-command"], None),
        ("wavecheck", ["drives"], "wavecheck.cli.drives"),
        ("wavecheck", ["drives", "gecko-g202", "--format", "json"], "wavecheck.cli.drives"),
        ("wavecheck", ["sigrok", "--help"], "wavecheck.cli.sigrok"),
        ("stepgen", ["--help"], None),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else str(v),
)
def test_short_commands_load_no_numpy_and_one_subcommand(
    tool: str, argv: list[str], module: str | None
) -> None:
    loaded = _loaded_after(argv, tool)
    assert f"{tool}.cli._main" in loaded or "wavecheck.cli._main" in loaded
    assert "numpy" not in loaded
    assert sorted(SUBCOMMAND_MODULES & loaded) == ([module] if module else [])


def test_the_drive_table_loads_no_python_toml_parser() -> None:
    """``wavecheck drives`` (issue 38): the rule files are parsed by rtoml, tomllib only for a
    file rtoml refuses; difflib only for an error's hint."""
    assert sorted({"tomllib", "difflib"} & _loaded_after(["drives"])) == []
    assert "difflib" in _loaded_after(["drives", "no-such-drive"])  # the probe sees it


def test_the_drive_table_defines_no_dataclass() -> None:
    """``wavecheck drives`` (issue 38): its record types (Drive, Figure, Rule, the format
    registry …) are :mod:`wavecheck.record` classes, so neither :mod:`dataclasses` nor the
    :mod:`inspect` it imports loads (~6 ms), and no method is compiled per class."""
    loaded = _loaded_after(["drives"])
    assert sorted({"dataclasses", "inspect"} & loaded) == []
    assert "wavecheck.record" in loaded  # the probe sees the records' module


def test_argparse_asks_the_terminal_width_only_to_write_help() -> None:
    """argparse's formatter imports shutil for the terminal's width (~2 ms with bz2/lzma):
    ``drives`` writes no help, so builds no formatter that asks; ``--help`` does."""
    assert "shutil" not in _loaded_after(["drives"])
    assert "shutil" in _loaded_after(["drives", "--help"])  # the probe sees it


def test_a_command_first_builds_no_other_subcommand_parser() -> None:
    """The other subcommands' (empty) parsers are listed only where argparse may show them:
    ``--help`` or an error before the command word."""
    code = (
        "import argparse\n"
        "from wavecheck.cli import main\n"
        "made = []\n"
        "init = argparse.ArgumentParser.__init__\n"
        "def spy(self, *a, **k):\n"
        "    made.append(k.get('prog'))\n"
        "    init(self, *a, **k)\n"
        "argparse.ArgumentParser.__init__ = spy\n"
        "main(['drives'])\n"
        "print('--- parsers ---', len(made))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    assert run.stdout.rpartition("--- parsers ---")[2].split() == ["2"]  # the tool's, drives'


def test_a_check_plot_loads_no_measurement_module(tmp_path: Path) -> None:
    """``check --plot`` (issue 38: CPU beyond matplotlib's import) draws the motion panel with
    report.measured_plot, whose measure-only types are annotations, not imports."""
    out = tmp_path / "p.png"
    loaded = _loaded_after(["check", str(TINY), "--drive", "gecko-g202", "--plot", str(out)])
    assert out.stat().st_size > 10_000  # it drew
    assert "wavecheck.report.measured_plot" in loaded
    assert "wavecheck.measurement" not in loaded


@pytest.mark.parametrize(
    ("tool", "call", "young", "frozen"),
    [("wavecheck", "main()", "50000", "True"), ("wavecheck", "main(['drives'])", "700", "False"),
     ("stepgen", "main()", "50000", "True"), ("stepgen", "main(['--help'])", "700", "False")],
)  # fmt: skip
def test_only_the_program_tunes_the_garbage_collector(
    tool: str, call: str, young: str, frozen: str
) -> None:
    """``main()`` as the console script calls it: fewer young collections, the objects left
    frozen for the exit (issue 38); ``main(argv)`` from another program changes nothing. (The
    state is printed by an atexit callback, which also keeps the process from ending before
    the interpreter's exit: tests/wavecheck/cli/test_program_exit.py.)"""
    argv = ["drives"] if tool == "wavecheck" else ["--help"]
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('--- gc ---', gc.get_threshold()[0],"
        " gc.get_freeze_count() > 0))\n"
        f"sys.argv = [{tool!r}, *{argv!r}]\n"
        f"from {tool}.cli import main\n"
        "try:\n"
        f"    {call}\n"
        "except SystemExit:\n"
        "    pass\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    assert run.stdout.rpartition("--- gc ---")[2].split() == [young, frozen]


def test_a_simulated_vcd_loads_no_numpy_ma(tmp_path: Path) -> None:
    """``np.unique`` imports numpy.ma (8 ms, issue 38): the engine and the VCD writer avoid it."""
    out = tmp_path / "o.vcd"
    argv = ["simulate", "--mode", "velocity", "--velocity", "2", "--position-scale", "1000",
            "--duration", "20ms", "--latency", "uniform:5us", "--seed", "1", "-o", str(out), "-q"]  # fmt: skip
    loaded = _loaded_after(argv, "stepgen")
    assert out.stat().st_size > 1000  # it simulated and wrote
    assert "numpy" in loaded and "numpy.ma" not in loaded


def test_the_probe_sees_numpy_and_the_subcommand_when_they_load() -> None:
    loaded = _loaded_after(["check", str(TINY), "--drive", "gecko-g202"])
    assert "numpy" in loaded
    assert "wavecheck.cli.check" in loaded
    assert "wavecheck.cli.info" not in loaded


@pytest.mark.parametrize(
    ("name", "module"),
    [(n, c.module) for n, c in (*COMMANDS.items(), *STEPGEN_COMMANDS.items())],
)
def test_each_listed_subcommand_is_built_by_its_module(name: str, module: str) -> None:
    """The table's name is the one parser its module's ``register`` adds, and that parser
    runs the module's command; ``--help`` lists the table's line (one place for it)."""
    sub = argparse.ArgumentParser().add_subparsers()
    importlib.import_module(module).register(sub)
    assert list(sub.choices) == [name]
    assert callable(sub.choices[name].get_default("func"))


GRBL_SR = ROOT / "captures/real/grbl_cnc_1.sr"

#: The project's modules each short path loads, pinned (issue 38: start-up is what a command
#: imports before it reads a byte). A module joining one of these sets costs every such run;
#: add it here only when the path needs it.
PINNED: dict[str, tuple[list[str], set[str]]] = {
    "drives": (
        ["drives"],
        {
            "wavecheck", "wavecheck.cli", "wavecheck.cli._formats", "wavecheck.cli._main",
            "wavecheck.cli._tuning_args", "wavecheck.cli.drives", "wavecheck.drives",
            "wavecheck.drives.datasheet", "wavecheck.drives.library", "wavecheck.errors",
            "wavecheck.output", "wavecheck.record", "wavecheck.rules", "wavecheck.steptypes",
            "wavecheck.units",
        },
    ),
    "check sr --map": (
        ["check", str(GRBL_SR), "--drive", "leadshine-dm542", "--map", "step=STEP (Y axis),dir=EN"],
        {
            "wavecheck", "wavecheck.capture", "wavecheck.capture.blocks", "wavecheck.capture.edges",
            "wavecheck.capture.formats", "wavecheck.capture.keyfile", "wavecheck.capture.open",
            "wavecheck.capture.sr", "wavecheck.capture.srzip", "wavecheck.capture.zipdir",
            "wavecheck.cli", "wavecheck.cli._axis_args",
            "wavecheck.cli._batch", "wavecheck.cli._capture_args", "wavecheck.cli._check_flow",
            "wavecheck.cli._firmware_args", "wavecheck.cli._formats",
            "wavecheck.cli._linuxcnc_args", "wavecheck.cli._main", "wavecheck.cli._pulseview_args",
            "wavecheck.cli._reports", "wavecheck.cli._stepgen_args", "wavecheck.cli._steps_args",
            "wavecheck.cli._tuning_args", "wavecheck.cli.check", "wavecheck.drives",
            "wavecheck.drives.datasheet", "wavecheck.drives.library", "wavecheck.drives.overrides",
            "wavecheck.engine", "wavecheck.engine.axis", "wavecheck.engine.intervals",
            "wavecheck.engine.judge", "wavecheck.engine.options", "wavecheck.engine.outcome",
            "wavecheck.engine.rates", "wavecheck.engine.resolve", "wavecheck.engine.results",
            "wavecheck.engine.run", "wavecheck.engine.sinks", "wavecheck.engine.trace",
            "wavecheck.engine.windows", "wavecheck.errors", "wavecheck.firmware",
            "wavecheck.output", "wavecheck.progress", "wavecheck.record", "wavecheck.report",
            "wavecheck.report.assumptions", "wavecheck.report.claims", "wavecheck.report.groups",
            "wavecheck.report.json", "wavecheck.report.machine", "wavecheck.report.text",
            "wavecheck.roles", "wavecheck.roles.names", "wavecheck.rules", "wavecheck.steps",
            "wavecheck.steps.decode", "wavecheck.steps.interface", "wavecheck.steps.mapping",
            "wavecheck.steps.primitives", "wavecheck.steptypes", "wavecheck.timebase",
            "wavecheck.units", "wavecheck.verdict",
        },
    ),
}  # fmt: skip

#: Never on those paths: roles inference (the channels are mapped; roles.names, what a name
#: says, is read), the firmware records and readers (no --firmware), the LinuxCNC configuration
#: (no --ini/--hal/--base-period), the steps CSV writer, the PulseView session writer, json (a
#: text report), tempfile (only standard input is spooled), numpy.ma (np.unique), numpy.typing
#: (annotations only), shlex (only messages quote a --map example), glob (no wildcard given).
NOT_LOADED = ("wavecheck.roles.infer", "wavecheck.firmware.guarantee", "wavecheck.linuxcnc",
              "wavecheck.report.steps_csv", "wavecheck.sigrok.session", "json", "tempfile",
              "numpy.ma", "numpy.typing", "shlex", "glob")  # fmt: skip


def test_a_check_of_an_sr_reads_the_zip_and_metadata_without_the_stdlib_parsers() -> None:
    """Issue 38: an ordinary .sr's zip directory and members are read by capture.zipdir, its
    metadata by capture.keyfile; zipfile (threading, bz2, lzma, binascii, cp437), configparser
    and shutil cost ~4 ms of the check's start-up and are loaded only for an exotic zip."""
    loaded = _loaded_after(PINNED["check sr --map"][0])
    assert "wavecheck.capture.zipdir" in loaded  # the probe sees the reader
    unwanted = ("zipfile", "configparser", "shutil", "bz2", "lzma", "threading", "encodings.cp437")
    assert sorted(m for m in unwanted if m in loaded) == []


@pytest.mark.parametrize("path", list(PINNED))
def test_a_short_path_loads_the_pinned_modules(path: str) -> None:
    argv, pinned = PINNED[path]
    loaded = _loaded_after(argv)
    ours = {m for m in loaded if m == "wavecheck" or m.startswith("wavecheck.")}
    assert sorted(ours - pinned) == [], "new on the path: pin it here only if the path needs it"
    assert sorted(pinned - ours) == [], "no longer on the path: take it out of the pin"
    assert sorted(m for m in NOT_LOADED if m in loaded) == []


@pytest.mark.parametrize(
    ("option", "module"),
    [
        (["--steps-csv", "STEPS"], "wavecheck.report.steps_csv"),
        (["--format", "json"], "json"),
        (["--base-period", "25us"], "wavecheck.linuxcnc.stepgen_config"),
        (["--pulseview", "PVS"], "wavecheck.sigrok.session"),
        (
            ["--firmware", str(ROOT / "captures/firmware/grbl/settings.md")],
            "wavecheck.firmware.guarantee",
        ),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else v,
)
def test_the_option_that_needs_a_lazy_module_loads_it(
    option: list[str], module: str, tmp_path: Path
) -> None:
    argv = [
        *PINNED["check sr --map"][0],
        *(
            {"STEPS": str(tmp_path / "s.csv"), "PVS": str(tmp_path / "s.pvs")}.get(o, o)
            for o in option
        ),
    ]
    assert module in _loaded_after(argv)


def test_a_named_capture_without_map_loads_roles_inference() -> None:
    """The probe's other side: a capture mapped by its channels' names loads the inference
    (the waveforms of the named lines are checked against their names)."""
    assert "wavecheck.roles.infer" in _loaded_after(["check", str(TINY), "--drive", "gecko-g202"])
