"""Run the CLIs in-process and hold them to the error contract of DESIGN.md (issue 8).

Exit 2 for unusable input with exactly one line on stderr that names the file, never a
traceback; any other exception escaping ``main`` fails the test (that is the traceback a user
would see). With ``-o``, a failed run leaves no file behind.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from pathlib import Path

from tests.bounds import hang_guard
from tests.reliability.corpus import Case, one_line_error


def cli(prog: str, argv: Sequence[str]) -> tuple[int, str, str]:
    """Run ``wavecheck`` or ``stepgen`` in-process: (exit code, stdout, stderr)."""
    if prog == "wavecheck":
        from wavecheck.cli import main
    else:
        from stepgen.cli import main
    out, err = io.StringIO(), io.StringIO()
    with hang_guard(), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(list(argv))
        except SystemExit as exc:  # argparse
            rc = int(exc.code) if isinstance(exc.code, int) else 2
    return rc, out.getvalue(), err.getvalue()


def write_case(folder: Path, case: Case) -> Path:
    path = folder / f"{case.name.replace('/', '_')}{case.suffix}"
    path.write_bytes(case.data)
    return path


def assert_contract(
    rc: int, err: str, path: str, expect: str, ok_codes: Sequence[int] = (0,)
) -> None:
    """``rc``/``err`` of one run obey the contract for a case expected to be ``expect``."""
    if rc == 2:
        problem = one_line_error(err, path)
        assert problem is None, problem
        assert expect != "ok", f"a valid input was refused: {err.strip()}"
    else:
        assert rc in ok_codes, f"exit {rc}, stderr {err[:300]!r}"
        assert "Traceback" not in err
        assert expect != "error", f"accepted a broken input (exit {rc})"


def assert_no_output(folder: Path) -> None:
    """No report and no temporary file was left in ``folder``."""
    left = sorted(p.name for p in folder.iterdir())
    assert left == [], f"files left behind after a failed run: {left}"


def info_then_check(folder: Path, case: Case, *, missing_channels_ok: bool = False) -> None:
    """Run ``wavecheck info`` and ``wavecheck check -o report.json`` on ``case`` and hold both to
    the error contract: a file ``info`` cannot read cannot be checked either; a refused check
    leaves no report, an accepted one leaves a whole one.

    ``missing_channels_ok``: a valid file without STEP/DIR channels may refuse the mapping.
    """
    path = write_case(folder, case)
    rc, _, err = cli("wavecheck", ["info", str(path)])
    assert_contract(rc, err, str(path), case.expect)
    out_dir = folder / "out"
    out_dir.mkdir(exist_ok=True)
    rc2, _, err2 = cli(
        "wavecheck",
        ["check", str(path), "--drive", "gecko-g202", "--map", "step=STEP,dir=DIR",
         "--format", "json", "-o", str(out_dir / "report.json")],
    )  # fmt: skip
    try:
        if missing_channels_ok and case.expect == "ok" and rc2 == 2 and "no channel" in err2:
            return
        expect = "error" if rc == 2 else case.expect
        assert_contract(rc2, err2, str(path), expect, ok_codes=(0, 1, 3))
        if rc2 == 2:
            assert_no_output(out_dir)
        else:
            assert (out_dir / "report.json").exists()
    finally:
        for p in out_dir.iterdir():
            p.unlink()
