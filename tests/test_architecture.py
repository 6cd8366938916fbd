"""The package's layers: data flows one way (docs/architecture.md, "Which part may import which"), so a part
imports only parts below it. Read from the source with ``ast``: every import, at any depth, lazy ones included;
only those a type checker alone reads (under ``if TYPE_CHECKING:``) are not dependencies."""

from __future__ import annotations

import ast
from pathlib import Path

import smartllm_local

ROOT = Path(smartllm_local.__file__).parent
#: From the top down; a part may import the parts of any layer below its own, none of its own layer or above.
LAYERS = [
    {"__main__"},
    {"cli"},
    {"report"},
    {"benchmark"},
    {"planner"},
    {"worlds"},
    {"executor"},
    {"plan_language", "scene"},
    {"domain", "goal_language", "provenance"},
    {"robots", "scoring", "files"},
    {"skills"},
    {"world"},
    {"errors", "resources"},
]
RANK = {part: k for k, layer in enumerate(LAYERS) for part in layer}


def _part(module: str) -> str:
    """The top-level part of the package a dotted module name lies in."""
    return module.split(".")[1] if "." in module else "__init__"


def _imports(path: Path, root: Path) -> list[tuple[int, str]]:
    """The package's modules ``path`` imports (line, dotted name), relative imports resolved."""
    module = ".".join(path.relative_to(root.parent).with_suffix("").parts)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    package = package.removesuffix(".__init__")
    found = []
    for node in _nodes(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.append((node.lineno, target))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
    return [(line, name) for line, name in found if name.startswith("smartllm_local.")]


def _nodes(tree: ast.AST):
    """Every node of ``tree`` but those under ``if TYPE_CHECKING:``."""
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, ast.If) and isinstance(child.test, ast.Name) and child.test.id == "TYPE_CHECKING":
            yield from (n for c in child.orelse for n in [c, *_nodes(c)])
            continue
        yield child
        yield from _nodes(child)


def test_every_part_is_in_a_layer():
    parts = {p.stem if p.is_file() else p.name for p in ROOT.iterdir()
             if (p.suffix == ".py" and p.stem != "__init__") or (p.is_dir() and (p / "__init__.py").exists())}
    assert parts == set(RANK), f"parts not in LAYERS: {parts - set(RANK)}; gone: {set(RANK) - parts}"


def violations(root: Path) -> list[str]:
    """Every import of a part by a part of its own layer or one below it."""
    wrong = []
    for path in sorted(root.rglob("*.py")):
        source = _part(".".join(path.relative_to(root.parent).with_suffix("").parts))
        if source == "__init__":
            continue
        for line, target in _imports(path, root):
            part = _part(target)
            if part != source and part != "__init__" and RANK[part] <= RANK[source]:
                wrong.append(f"{path.relative_to(root.parent)}:{line} ({source}) imports {target} ({part})")
    return wrong


def test_no_part_imports_its_own_layer_or_one_above():
    wrong = violations(ROOT)
    assert not wrong, "\n".join(wrong)


def test_the_check_finds_an_import_upwards(tmp_path):
    """The rule is not vacuous: a world module that imported the planner lazily, inside a function, is found."""
    fake = tmp_path / "smartllm_local" / "world"
    fake.mkdir(parents=True)
    (fake / "bad.py").write_text("def f():\n    from ..planner import pipeline\n", encoding="utf-8")
    assert violations(tmp_path / "smartllm_local") == [
        "smartllm_local/world/bad.py:2 (world) imports smartllm_local.planner (planner)"]
