"""The package structure: dependencies run one way, every module imports on its own, and each
rule is declared once (issue 11)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from wavecheck.rules import RULE_IDS, RULES

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("wavecheck", "stepgen")


def _modules(package: str) -> list[tuple[str, Path]]:
    out = []
    for path in sorted((ROOT / package).rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
        out.append((".".join(parts), path))
    return out


def _imported(path: Path) -> set[str]:
    """Every module name an ``import`` or ``from … import`` in ``path`` names (at any depth)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


@pytest.mark.parametrize("module,path", _modules("wavecheck"), ids=lambda v: str(v))
def test_wavecheck_never_imports_stepgen(module: str, path: Path) -> None:
    bad = sorted(n for n in _imported(path) if n == "stepgen" or n.startswith("stepgen."))
    assert not bad, f"{module} imports {bad}: wavecheck must not depend on stepgen"


def test_the_layering_test_sees_a_stepgen_import(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text("def f():\n    from stepgen.plan import plan\n    return plan\n")
    assert "stepgen.plan" in _imported(probe)


def test_every_module_imports_alone_in_a_fresh_interpreter() -> None:
    modules = [m for pkg in PACKAGES for m, _ in _modules(pkg) if not m.endswith("__main__")]
    script = (
        "import importlib, subprocess, sys\n"
        "bad = []\n"
        "for m in sys.argv[1:]:\n"
        "    r = subprocess.run([sys.executable, '-c', f'import {m}'], capture_output=True, text=True)\n"
        "    if r.returncode:\n"
        "        bad.append(m + ': ' + (r.stderr.strip().splitlines() or ['?'])[-1])\n"
        "print('\\n'.join(bad))\n"
        "sys.exit(1 if bad else 0)\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", script, *modules], capture_output=True, text=True, cwd=ROOT
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert len(modules) > 50


def _literal_rule_ids(node: ast.AST) -> set[str]:
    elts: list[ast.expr] = []
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        elts = list(node.elts)
    elif isinstance(node, ast.Dict):
        elts = [k for k in node.keys if k is not None]
    return {e.value for e in elts if isinstance(e, ast.Constant) and e.value in RULE_IDS}


def test_each_rule_is_declared_once_in_the_rule_table() -> None:
    assert len(RULE_IDS) == len(set(RULE_IDS)) == len(RULES)
    table = ROOT / "wavecheck" / "rules.py"
    declared = [
        n.args[0].value
        for n in ast.walk(ast.parse(table.read_text(encoding="utf-8")))
        if isinstance(n, ast.Call)
        and getattr(n.func, "id", None) == "Rule"
        and n.args
        and isinstance(n.args[0], ast.Constant)
    ]
    assert sorted(declared) == sorted(RULE_IDS)
    # No other module keeps a rival list of the rules (a literal naming five or more of them).
    rivals = []
    for pkg in PACKAGES:
        for module, path in _modules(pkg):
            if path == table:
                continue
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                found = _literal_rule_ids(node)
                if len(found) >= 5:
                    rivals.append(f"{module}:{getattr(node, 'lineno', '?')} {sorted(found)}")
    assert not rivals, "rule lists outside wavecheck/rules.py: " + "; ".join(rivals)


# -- layers: capture → blocks → engine (decode/check) → report → cli; firmware beside; stepgen on top
#: Lowest first. A module may import its own layer and the layers below it, never one above;
#: and the packages of one layer import each other without a circle. Imports inside functions and
#: under ``TYPE_CHECKING`` count: they are dependencies too.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("language", ("wavecheck.record",)),
    ("base", ("wavecheck.errors", "wavecheck.units", "wavecheck.verdict", "wavecheck.timebase",
              "wavecheck.progress", "wavecheck.output", "wavecheck.config_text")),
    ("vocabulary", ("wavecheck.steptypes", "wavecheck.rules")),
    ("drives", ("wavecheck.drives",)),
    ("linuxcnc", ("wavecheck.linuxcnc",)),
    ("capture", ("wavecheck.capture",)),
    ("roles", ("wavecheck.roles",)),
    ("step times", ("wavecheck.lattice",)),
    ("step interface", ("wavecheck.steps",)),
    ("engine", ("wavecheck.engine",)),
    ("options as users spell them", ("wavecheck.options",)),
    ("uses of the engine", ("wavecheck.measurement", "wavecheck.compare", "wavecheck.follow",
                            "wavecheck.step_latency",
                            "wavecheck.crosscheck", "wavecheck.firmware", "wavecheck.mcu")),
    ("report", ("wavecheck.report",)),
    ("entry points", ("wavecheck.api", "wavecheck.live", "wavecheck.cocotb",
                      "wavecheck.pytest_plugin", "wavecheck.sigrok", "wavecheck")),
    ("cli", ("wavecheck.cli", "wavecheck.__main__")),
    ("stepgen", ("stepgen",)),
)  # fmt: skip


def _layer(module: str) -> tuple[int, str]:
    """(layer number, the layer entry it belongs to) of a module name (longest prefix)."""
    best: tuple[int, str] | None = None
    for k, (_, names) in enumerate(LAYERS):
        for n in names:
            if module == n or module.startswith(n + "."):
                if best is None or len(n) > len(best[1]):
                    best = (k, n)
    assert best is not None, f"{module} is in no layer of LAYERS: add it"
    return best


def _deps() -> dict[str, set[str]]:
    """Module → the project modules it imports (at any depth of the file)."""
    mods = {m for pkg in PACKAGES for m, _ in _modules(pkg)}
    out: dict[str, set[str]] = {}
    for pkg in PACKAGES:
        for module, path in _modules(pkg):
            names = set()
            for n in _imported(path):
                # "from wavecheck.engine import axis": the name may be a module itself
                while n and n not in mods:
                    n = n.rpartition(".")[0]
                if n:
                    names.add(n)
            out[module] = names - {module}
    return out


def test_every_module_is_in_a_layer() -> None:
    for pkg in PACKAGES:
        for module, _ in _modules(pkg):
            _layer(module)


def test_no_module_imports_a_higher_layer() -> None:
    bad = []
    for module, names in _deps().items():
        k, _ = _layer(module)
        for n in sorted(names):
            j, _ = _layer(n)
            if j > k:
                bad.append(f"{module} ({LAYERS[k][0]}) imports {n} ({LAYERS[j][0]})")
    assert not bad, "\n".join(bad)


def test_no_circle_between_packages() -> None:
    """The graph of the layers' entries (packages and top-level modules) has no cycle."""
    graph: dict[str, set[str]] = {}
    for module, names in _deps().items():
        a = _layer(module)[1]
        graph.setdefault(a, set()).update(_layer(n)[1] for n in names if _layer(n)[1] != a)
    seen: dict[str, int] = {}  # 1 on the path, 2 done
    path: list[str] = []

    def visit(u: str) -> None:
        seen[u] = 1
        path.append(u)
        for v in sorted(graph.get(u, ())):
            if seen.get(v) == 1:
                raise AssertionError("circle: " + " → ".join([*path[path.index(v) :], v]))
            if v not in seen:
                visit(v)
        path.pop()
        seen[u] = 2

    for u in sorted(graph):
        if u not in seen:
            visit(u)


def test_the_layer_test_sees_an_import_inside_type_checking(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from wavecheck.cli import main\n"
    )
    assert "wavecheck.cli" in _imported(probe)


def _rule_branches(path: Path) -> list[str]:
    """``x == "dir_setup"``, ``r in ("step_high", …)``, ``"step_high" if … else "step_low"``:
    a branch on a rule id (a table keyed by rule id is no branch)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        parts: list[ast.expr] = []
        if isinstance(node, ast.Compare):
            parts = [node.left, *node.comparators]
        elif isinstance(node, ast.IfExp):
            parts = [node.body, node.orelse]
        for p in parts:
            if _literal_rule_ids(p) or (isinstance(p, ast.Constant) and p.value in RULE_IDS):
                out.append(f"{path.relative_to(ROOT)}:{node.lineno}")
                break
    return out


def test_no_module_outside_the_rule_table_branches_on_a_rule_id() -> None:
    """What a rule needs (its pulse level, the events that close it, what the engine holds between
    windows, whether a plan needs it) is declared in wavecheck/rules.py."""
    table = ROOT / "wavecheck" / "rules.py"
    bad = [
        hit
        for pkg in PACKAGES
        for _, path in _modules(pkg)
        if path != table
        for hit in _rule_branches(path)
    ]
    assert not bad, "branches on a rule id: " + ", ".join(bad)
