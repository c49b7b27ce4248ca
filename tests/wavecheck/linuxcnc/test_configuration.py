"""A LinuxCNC configuration as the ``linuxcnc`` script reads it (:mod:`wavecheck.linuxcnc.configuration`):
a HAL file given alone is read with the INI beside it whose ``HALFILE`` names it, or with the INI
given as a second file (either order, before or after the options); no refusal advises an
option that does not exist (issue 32, class 6)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.guarantee import FirmwareConfig

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
LCNC = CORPUS / "linuxcnc/configs"
FLUIDNC = CORPUS / "fluidnc/official/6_pack_TMC2130_XYZ.yaml"


def test_a_hal_file_alone_is_read_with_the_ini_naming_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Gecko_540B3.hal refers to [EMCMOT] values: it was refused with 'give --ini FILE', an option
    `config` does not have. The INI beside it whose HALFILE names it is read."""
    hal = LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.hal"
    code = main(["config", str(hal), "--drive", "gecko-g540", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    assert code in (0, 1, 3)
    assert any(n.startswith("a HAL file given alone: read with") for n in doc["notes"])


def test_a_hal_file_named_by_several_inis_asks_for_one(tmp_path: Path) -> None:
    src = LCNC / "by_machine/sherline/Sherline4Axis"
    with pytest.raises(ConfigError, match="2 INIs beside it") as err:
        read_firmware(src / "stepper_xyza.hal")
    assert "--ini" not in str(err.value) and "Sherline4Axis_mm.ini" in str(err.value)


SHERLINE = LCNC / "by_machine/sherline/Sherline4Axis"


def _figures(doc: dict[str, object]) -> object:
    return doc["axes"], doc["pairs"], doc["exit_code"]


@pytest.mark.parametrize("order", ["hal ini", "ini hal", "hal --drive ini"])
def test_a_hal_file_with_its_ini_as_a_second_file(
    capsys: pytest.CaptureFixture[str], order: str
) -> None:
    """stepper_xyza.hal is named by two INIs beside it: `config` refused it and took no second
    file. Given with Sherline4Axis_inch.ini (either order, also after the options: `config HAL
    --drive X INI` was refused as an unrecognised argument), it reads what the INI alone gives:
    the INI's [HAL] HALFILE runs it."""
    hal, ini = str(SHERLINE / "stepper_xyza.hal"), str(SHERLINE / "Sherline4Axis_inch.ini")
    drive = ["--drive", "gecko-g540", "--format", "json"]
    argv = {"hal ini": [hal, ini, *drive], "ini hal": [ini, hal, *drive],
            "hal --drive ini": [hal, *drive, ini]}[order]  # fmt: skip
    code = main(["config", *argv])
    doc = json.loads(capsys.readouterr().out)
    assert code in (0, 1, 3)
    assert any("read with the INI given" in n for n in doc["notes"])
    main(["config", str(ini), "--drive", "gecko-g540", "--format", "json"])
    assert _figures(doc) == _figures(json.loads(capsys.readouterr().out))


def test_the_several_inis_refusal_advises_a_command_that_works(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(ConfigError) as err:
        read_firmware(SHERLINE / "stepper_xyza.hal")
    advised = str(err.value).split("(wavecheck config ", 1)[1].split(" …)")[0].split()
    code = main(["config", *(str(SHERLINE / f) for f in advised), "--drive", "gecko-g540"])
    assert code in (0, 1, 3), capsys.readouterr().err


def test_an_ini_that_does_not_run_the_hal_file_only_gives_its_values(tmp_path: Path) -> None:
    """As `halcmd -i INI -f HAL` (LinuxCNC/linuxcnc:scripts/linuxcnc.in @ 013b2f9, step 4.3.6
    runs each HALFILE that way): the HAL file alone, its [EMCMOT]BASE_PERIOD references
    resolved from the INI given; the INI's own HALFILEs (which name another file) not read."""
    src = LCNC / "by_interface/parport/gecko/Gecko_540B3"
    shutil.copy(src / "Gecko_540B3.hal", tmp_path)
    cfg = read_firmware(tmp_path / "Gecko_540B3.hal", ini=src / "Gecko_540B3.ini")
    assert cfg.files == (str(tmp_path / "Gecko_540B3.hal"), str(src / "Gecko_540B3.ini"))
    assert any("do not name it" in n for n in cfg.notes) and cfg.axes
    whole = read_firmware(src / "Gecko_540B3.ini")

    def values(c: FirmwareConfig) -> list[tuple[object, ...]]:
        return [(a.axis, a.pulse.value, a.idle.value, a.dir_setup.value, a.max_rate.value)
                for a in c.axes]  # fmt: skip

    assert values(cfg) == values(whole)[: len(cfg.axes)]


@pytest.mark.parametrize(
    ("first", "second", "message"),
    [
        (SHERLINE / "stepper_xyza.hal", SHERLINE / "standard_pinout.hal", "two HAL files"),
        (SHERLINE / "Sherline4Axis_mm.ini", SHERLINE / "Sherline4Axis_inch.ini", "two INIs"),
        (FLUIDNC, SHERLINE / "Sherline4Axis_mm.ini", "read only with a LinuxCNC HAL file"),
    ],
)
def test_a_second_file_that_is_not_the_hal_files_ini_is_refused(
    capsys: pytest.CaptureFixture[str], first: Path, second: Path, message: str
) -> None:
    code = main(["config", str(first), str(second), "--drive", "gecko-g540"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_a_hal_file_without_its_ini_never_advises_a_missing_option(tmp_path: Path) -> None:
    shutil.copy(LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.hal", tmp_path)
    with pytest.raises(ConfigError) as err:
        read_firmware(tmp_path / "Gecko_540B3.hal")
    assert "--ini" not in str(err.value) and "give the INI" in str(err.value)
