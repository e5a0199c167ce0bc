#!/usr/bin/env python3
"""Draw emscatter's import graph and check the house rules (issue 16).

Every ``import`` in ``src/emscatter`` — at module level *and* inside functions (a lazy import is
still a dependency) — becomes an arrow between two modules. The rules checked:

* **no circles**: no strongly connected component with more than one module;
* **no upward imports**: every module sits on a floor (:data:`FLOORS`, lowest first); an arrow
  may stay on its floor or go down, never up;
* **no module over** :data:`MAX_MODULE_LINES` lines, **no folder over** :data:`MAX_FOLDER_LINES`
  lines of its own ``.py`` files without subfolders.

Run ``python tools/import_graph.py`` for the summary, ``--check`` to exit 1 on a violation (the
test ``tests/test_architecture.py`` does), ``--dot FILE`` to write a Graphviz drawing.
The package root ``emscatter/__init__.py`` is the public facade: it may import anything, and
nothing inside the package may import it (``__version__`` lives in ``emscatter._version``).
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "src" / "emscatter"
PACKAGE = "emscatter"
MAX_MODULE_LINES = 700
MAX_FOLDER_LINES = 3000

#: Floors, lowest first: a module may import from its own floor or below. The first prefix that
#: matches a module's dotted name (without ``emscatter.``) gives its floor.
FLOORS: list[tuple[str, ...]] = [
    ("_version", "constants", "conventions", "io", "progress", "parallel"),
    ("spectra", "fresnel", "materials", "montecarlo", "plots", "cache", "cache_entries"),
    ("frequency", "kernels", "surfaces"),
    ("scattering", "emissivity"),
    ("solvers.validity", "solvers.quadrature", "solvers.__init__"),
    ("solvers.spm", "solvers.kirchhoff", "solvers.mom", "solvers.mom3d"),
    ("solvers.iem",),
    ("solvers.measured", "solvers.select", "solvers.blend", "solvers.auto_crosspol"),
    ("method_resolution", "api", "emissivity_api", "coherent"),
    ("brdf", "radio", "render"),
    ("validation", "validity_maps", "demo", "warm", "cli", "__main__"),
]


def module_name(path: Path, root: Path = ROOT) -> str:
    rel = path.relative_to(root.parent).with_suffix("")
    parts = list(rel.parts)
    return ".".join(parts)


def _resolve(module: str, is_package: bool, level: int, target: str | None) -> str:
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def collect(root: Path = ROOT) -> tuple[dict[str, Path], dict[str, set[str]]]:
    """Modules (dotted name → file) and arrows (module → modules it imports) inside the package."""
    files = {module_name(p, root): p for p in sorted(root.rglob("*.py"))}
    names = set(files)

    def known(name: str) -> str | None:
        while name:
            if name in names:
                return name
            if name + ".__init__" in names:
                return name + ".__init__"
            name = name.rpartition(".")[0]
        return None

    edges: dict[str, set[str]] = defaultdict(set)
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        pkg_mod = mod[: -len(".__init__")] if is_pkg else mod
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == PACKAGE]
            elif isinstance(node, ast.ImportFrom):
                if node.level == 0:
                    if not (node.module or "").startswith(PACKAGE):
                        continue
                    base = node.module
                else:
                    base = _resolve(pkg_mod, is_pkg, node.level, node.module)
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    targets.append(
                        sub if known(sub) == sub or known(sub) == sub + ".__init__" else base
                    )
            for t in targets:
                k = known(t)
                if k and k != mod:
                    edges[mod].add(k)
    return files, edges


def floor_of(module: str) -> int | None:
    name = module[len(PACKAGE) + 1 :] if module.startswith(PACKAGE + ".") else module
    for i, prefixes in enumerate(FLOORS):
        for p in prefixes:
            if name == p or name.startswith(p + "."):
                return i
    return None


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    nodes = set(edges) | {t for ts in edges.values() for t in ts}
    for start in sorted(nodes):
        if start in index:
            continue
        work = [(start, iter(sorted(edges.get(start, ()))))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def violations(root: Path = ROOT) -> list[str]:
    """Every broken house rule, one line each (empty when the house is in order)."""
    files, edges = collect(root)
    facade = f"{PACKAGE}.__init__"
    problems: list[str] = []
    for mod in sorted(files):
        if mod != facade and floor_of(mod) is None:
            problems.append(f"{mod}: on no floor (add it to FLOORS in tools/import_graph.py)")
    inner = {m: {t for t in ts if t != facade} for m, ts in edges.items() if m != facade}
    for mod, targets in sorted(edges.items()):
        if mod != facade and facade in targets:
            problems.append(
                f"{mod} imports the package facade emscatter/__init__ (import from a module)"
            )
    for comp in circles(inner):
        problems.append("circle: " + " ↔ ".join(comp))
    for mod, targets in sorted(inner.items()):
        fm = floor_of(mod)
        for t in sorted(targets):
            ft = floor_of(t)
            if fm is not None and ft is not None and ft > fm:
                problems.append(f"upward import: {mod} (floor {fm}) → {t} (floor {ft})")
    folder_lines: dict[Path, int] = defaultdict(int)
    for mod, path in files.items():
        n = len(path.read_text(encoding="utf-8").splitlines())
        folder_lines[path.parent] += n
        if n > MAX_MODULE_LINES:
            problems.append(f"{mod}: {n} lines > {MAX_MODULE_LINES}")
    for folder, n in sorted(folder_lines.items()):
        has_sub = any(p.is_dir() and (p / "__init__.py").exists() for p in folder.iterdir())
        if n > MAX_FOLDER_LINES and not has_sub:
            problems.append(
                f"{folder.relative_to(root.parent)}/: {n} lines > {MAX_FOLDER_LINES}, no subfolders"
            )
    return problems


def to_dot(edges: dict[str, set[str]]) -> str:
    lines = ["digraph emscatter {", "  rankdir=BT; node [shape=box, fontsize=9];"]
    for mod, targets in sorted(edges.items()):
        for t in sorted(targets):
            lines.append(f'  "{mod[len(PACKAGE) + 1 :]}" -> "{t[len(PACKAGE) + 1 :]}";')
    lines.append("}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when a rule is broken")
    parser.add_argument("--dot", type=Path, help="write the graph in Graphviz format")
    args = parser.parse_args(argv)
    files, edges = collect()
    n_edges = sum(len(v) for v in edges.values())
    rooms = {p.parent for p in files.values()}
    print(f"{len(files)} modules in {len(rooms)} folders, {n_edges} arrows")
    problems = violations()
    for p in problems:
        print("  " + p)
    print(f"{len(problems)} problem(s)")
    if args.dot:
        args.dot.write_text(to_dot(edges), encoding="utf-8")
    return 1 if (args.check and problems) else 0


if __name__ == "__main__":
    sys.exit(main())
