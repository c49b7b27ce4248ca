"""The rule library: every shipped file loads, key figures match drive-timing.md, bad files fail."""

from __future__ import annotations

import json
import tomllib
from fractions import Fraction
from pathlib import Path

import pytest
import rtoml

from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import list_drives, load_drive, rules_dir
from wavecheck.errors import RuleError

RULE_FILES = sorted(rules_dir().glob("*.toml"))

US = 1000  # ns


def test_rules_dir_is_the_repo_rules_folder() -> None:
    assert rules_dir().name == "rules"
    assert (rules_dir() / "README.md").is_file()


@pytest.mark.parametrize("path", RULE_FILES, ids=lambda p: p.stem)
def test_every_rule_file_loads(path: Path) -> None:
    drive = load_drive(path.stem)
    assert drive.id == path.stem
    assert drive.path == path
    for fig in [*drive.limits.values(), *([drive.max_rate] if drive.max_rate else [])]:
        assert fig.source in drive.sources
    if drive.kind == "preset":
        # config-tool presets; a firmware's built-in default (klipper-default) says so instead
        assert all(f.status in ("preset", "firmware-default") for f in drive.limits.values())


def test_list_drives_covers_every_file() -> None:
    assert [d.id for d in list_drives()] == [p.stem for p in RULE_FILES]


# Values copied by hand from ../shared/reference/drive-timing.md (the independent source):
# id, edge, step_high, step_low, dir_setup, dir_hold (ns; None = not given), max rate (Hz).
REFERENCE: list[
    tuple[str, str, float | None, float | None, float | None, float | None, int | None]
] = [
    ("gecko-g202", "falling", 4.5 * US, 0.5 * US, 1 * US, 20 * US, 200_000),
    # issue 15: firmware-timing.md (Marlin defaults, RRF community table, PncConf DM860T,
    # Klipper default) and drive-timing.md gotcha 5 (DFRobot TB6600 30 us)
    ("a5984", "rising", 1 * US, 1 * US, 400, 400, 500_000),
    ("lv8729", "rising", 500, 500, 500, 500, 1_000_000),
    ("tmc2226", "rising", 100, 100, 100, 100, 5_000_000),
    ("tmc2240", "rising", 100, 100, 100, 100, 5_000_000),
    ("linuxcnc-preset-dm860t", "rising", 5 * US, 5 * US, 5 * US, 5 * US, None),
    ("klipper-default", "rising", 2 * US, 2 * US, 2 * US, 2 * US, None),
    ("dfrobot-dri0043-tb6600", "rising", 30 * US, 30 * US, None, None, None),
    ("xylotex", "rising", 2 * US, 1 * US, 200, 200, None),
    ("leadshine-dm542", "rising", 2.5 * US, 2.5 * US, 5 * US, None, 200_000),
    ("a4988", "rising", 1 * US, 1 * US, 200, 200, 500_000),
    ("gecko-g203v", "rising", 1 * US, 2 * US, 200, 200, 333_000),
    ("gecko-g540", "rising", 1000, 2000, 200, 200, None),  # preset figures only
    ("stepperonline-dm542t", "rising", 2.5 * US, 2.5 * US, 5 * US, None, 200_000),
    ("leadshine-dm556", "rising", 2.5 * US, None, 5 * US, None, 200_000),
    ("leadshine-hbs86h", "rising", 2.5 * US, 2.5 * US, 6 * US, None, None),
    ("tb6600", "rising", 2.2 * US, 2.2 * US, None, None, None),
    ("tb6560", "rising", 30 * US, None, None, None, None),
    ("drv8825", "rising", 1.9 * US, 1.9 * US, 650, 650, 250_000),
    ("drv8834", "rising", 1.9 * US, 1.9 * US, 200, None, None),
    ("drv8884", "rising", 970, 970, 200, 200, 500_000),
    ("drv8886", "rising", 970, 970, 200, 200, 500_000),
    ("drv8880", "rising", 1 * US, 1 * US, None, None, None),
    ("tmc2209", "rising", 100, 100, 20, 20, None),
    ("tmc2208", "rising", 100, 100, 20, 20, None),
    ("tmc2130", "rising", 100, 100, 20, 20, None),
    ("tmc2100", "rising", None, None, 20, 20, None),
    ("tmc5160", "rising", 100, 100, 20, 20, 6_000_000),
    ("teknic-clearpath", "rising", 715, 715, 25, 1 * US, 2_000_000),
    ("novanta-everest", "falling", 5 * US, 5 * US, 1 * US, 20 * US, 100_000),
    ("igus-dryve-d1", "rising", None, None, None, None, 25_000),
    # LinuxCNC presets: steptime = t_active, stepspace = t_idle; falling edge swaps them.
    ("linuxcnc-preset-gecko-202", "falling", 4500, 500, 1000, 20000, None),
    ("linuxcnc-preset-gecko-203v", "rising", 1000, 2000, 200, 200, None),
    ("linuxcnc-preset-xylotex-8s-3", "rising", 2000, 1000, 200, 200, None),
    ("linuxcnc-preset-gecko-201", "rising", 500, 4000, 1000, 20000, None),
    ("linuxcnc-preset-gecko-320", "rising", 3500, 500, 200, 200, None),
    ("linuxcnc-preset-gecko-540", "rising", 1000, 2000, 200, 200, None),
    ("linuxcnc-preset-l297", "rising", 500, 4000, 1000, 4000, None),
    ("linuxcnc-preset-pmdx-150", "rising", 1000, 2000, 1000, 1000, None),
    ("linuxcnc-preset-parker-compumotor-oem750", "rising", 1000, 1000, 200000, 1000, None),
    ("linuxcnc-preset-jvl-smd41", "rising", 500, 500, 2500, 2500, None),
    ("linuxcnc-preset-hobbycnc-pro-chopper", "rising", 2000, 2000, 2000, 2000, None),
    ("linuxcnc-preset-keling-4030", "rising", 5000, 5000, 20000, 20000, None),
    ("linuxcnc-preset-sherline", "rising", 22000, 22000, 100000, 100000, None),
    ("linuxcnc-preset-tb6560", "rising", 5000, 5000, 20000, 20000, None),
    ("linuxcnc-preset-stepcraft", "rising", 1000, 1000, 20000, 20000, None),
]

REQUIRED_IDS = [
    "gecko-g202", "gecko-g203v", "gecko-g540", "xylotex", "leadshine-dm542", "leadshine-dm556",
    "tb6600", "tb6560", "a4988", "drv8825", "drv8834", "drv8884", "tmc2209", "tmc5160",
    "teknic-clearpath", "linuxcnc-preset-gecko-202",
]  # fmt: skip


def test_library_has_the_required_drives() -> None:
    ids = {p.stem for p in RULE_FILES}
    assert set(REQUIRED_IDS) <= ids
    assert len(ids) >= 20


def test_reference_table_covers_every_file() -> None:
    assert {row[0] for row in REFERENCE} == {p.stem for p in RULE_FILES}


@pytest.mark.parametrize(
    ("drive_id", "rule", "status"),
    [
        ("teknic-clearpath", "step_low", "uncertain"),
        ("teknic-clearpath", "step_high", "datasheet"),
        ("teknic-clearpath", "max_rate", "uncertain"),
        ("tmc2209", "step_high", "uncertain"),
        ("tmc5160", "step_high", "uncertain"),
        ("tmc5160", "dir_setup", "datasheet"),
        ("a4988", "max_rate", "uncertain"),
        ("a4988", "step_high", "secondary"),
        ("leadshine-dm556", "dir_setup", "uncertain"),
        ("novanta-everest", "dir_setup", "uncertain"),
        ("gecko-g540", "step_high", "preset"),
        ("gecko-g202", "dir_hold", "datasheet"),
    ],
)
def test_figure_status(drive_id: str, rule: str, status: str) -> None:
    d = load_drive(drive_id)
    fig = d.max_rate if rule == "max_rate" else d.limits[rule]
    assert fig is not None and fig.status == status


def test_uncertain_edges_are_marked() -> None:
    assert load_drive("gecko-g203v").edge_status == "uncertain"
    assert load_drive("gecko-g202").edge_status == "datasheet"
    assert load_drive("tb6600").edge_status == "uncertain"


def test_preset_notes_explain_the_mapping() -> None:
    d = load_drive("linuxcnc-preset-gecko-202")
    assert d.kind == "preset"
    assert any("steptime is step_low" in n for n in d.notes)
    assert "steptime" in d.limits["step_low"].note


@pytest.mark.parametrize(("drive_id", "edge", "high", "low", "setup", "hold", "rate"), REFERENCE)
def test_key_figures_match_reference(
    drive_id: str,
    edge: str,
    high: float | None,
    low: float | None,
    setup: float | None,
    hold: float | None,
    rate: int | None,
) -> None:
    d = load_drive(drive_id)
    assert d.active_edge == edge
    for rule, want in (
        ("step_high", high),
        ("step_low", low),
        ("dir_setup", setup),
        ("dir_hold", hold),
    ):
        got = d.limit_ns(rule)
        assert (got is None and want is None) or got == Fraction(str(want)), (rule, got, want)
    assert (d.max_rate.value if d.max_rate else None) == rate


def test_g202_hold_note_says_from_the_step_edge() -> None:
    d = load_drive("gecko-g202")
    assert "after Step edge" in d.limits["dir_hold"].note
    assert d.complete


def test_load_by_path(tmp_path: Path) -> None:
    src = rules_dir() / "xylotex.toml"
    own = tmp_path / "xylotex.toml"
    own.write_text(src.read_text())
    d = load_drive(str(own))
    assert isinstance(d, Drive) and d.path == own


def test_env_var_adds_a_search_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = (rules_dir() / "xylotex.toml").read_text().replace('"xylotex"', '"my-drive"', 1)
    (tmp_path / "my-drive.toml").write_text(text)
    monkeypatch.setenv("WAVECHECK_RULES", str(tmp_path))
    assert load_drive("my-drive").limit_ns("step_high") == 2000
    assert "my-drive" in [d.id for d in list_drives()]


def test_unknown_id_lists_close_matches() -> None:
    with pytest.raises(RuleError) as exc:
        load_drive("gecko-g20")
    msg = str(exc.value)
    assert "gecko-g202" in msg and "wavecheck drives" in msg and "\n" not in msg


GOOD = """\
id = "mine"
name = "My drive"
kind = "user"
interface = "step-dir"
active_edge = "rising"

[limits.step_high]
value = "2us"
source = "M"
status = "datasheet"

[limits.max_rate]
value = "100 kHz"
source = "M"
status = "secondary"

[sources]
M = "my manual"
"""


def test_good_user_file(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(GOOD)
    d = load_drive(str(path))
    assert d.kind == "user" and d.limit_ns("step_high") == 2000 and d.max_rate is not None
    assert d.max_rate.value == 100_000 and d.edge_status is None and not d.complete


BAD = [
    # (replace this, with this, key expected in the message)
    ('name = "My drive"\n', "", "name"),
    ('kind = "user"', 'kind = "user"\nmaker = "x"', "maker"),
    ('value = "2us"', 'value = "-2us"', "limits.step_high.value"),
    ('value = "2us"', "value = 2", "limits.step_high.value"),
    ('value = "2us"', 'value = "two us"', "limits.step_high.value"),
    ('value = "2us"', 'value = "2 furlongs"', "limits.step_high.value"),
    ('value = "2us"', 'value = "2 kHz"', "limits.step_high.value"),
    ('value = "100 kHz"', 'value = "10us"', "limits.max_rate.value"),
    ('status = "datasheet"', 'status = "datasheat"', "limits.step_high.status"),
    ('interface = "step-dir"', 'interface = "pwm"', "interface"),
    ('active_edge = "rising"', 'active_edge = "up"', "active_edge"),
    ('id = "mine"', 'id = "Mine X"', "id"),  # any valid id is fine for a file given by path
    ("[limits.step_high]", "[limits.step_hi]", "limits.step_hi"),
    (
        'source = "M"\nstatus = "datasheet"',
        'source = "Q"\nstatus = "datasheet"',
        "limits.step_high.source",
    ),
    ('source = "M"\nstatus = "datasheet"', 'status = "datasheet"', "limits.step_high.source"),
    ('status = "datasheet"', 'status = "datasheet"\nnot = "x"', "limits.step_high.not"),
    ("[sources]", "[sourcez]", "sourcez"),
    ('kind = "user"', 'kind = "robot"', "kind"),
    ('value = "2us"', 'value = "2us', None),  # not TOML
]


@pytest.mark.parametrize(("old", "new", "key"), BAD)
def test_malformed_file_names_file_and_key(
    tmp_path: Path, old: str, new: str, key: str | None
) -> None:
    assert old in GOOD
    path = tmp_path / "mine.toml"
    path.write_text(GOOD.replace(old, new, 1))
    with pytest.raises(RuleError) as exc:
        load_drive(str(path))
    msg = str(exc.value)
    assert msg.startswith(f"{path}: ")
    assert "\n" not in msg
    if key is not None:
        assert exc.value.key == key
        assert f": {key}: " in msg


@pytest.mark.parametrize("path", RULE_FILES, ids=lambda p: p.stem)
def test_rtoml_reads_every_rule_file_as_tomllib_does(path: Path) -> None:
    # the library parses with rtoml (start-up, issue 38); tomllib is the reference
    text = path.read_text(encoding="utf-8")
    fast, slow = rtoml.loads(text), tomllib.loads(text)
    assert fast == slow
    assert json.dumps(fast) == json.dumps(slow)  # key order too: tables and figures keep theirs


# TOML that both parsers must refuse; the message is tomllib's ("… (at line L, column C)")
NOT_TOML = [
    'value = "2us',  # unterminated string
    "a = 1\na = 2",  # duplicate key
    "a = ",  # no value
    "[t]\n[t]",  # table defined twice
    "a = 1 b = 2",  # two pairs on one line
    "a = 01",  # leading zero
    "a = 1__0",  # double underscore
    "a = [1, 2",  # unterminated array
    'a = "\\q"',  # unknown escape
    "a = 1979-13-01",  # no month 13
    "a.b = 1\na = 2",  # a table overwritten by a value
    "a = tru",  # not a boolean
]


# TOML 1.1 forms (and a leading byte-order mark) that rtoml reads and tomllib (TOML 1.0) refuses:
# a rule file may use them (rules/README.md)
TOML_11 = [
    ("a = { b = 1, }", {"a": {"b": 1}}),
    ("a = {\n  b = 1 }", {"a": {"b": 1}}),
    ('a = "\\x41\\e"', {"a": "A\x1b"}),
    ("\ufeffa = 1", {"a": 1}),
]


@pytest.mark.parametrize(("text", "data"), TOML_11)
def test_toml_11_forms_are_read(text: str, data: dict[str, object]) -> None:
    with pytest.raises(tomllib.TOMLDecodeError):
        tomllib.loads(text)
    assert rtoml.loads(text) == data


@pytest.mark.parametrize("text", NOT_TOML)
def test_invalid_toml_is_refused_with_tomllibs_message(tmp_path: Path, text: str) -> None:
    with pytest.raises(tomllib.TOMLDecodeError) as ref:
        tomllib.loads(text)
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(RuleError) as exc:
        load_drive(str(path))
    assert str(exc.value) == f"{path}: not valid TOML: {ref.value}"


def test_missing_file_is_a_rule_error(tmp_path: Path) -> None:
    with pytest.raises(RuleError, match="no such rule file"):
        load_drive(str(tmp_path / "nope.toml"))


def test_wheel_ships_the_rules_through_the_package_symlink() -> None:
    # pyproject's package-data takes wavecheck/_rules/*.toml; the symlink must reach rules/.
    link = Path(__file__).resolve().parents[3] / "wavecheck" / "_rules"
    assert link.is_symlink() and link.resolve() == rules_dir().resolve()


@pytest.mark.parametrize("spelling", ["DRV8825", "Drv8825", "drv8825"])
def test_drive_ids_are_case_insensitive(spelling: str) -> None:
    """Issue 34: ``--drive DRV8825`` was refused while the error suggested ``drv8825``."""
    assert load_drive(spelling).id == "drv8825"


def test_a_drive_extends_an_id_in_any_case(tmp_path: Path) -> None:
    own = tmp_path / "mine.toml"
    own.write_text('extends = "GECKO-G202"\nid = "mine"\n')
    assert load_drive(str(own)).limit_ns("step_high") == load_drive("gecko-g202").limit_ns(
        "step_high"
    )


def test_the_cli_takes_a_drive_id_in_capitals() -> None:
    from wavecheck.cli import main

    vcd = Path(__file__).resolve().parents[3] / "captures" / "golden" / "stepgen0.vcd"
    assert main(["check", str(vcd), "--drive", "GECKO-G202", "--format", "json"]) in (0, 1)
    assert main(["check", str(vcd), "--drive", "GECKO-G2O2"]) == 2  # letter O: still unknown
