"""A command run as the program (``cli._main.as_program``) may end without the interpreter's
teardown (``_leave_now``): only when that teardown has nothing left to do but free memory. Each
case runs a real interpreter and checks what the teardown would have done still happens."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

PROGRAM = """
import atexit, os, sys, threading, time
from wavecheck.cli._main import as_program

def run():
    {body}
    print("printed", end="")  # no newline: left in the buffer until a flush
    return 3

sys.exit(as_program(run))
"""

CASES = {
    # nothing left: the process ends in _leave_now, after flushing the standard streams
    "plain": ("pass", "printed", ""),
    # a file opened and never closed (alive: a global): the usual exit writes its buffer
    "open file": ("global f; f = open(sys.argv[1], 'w'); f.write('kept')", "printed", "kept"),
    # an atexit callback runs
    "atexit": (
        "atexit.register(lambda: open(sys.argv[1], 'w').write('ran'))",
        "printed",
        "ran",
    ),
    # another thread is joined before the process ends
    "thread": (
        "threading.Thread(target=lambda: (time.sleep(0.2), "
        "open(sys.argv[1], 'w').write('joined'))).start()",
        "printed",
        "joined",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_program_ends_with_its_code_and_loses_nothing(case: str, tmp_path: Path) -> None:
    body, stdout, written = CASES[case]
    script = tmp_path / "prog.py"
    script.write_text(textwrap.dedent(PROGRAM).replace("{body}", body))
    side = tmp_path / "side.txt"
    run = subprocess.run(
        [sys.executable, str(script), str(side)], capture_output=True, text=True, timeout=60
    )
    assert (run.returncode, run.stdout, run.stderr) == (3, stdout, "")
    assert (side.read_text() if side.exists() else "") == written


@pytest.mark.parametrize(("extra", "torn_down"), [("", False), ("atexit", True)])
def test_the_plain_case_skips_the_teardown(extra: str, torn_down: bool, tmp_path: Path) -> None:
    """The fast end is taken when nothing is left: the teardown's audit event (raised when the
    interpreter state is cleared) never comes; with an atexit callback it does. The hook
    writes to a descriptor open from the start, which the descriptor check accepts."""
    side = tmp_path / "side.txt"
    script = tmp_path / "prog.py"
    script.write_text(
        textwrap.dedent(
            """
            import atexit, os, sys
            from wavecheck.cli._main import as_program

            fd = os.open(sys.argv[1], os.O_WRONLY | os.O_CREAT)

            def hook(event, args, write=os.write):
                if event == "cpython.PyInterpreterState_Clear":
                    write(fd, b"torn down")

            sys.addaudithook(hook)
            if sys.argv[2:] == ["atexit"]:
                atexit.register(int)
            sys.exit(as_program(lambda: 0))
            """
        )
    )
    argv = [sys.executable, str(script), str(side), *([extra] if extra else [])]
    run = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    assert (run.returncode, run.stderr) == (0, "")
    assert side.read_text() == ("torn down" if torn_down else "")


def test_a_failed_flush_keeps_the_usual_exit(tmp_path: Path) -> None:
    """Standard output gone before its last flush (here its descriptor closed): _leave_now's
    flush fails, so the interpreter's own exit reports it as it always did (exit 120)."""
    script = tmp_path / "prog.py"
    script.write_text(
        textwrap.dedent(
            """
            import os, sys
            from wavecheck.cli._main import as_program

            def run():
                sys.stdout.write("left in the buffer")
                os.close(1)
                return 0

            sys.exit(as_program(run))
            """
        )
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}  # keep the buffer
    run = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=60, env=env
    )
    assert run.returncode == 120
    assert "Bad file descriptor" in run.stderr


SPY = """
import sys
from wavecheck.cli import _main

def spy(top_pad=0, side=sys.argv[1]):
    open(side, "a").write(f"tuned {top_pad}\\n")

_main.keep_freed_memory = spy
from wavecheck.cli import main
sys.argv = ["wavecheck", *sys.argv[2:]]
sys.exit(main() if "--argv" not in sys.argv else main(sys.argv[1:-1]))
"""


@pytest.mark.parametrize(
    ("argv", "tuned"),
    [
        (["check", "captures/real/grbl_cnc_1.sr", "--drive", "leadshine-dm542", "-q"], "tuned 0\n"),
        (["drives"], ""),  # no numpy: not worth loading ctypes for
        (
            ["check", "captures/real/grbl_cnc_1.sr", "--drive", "leadshine-dm542", "-q", "--argv"],
            "",
        ),
    ],
    ids=["check as the program", "drives", "main(argv)"],
)
def test_the_program_of_an_array_command_keeps_freed_memory(
    argv: list[str], tuned: str, tmp_path: Path
) -> None:
    """``run_cli`` asks glibc to keep freed memory (``keep_freed_memory``) only for the
    program's run (``main()``, as the console script) of a command that loaded numpy; another
    program calling ``main(argv)`` keeps its allocator as it was."""
    side = tmp_path / "side.txt"
    script = tmp_path / "prog.py"
    script.write_text(SPY)
    root = Path(__file__).resolve().parents[3]
    subprocess.run(
        [sys.executable, str(script), str(side), *argv], capture_output=True, text=True,
        timeout=120, cwd=root,
    )  # fmt: skip
    assert (side.read_text() if side.exists() else "") == tuned
