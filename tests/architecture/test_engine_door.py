"""The engine has one front door of about a dozen names (issue 37), and two side doors named
here: code outside ``wavecheck/engine/`` imports the engine's names from ``wavecheck.engine``
(or ``.planning`` / ``.parts``), never from its other modules, so the engine can rearrange its
rooms without touching its users. Tests are exempt: they test the modules themselves."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

import wavecheck.engine as engine

ROOT = Path(__file__).resolve().parents[2]
MODULES = {p.stem for p in (ROOT / "wavecheck" / "engine").glob("*.py")} - {"__init__"}
#: The side doors: modules that only gather names of the rooms for a few users.
SIDE_DOORS = {"planning", "parts"}
#: The front door's size: "a public face of about a dozen names" (issue 37).
FACE_MAX = 13
OUTSIDE = [
    p
    for top in ("wavecheck", "stepgen", "tools", "bench")
    for p in sorted((ROOT / top).rglob("*.py"))
    if not p.relative_to(ROOT).as_posix().startswith("wavecheck/engine/")
]


_SIDE = {f"wavecheck.engine.{m}" for m in SIDE_DOORS}


def _reaches_past(path: Path) -> list[str]:
    """Every engine module ``path`` imports past the door (at any depth)."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.startswith("wavecheck.engine.") and node.module not in _SIDE:
                bad.append(node.module)
            elif node.module == "wavecheck.engine":  # a module taken by name through the door
                bad += [f"wavecheck.engine.{a.name}" for a in node.names if a.name in MODULES]
        elif isinstance(node, ast.Import):
            bad += [
                a.name
                for a in node.names
                if a.name.startswith("wavecheck.engine.") and a.name not in _SIDE
            ]
    return bad


def test_nothing_outside_reaches_past_the_door() -> None:
    bad = {str(p.relative_to(ROOT)): r for p in OUTSIDE if (r := _reaches_past(p))}
    assert len(OUTSIDE) > 150
    assert not bad, f"import these from wavecheck.engine instead: {bad}"


@pytest.mark.parametrize(
    "source",
    [
        "from wavecheck.engine.outcome import Report\n",
        "def f():\n    import wavecheck.engine.run\n",
        "if TYPE_CHECKING:\n    from wavecheck.engine.results import RuleResult\n",
        "from wavecheck.engine import outcome\n",
        "from wavecheck.engine import planning\n",
        "from wavecheck.engine.resolve import plan_axes\n",
    ],
)
def test_the_door_test_sees_a_reach(source: str, tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text(source)
    assert _reaches_past(probe)


def test_through_the_door_is_not_a_reach(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text(
        "from wavecheck.engine import Report, check_source\n"
        "from wavecheck.engine.planning import plan_axes\n"
        "from wavecheck.engine.parts import StepTrace\n"
    )
    assert not _reaches_past(probe)


def test_every_name_of_the_door_opens() -> None:
    """Each name in ``__all__`` loads from the module the door says, and it is that object, even
    after every module is imported (which sets each module on the package by its name)."""
    import importlib

    for module in MODULES:
        importlib.import_module(f"wavecheck.engine.{module}")
    assert not set(engine.__all__) & MODULES  # a name of the door no module shadows

    for name in engine.__all__:
        module = importlib.import_module(f"wavecheck.engine.{engine._FACE[name]}")
        assert getattr(engine, name) is getattr(module, name), name
    assert set(engine.__all__) == set(engine._FACE)


def test_the_front_door_is_about_a_dozen_names() -> None:
    assert len(engine.__all__) <= FACE_MAX, sorted(engine.__all__)


@pytest.mark.parametrize("door", sorted(SIDE_DOORS))
def test_a_side_door_only_gathers_names_of_the_rooms(door: str) -> None:
    """A side door defines nothing of its own (imports from the rooms and ``__all__`` only), gives
    exactly its ``__all__``, and shares no name with the front door."""
    import importlib

    path = ROOT / "wavecheck" / "engine" / f"{door}.py"
    body = ast.parse(path.read_text(encoding="utf-8")).body
    for node in body:
        is_doc = isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
        is_all = isinstance(node, ast.Assign) and [
            getattr(t, "id", None) for t in node.targets
        ] == ["__all__"]
        rooms = isinstance(node, ast.ImportFrom) and (
            node.module == "__future__"
            or (node.module or "").removeprefix("wavecheck.engine.") in MODULES - SIDE_DOORS
        )
        assert is_doc or is_all or rooms, f"{door}.py:{node.lineno} is more than a door"
    module = importlib.import_module(f"wavecheck.engine.{door}")
    given = {
        a.asname or a.name
        for n in body
        if isinstance(n, ast.ImportFrom) and n.module != "__future__"
        for a in n.names
    }
    assert given == set(module.__all__)
    assert not given & set(engine.__all__)


def test_the_door_loads_nothing_until_a_name_is_used() -> None:
    """Importing the door costs no numpy: the names load on first use, as ``wavecheck``'s do."""
    code = "import sys, wavecheck.engine; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_docstring_names_only_modules_that_exist() -> None:
    named = set(re.findall(r":mod:`\.(\w+)`", engine.__doc__ or ""))
    assert named == MODULES, named ^ MODULES
