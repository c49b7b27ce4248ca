"""The README's one-line command per firmware, run as written on the shared real files."""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import pytest

from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
FW = Path("/work/shared/firmware")
pytestmark = pytest.mark.skipif(not FW.is_dir(), reason="shared firmware files not present")

FILES = {
    "grbl": ["grbl/settings.md"],
    "klipper": ["klipper/generic-bigtreetech-skr-mini-e3-v2.0.cfg"],
    "marlin": ["marlin/VORONDesign/Configuration.h", "marlin/VORONDesign/Configuration_adv.h"],
    "rrf": ["reprapfirmware/cnc-one/config.g"],
    "smoothie": ["smoothieware/Smoothieboard/config"],
    "hm2": ["linuxcnc/hm2-stepper/5i20.ini", "linuxcnc/hm2-stepper/hm2-stepper.hal"],
}
EXPECT = {
    "grbl": "grbl",
    "klipper": "klipper",
    "marlin": "marlin",
    "rrf": "reprapfirmware",
    "smoothie": "smoothieware",
    "hm2": "hm2",
    "linuxcnc": "linuxcnc",
}


@pytest.mark.parametrize("name", sorted(EXPECT))
def test_readme_firmware_command(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    m = re.search(rf"<!-- readme-test: firmware-{name} -->\n```sh\n(.*?)```", text, re.S)
    assert m, f"README has no firmware-{name} block"
    for rel in FILES.get(name, []):
        shutil.copy(FW / rel, tmp_path / Path(rel).name)
    if name == "linuxcnc":  # the README's machine.ini: a software stepgen configuration
        (tmp_path / "machine.hal").write_text(
            "loadrt stepgen step_type=0\nsetp stepgen.0.steplen 5000\nsetp stepgen.0.stepspace 5000\n"
            "setp stepgen.0.dirsetup 20000\nsetp stepgen.0.dirhold 20000\n"
        )
        (tmp_path / "machine.ini").write_text(
            "[EMCMOT]\nBASE_PERIOD = 20000\n[HAL]\nHALFILE = machine.hal\n"
        )
    monkeypatch.chdir(tmp_path)
    argv = shlex.split(m.group(1).strip())
    assert argv[0] == "wavecheck"
    code = main(argv[1:])
    out = capsys.readouterr().out
    assert code in (0, 1, 3)
    assert out.startswith(f"{EXPECT[name]} configuration") and "verdict:" in out
