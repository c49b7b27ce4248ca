"""Fixtures: simavr (patched and as it is) and grbl, each built once per cache key.

The cache is ``build/mcu-cache`` in the repository unless ``$WAVECHECK_CACHE`` says otherwise, so
a second run of the suite builds nothing (the builds are keyed by the hash of their sources)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import GRBL_SRC, KLIPPER_SRC, REPO, SIMAVR_SRC, need_sources


@pytest.fixture(scope="session", autouse=True)
def _mcu_cache() -> Iterator[None]:
    old = os.environ.get("WAVECHECK_CACHE")
    if old is None:
        os.environ["WAVECHECK_CACHE"] = str(REPO / "build" / "mcu-cache")
    yield
    if old is None:
        del os.environ["WAVECHECK_CACHE"]


@pytest.fixture(scope="session")
def runner() -> Path:
    need_sources()
    from wavecheck.mcu.build import build_runner

    return build_runner(SIMAVR_SRC)


@pytest.fixture(scope="session")
def runner_unpatched() -> Path:
    need_sources()
    from wavecheck.mcu.build import build_runner

    return build_runner(SIMAVR_SRC, fixes=False)


def grbl_elf(config_h: bytes | None = None) -> Path:
    from wavecheck.mcu.build import build_firmware

    replace = {"grbl/config.h": config_h} if config_h is not None else {}
    target = ["build/main.elf", "CLOCK=16000000"]
    return build_firmware(GRBL_SRC, "grbl/stepper.c", replace, target, "build/main.elf")


@pytest.fixture(scope="session")
def grbl() -> Path:
    need_sources()
    return grbl_elf()


def delay_config_h() -> bytes:
    """grbl's own config.h with its STEP_PULSE_DELAY line (config.h:425) switched on."""
    text = (GRBL_SRC / "grbl" / "config.h").read_text()
    line = "// #define STEP_PULSE_DELAY 10"
    assert line in text
    return text.replace(line, "#define STEP_PULSE_DELAY 10").encode()


@pytest.fixture(scope="session")
def grbl_delay() -> Path:
    need_sources()
    return grbl_elf(delay_config_h())


@pytest.fixture(scope="session")
def klipper_build() -> tuple[Path, Path]:
    """Klipper for the ATmega644P at 16 MHz (wavecheck's default .config): its ELF and dict."""
    need_sources(KLIPPER_SRC)
    from wavecheck.mcu.klipper import build

    return build(KLIPPER_SRC, None)


@pytest.fixture(scope="session")
def klippy() -> Path:
    need_sources(KLIPPER_SRC)
    from wavecheck.mcu.build import build_klippy

    return build_klippy(KLIPPER_SRC, sys.executable)
