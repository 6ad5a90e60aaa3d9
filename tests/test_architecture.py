"""The house rules of the code, checked on its source.

- ARCHITECTURE.md is the map: every module of the three packages is named in it.
- No private name crosses a module: no ``from m import _name`` of another flexval
  module, and no ``obj._name`` read of a private attribute that only another
  module defines.
- No import circle between flexval's modules, counting the imports inside
  functions (a lazy import is still a dependency).
- The catalogue knows every built-in family by name, the continuum included,
  without a package having to be imported first.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "reducedmodels", "validation")


def _modules() -> dict[str, Path]:
    """Every module of the package by its dotted name (``flexval.x.y``)."""
    found = {"flexval": ROOT / "__init__.py"}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            parts = ("flexval", *path.relative_to(ROOT).with_suffix("").parts)
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


MODULES = _modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8")) for name, path in MODULES.items()}


def _type_checking_nodes(tree: ast.Module) -> set[int]:
    """ids of the nodes under ``if TYPE_CHECKING:`` (imports for annotations only)."""
    return {
        id(sub)
        for node in tree.body
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
        for sub in ast.walk(node)
    }


def _absolute(name: str, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` names, as an absolute dotted name."""
    if node.level == 0:
        return node.module or ""
    base = name.split(".")
    if MODULES[name].name != "__init__.py":
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(name: str) -> list[tuple[str, str | None]]:
    """(module, imported name or None) of every flexval import of module ``name``."""
    tree, out = TREES[name], []
    skip = _type_checking_nodes(tree)
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.ImportFrom):
            target = _absolute(name, node)
            if target.split(".")[0] == "flexval":
                out += [(target, alias.name) for alias in node.names]
        elif isinstance(node, ast.Import):
            out += [(a.name, None) for a in node.names if a.name.split(".")[0] == "flexval"]
    return out


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def test_every_module_is_named_in_the_architecture():
    """Each module by its folder and name (``core/system.py``): names repeat across rooms."""
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    missing = [
        str(path.relative_to(ROOT))
        for package in PACKAGES
        for path in sorted((ROOT / package).rglob("*.py"))
        if path.name != "__init__.py"
        and "__pycache__" not in path.parts
        and f"{path.parent.name}/{path.name}" not in text
    ]
    assert not missing, f"modules ARCHITECTURE.md does not name: {missing}"


MAX_LINES = 800
"""The longest a module may be: beyond it, a module holds more than one idea."""


def test_no_module_is_longer_than_the_limit():
    long = {
        str(path.relative_to(ROOT)): n
        for path in MODULES.values()
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, long


def test_every_package_says_what_it_holds():
    """Every package has a docstring and a curated ``__all__`` of names it has."""
    for name, tree in TREES.items():
        if MODULES[name].name != "__init__.py":
            continue
        assert ast.get_docstring(tree), name
        declared = [
            node
            for node in tree.body
            if isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
        ]
        assert declared, f"{name} has no __all__"


def test_no_module_imports_a_private_name_of_another():
    found = [
        f"{name} imports {target}.{imported}"
        for name in MODULES
        for target, imported in _imports(name)
        if imported is not None and _private(imported) and target != name
    ]
    assert not found, found


def _defined_private_names(tree: ast.Module) -> set[str]:
    """The private names a module defines: functions, classes, assigned names and
    attributes, arguments."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
    return {n for n in names if _private(n)}


def _foreign_private_reads(trees: dict[str, ast.Module]) -> list[str]:
    """Every ``obj._x`` read off anything but ``self``/``cls`` whose ``_x`` only another of
    ``trees``' modules defines."""
    defined = {name: _defined_private_names(tree) for name, tree in trees.items()}
    everywhere = set().union(*defined.values())
    found = []
    for name, tree in trees.items():
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and _private(node.attr)):
                continue
            if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                continue
            if node.attr in everywhere and node.attr not in defined[name]:
                found.append(f"{name}:{node.lineno} reads {ast.unparse(node)}")
    return found


def test_no_module_reads_a_private_attribute_only_another_module_defines():
    """``obj._x`` off anything but ``self``/``cls`` must name an attribute of this module's
    own making (a class of the same module); stdlib privates (``os._exit``) and
    named tuples' ``_replace`` are defined by no flexval module and pass."""
    found = _foreign_private_reads(TREES)
    assert not found, found


def test_the_private_attribute_check_finds_a_foreign_read():
    owner = ast.parse("class A:\n    def __init__(self):\n        self._hidden = 1\n")
    reader = ast.parse("import os\ndef f(a):\n    os._exit(0)\n    return a._hidden\n")
    own = ast.parse("class B:\n    def __init__(self):\n        self._hidden = 2\n")
    own_reader = ast.parse("def g(b):\n    return b._hidden\n")
    assert _foreign_private_reads({"owner": owner, "reader": reader}) == [
        "reader:4 reads a._hidden"
    ]
    both = {"owner": owner, "own": ast.parse(ast.unparse(own) + "\n" + ast.unparse(own_reader))}
    assert _foreign_private_reads(both) == []


def _dependencies() -> dict[str, set[str]]:
    """Each module's flexval modules it imports (a name imported from a package that is a
    module of it counts as that module)."""
    graph = defaultdict(set)
    for name in MODULES:
        for target, imported in _imports(name):
            sub = f"{target}.{imported}"
            module = sub if sub in MODULES else target
            if module in MODULES and module != name:
                graph[name].add(module)
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, stack, on_stack, out, counter = {}, {}, [], set(), [], [0]
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        top = stack.pop()
                        on_stack.discard(top)
                        component.append(top)
                        if top == node:
                            break
                    if len(component) > 1:
                        out.append(sorted(component))
            elif child not in index:
                index[child] = low[child] = counter[0]
                counter[0] += 1
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(sorted(graph[child]))))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return out


def test_no_import_circle():
    assert _circles(_dependencies()) == []


def test_the_circle_finder_finds_a_circle():
    graph = defaultdict(set, {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}})
    assert _circles(graph) == [["a", "b", "c"]]


def test_the_catalogue_knows_every_built_in_family_without_a_package_imported_first():
    code = (
        "import sys, flexval\n"
        "print(flexval.parse_model('continuum:1'), 'flexval.validation.run' in sys.modules)\n"
        "from flexval.reducedmodels.catalogue import families\n"
        "print(' '.join(f.name for f in families()))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.split("\n")
    assert out[0] == "continuum:1 False"  # known by name; the solver not imported
    assert out[1] == "beam prbm dcmm ee continuum"
