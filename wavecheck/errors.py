"""The one exception hierarchy of wavecheck and stepgen.

Every error a user can cause (a bad file, a bad option, a bad rule file, a bad stepgen setting)
is a :class:`WavecheckError`. The command-line tools print ``str(error)`` as one line (then its
``details``, if any, one a line) and exit with :attr:`WavecheckError.exit_code` (2). Messages say
what is wrong, show the value, and end with a hint in parentheses where one helps.
:class:`RequirementError` is the one that is not about the input: a check from Python
(:func:`wavecheck.check`, the cocotb monitor) whose ``require=`` rules were not decided, exit code
4 as the command line's ``--require``.
"""

from __future__ import annotations

from os import PathLike

__all__ = [
    "CaptureError",
    "ConfigError",
    "DeviceError",
    "RequirementError",
    "RuleError",
    "UnitError",
    "UsageError",
    "WavecheckError",
]


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


class WavecheckError(Exception):
    """Base of every error caused by unusable input; the CLI exits with :attr:`exit_code`.

    ``details``: lines the CLI prints below the one-line message (the candidates of an ambiguity,
    one a line); ``str(error)`` stays the one line.
    """

    exit_code = 2

    def __init__(self, message: str, details: tuple[str, ...] = ()) -> None:
        super().__init__(_one_line(message))
        # each detail one line, its indentation kept
        self.details = tuple(d[: len(d) - len(d.lstrip(" "))] + _one_line(d) for d in details)


class CaptureError(WavecheckError):
    """A capture file cannot be read.

    Args:
        path: the file.
        where: the place in it (``"line 12"``, ``"member logic-1-3"``, ``"metadata"``, ``"byte 4096"``).
        msg: what is wrong, with the value and a hint.
    """

    def __init__(self, path: str | PathLike[str], where: str | None, msg: str) -> None:
        self.path = str(path)
        self.where = where
        self.msg = msg
        prefix = f"{self.path}: {where}: " if where else f"{self.path}: "
        super().__init__(prefix + msg)


class RuleError(WavecheckError):
    """A drive rule file is malformed (names the file and the key)."""

    def __init__(self, path: str | PathLike[str], key: str | None, msg: str) -> None:
        self.path = str(path)
        self.key = key
        prefix = f"{self.path}: {key}: " if key else f"{self.path}: "
        super().__init__(prefix + msg)


class ConfigError(WavecheckError):
    """A stepgen setting (option, INI/HAL value, latency model) is out of range or malformed."""


class DeviceError(WavecheckError):
    """A live acquisition failed: no device, sigrok-cli died or stopped early, samples were lost."""


class UsageError(WavecheckError):
    """A command-line option or API argument cannot be used (unknown channel, bad --map, ...)."""


class UnitError(UsageError):
    """A quantity such as ``"4.5us"`` or ``"31 kHz"`` cannot be parsed."""


class RequirementError(WavecheckError):
    """A rule the run requires (``require=``, ``--require``) is unchecked or indeterminate.

    Attributes:
        report: the report of the check (a ``Report`` or ``MachineReport``), complete.
        unmet: the required rules not decided (:class:`wavecheck.verdict.Unmet`).
    """

    exit_code = 4

    def __init__(self, message: str, report: object, unmet: tuple[object, ...]) -> None:
        super().__init__(message)
        self.report = report
        self.unmet = unmet
