"""Walk rigidid's imports (ast) and print import circles and cross-module private imports.

Usage::

    python benchmarks/import_graph.py [--under rigidid.io] [--module-level-only]

Every ``import`` / ``from ... import`` in ``src/rigidid`` is read from the syntax tree, both at
module level and inside functions (``level`` says which). An edge ``a -> b`` means module ``a``
imports module ``b`` (``from rigidid.x import y`` counts as an import of ``rigidid.x.y`` when that
is a module, else of ``rigidid.x``). Printed:

- the import circles (strongly connected components of more than one module) of the module-level
  graph, and of the graph of all imports (module and function level);
- every import of a private name (``_x``) of another module (a package's ``__init__`` importing from
  its own submodules counts as cross-module too).

With ``--under PREFIX`` only circles and private imports that involve a module under PREFIX are
printed. The exit status is 0 whatever is found (this is a report, not a test).
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "src"


def modules(root: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` under ``root/rigidid``."""
    found = {}
    for path in sorted((root / "rigidid").rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


def _absolute(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module a ``from`` import names (relative imports resolved)."""
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    base = base if is_package else base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports(module: str, path: Path, known: dict[str, Path]) -> Iterator[tuple[str, str, bool, int]]:
    """(target module, imported name or "", at module level, line) for every import in `path`."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    top = {id(n) for n in tree.body}
    for stmt in tree.body:  # imports under `if TYPE_CHECKING:` at module level count as module level
        if isinstance(stmt, ast.If):
            top |= {id(n) for n in stmt.body}
    is_package = path.name == "__init__.py"
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("rigidid"):
                    yield alias.name, "", id(node) in top, node.lineno
        elif isinstance(node, ast.ImportFrom):
            target = _absolute(module, is_package, node)
            if not target.startswith("rigidid"):
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in known:
                    yield sub, "", id(node) in top, node.lineno
                else:
                    yield target, alias.name, id(node) in top, node.lineno


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                part = []
                while True:
                    member = stack.pop()
                    on.discard(member)
                    part.append(member)
                    if member == node:
                        break
                if len(part) > 1:
                    out.append(sorted(part))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--under", default="rigidid", help="report only what involves modules under this prefix")
    args = parser.parse_args(argv)
    known = modules(ROOT)
    top_graph: dict[str, set[str]] = {m: set() for m in known}
    all_graph: dict[str, set[str]] = {m: set() for m in known}
    private: list[str] = []
    for module, path in known.items():
        for target, name, at_top, line in imports(module, path, known):
            if target not in known or target == module:
                continue
            all_graph[module].add(target)
            if at_top:
                top_graph[module].add(target)
            hidden = name.startswith("_") and not name.startswith("__")
            if hidden and (module.startswith(args.under) or target.startswith(args.under)):
                private.append(f"{module}:{line} imports {target}.{name}")

    def involved(part: list[str]) -> bool:
        return any(m.startswith(args.under) for m in part)

    def package_of(m: str) -> str:
        return m if known[m].name == "__init__.py" else m.rpartition(".")[0]

    for title, graph in (("module-level", top_graph), ("module- and function-level", all_graph)):
        # a package's __init__ re-exporting its submodules is not a circle of its own
        pruned = {m: {t for t in ts if t != package_of(m)} for m, ts in graph.items()}
        found = [c for c in circles(pruned) if involved(c)]
        print(f"import circles ({title}) under {args.under}: {len(found)}")
        for part in found:
            print("  " + " <-> ".join(part))
    print(f"cross-module private imports under {args.under}: {len(private)}")
    for line in private:
        print("  " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
