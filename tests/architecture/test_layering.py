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
