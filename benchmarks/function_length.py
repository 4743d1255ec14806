"""Functions over 80 lines of code under src/rigidid (issue 20): docstring, blank and comment lines excluded.

Run: ``python benchmarks/function_length.py [--limit 80] [PATH]``
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "src" / "rigidid"


def code_lines(node: ast.FunctionDef | ast.AsyncFunctionDef, lines: list[str]) -> int:
    """Lines of code of a function (its signature included), without its docstring, blanks and comments."""
    body = node.body
    doc = None
    first = body[0] if body else None
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        doc = (first.lineno, first.end_lineno or first.lineno)
    count = 0
    for number in range(node.lineno, (node.end_lineno or node.lineno) + 1):
        if doc is not None and doc[0] <= number <= doc[1]:
            continue
        text = lines[number - 1].strip()
        if text and not text.startswith("#"):
            count += 1
    return count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("path", nargs="?", type=Path, default=ROOT)
    parser.add_argument("--limit", type=int, default=80)
    args = parser.parse_args()
    rows = []
    for path in sorted(args.path.rglob("*.py")):
        source = path.read_text()
        lines = source.splitlines()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = code_lines(node, lines)
                if n > args.limit:
                    rows.append((n, path.relative_to(args.path.parent), node.name))
    for n, path, name in sorted(rows, reverse=True):
        print(f"{n:5d}  {path}  {name}")
    print(f"{len(rows)} functions over {args.limit} lines of code")


if __name__ == "__main__":
    main()
