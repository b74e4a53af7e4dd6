"""Print the import graph between gpme's packages (issue 25): which package imports which,
with the count and the first place of each import, inside functions included.

    python tools/import_graph.py            # the package graph and its cycles
    python tools/import_graph.py --edges    # every cross-package import, file:line

Packages: gpme_core (engine) <- gpme_io (model descriptions, run service, writers) <-
crosscheck, gpme_study <- gpme (the command line); gpme_examples sits beside gpme_io.
"""
import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("gpme_core", "gpme_io", "gpme_examples", "crosscheck", "gpme_study", "gpme")


def package_of(module: str):
    top = module.split(".")[0]
    return top if top in PACKAGES else None


def imports(path: Path, package: str):
    """[(imported package, line, inside a function)] of one source file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    out = []
    parents = {}
    for node in ast.walk(tree):
        for child in ast.iter_child_nodes(node):
            parents[child] = node
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:                      # relative: inside the same package
                continue
            names = [node.module or ""]
        for name in names:
            target = package_of(name)
            if target is None or target == package:
                continue
            up, nested = node, False
            while up in parents:
                up = parents[up]
                if isinstance(up, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    nested = True
                    break
            out.append((target, node.lineno, nested))
    return out


def edges():
    """{(from package, to package): [(file, line, nested)]} over every package's files."""
    result = defaultdict(list)
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for target, line, nested in imports(path, package):
                result[(package, target)].append((path.relative_to(ROOT), line, nested))
    return result


def cycles(graph):
    """Package pairs that import each other (both directions present)."""
    return sorted({tuple(sorted(pair)) for pair in graph if pair[::-1] in graph})


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--edges", action="store_true", help="list every import")
    args = parser.parse_args(argv)
    graph = edges()
    for (a, b), places in sorted(graph.items()):
        nested = sum(n for _, _, n in places)
        print(f"{a:14s} -> {b:14s} {len(places):3d} imports ({nested} inside functions)")
        if args.edges:
            for path, line, n in places:
                print(f"    {path}:{line}{' (in a function)' if n else ''}")
    both = cycles(graph)
    print(f"\npackage pairs importing each other: {len(both)}")
    for a, b in both:
        print(f"  {a} <-> {b}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
