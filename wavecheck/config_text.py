"""A configuration file's text, read with a bound (every firmware reader and LinuxCNC's INI and
HAL readers read through it): never a device or a FIFO, never more than a configuration holds."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from wavecheck.errors import ConfigError

__all__ = ["MAX_CONFIG_BYTES", "is_file", "read_text"]


def is_file(path: str | os.PathLike[str]) -> bool:
    """True for an existing regular file; False for a name the system refuses (too long, a
    NUL byte) as for a missing one."""
    try:
        return Path(path).is_file()
    except (OSError, ValueError):
        return False


#: The most a configuration file (INI, HAL, a firmware's settings) may hold: the largest real one
#: in the shared corpora is 0.2 MB; anything beyond this is not a configuration.
MAX_CONFIG_BYTES = 4 * 1024 * 1024

_NOT_REGULAR = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def read_text(path: str | os.PathLike[str]) -> str:
    """A configuration file's text, read with a bound: a device, FIFO, socket or directory is
    refused before it is opened (``/dev/zero`` never ends, a FIFO without a writer blocks), and
    more than :data:`MAX_CONFIG_BYTES` is refused; undecodable bytes are replaced.

    Raises:
        ConfigError: one line naming the file.
    """
    try:
        mode = os.stat(path).st_mode
        for test, kind in _NOT_REGULAR:
            if test(mode):
                raise ConfigError(f"{path}: is {kind}, not a configuration file")
        with open(path, "rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
    except OSError as err:
        raise ConfigError(f"{path}: cannot read: {err.strerror or err}") from None
    if len(data) > MAX_CONFIG_BYTES:
        raise ConfigError(
            f"{path}: more than {MAX_CONFIG_BYTES // (1024 * 1024)} MiB, far larger than any "
            "configuration file; give the configuration itself"
        )
    return data.decode("utf-8", errors="replace")
