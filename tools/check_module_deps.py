#!/usr/bin/env python3
"""Module dependencies of mpmcd: declared (CMakeLists.txt) against used (#include).

Each module is one library, `mpmcd_module(<name> DEPS ...)` in CMakeLists.txt, with sources in
src/<name>/ and headers in include/mpmcd/<name>/ (docs/architecture.md). A file of module A that
includes "mpmcd/B/..." uses B; that is allowed only if B is A itself or among the modules A
declares, directly or through the modules it declares (what its PUBLIC link line makes visible).
The check fails (exit 1) on any undeclared use and on any cycle among the used dependencies, and
prints each offending include with its file and line. A successful run prints the module graph.

Usage:
  tools/check_module_deps.py [SOURCE_DIR]            check (used by ctest: unit_module_dependencies)
  tools/check_module_deps.py [SOURCE_DIR] --mermaid  print the used-dependency graph as Mermaid
"""
import pathlib
import re
import sys

MODULE_CALL = re.compile(r"mpmcd_module\(\s*(\w+)((?:\s+[^)]*)?)\)", re.S)
INCLUDE = re.compile(r'^\s*#\s*include\s+"mpmcd/(\w+)/', re.M)


def declared_modules(root):
    """{module: set of directly declared mpmcd modules} from CMakeLists.txt."""
    text = (root / "CMakeLists.txt").read_text()
    text = re.sub(r"#[^\n]*", "", text)  # comments
    mods = {}
    for m in MODULE_CALL.finditer(text):
        if m.group(1) == "name":  # the function's own definition
            continue
        words = m.group(2).split()
        deps = words[words.index("DEPS") + 1:] if "DEPS" in words else []
        mods[m.group(1)] = {d[len("mpmcd_"):] for d in deps if d.startswith("mpmcd_")}
    return mods


def closure(mods, name, seen=None):
    """The modules `name` may use: itself and everything its declarations reach."""
    seen = set() if seen is None else seen
    if name in seen:
        return seen
    seen.add(name)
    for d in mods.get(name, ()):
        closure(mods, d, seen)
    return seen


def used_modules(root, mods):
    """[(module, used module, file, line)] for every #include "mpmcd/<module>/..." of a module."""
    uses = []
    for mod in mods:
        for folder in (root / "src" / mod, root / "include" / "mpmcd" / mod):
            if not folder.is_dir():
                continue
            for f in sorted(folder.rglob("*")):
                if f.suffix not in (".cpp", ".hpp", ".h"):
                    continue
                text = f.read_text(errors="replace")
                for m in INCLUDE.finditer(text):
                    used = m.group(1)
                    if used in mods and used != mod:
                        line = text.count("\n", 0, m.start()) + 1
                        uses.append((mod, used, f.relative_to(root), line))
    return uses


def find_cycle(graph):
    """A list of modules forming a cycle in {module: set of used modules}, or None."""
    state = {}

    def visit(n, path):
        state[n] = 1
        for d in sorted(graph.get(n, ())):
            if state.get(d) == 1:
                return path[path.index(d):] + [d]
            if d not in state:
                c = visit(d, path + [d])
                if c:
                    return c
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state:
            c = visit(n, [n])
            if c:
                return c
    return None


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    root = pathlib.Path(args[0] if args else pathlib.Path(__file__).resolve().parent.parent)
    mods = declared_modules(root)
    if not mods:
        print(f"{root / 'CMakeLists.txt'}: no mpmcd_module(...) declarations found")
        return 1
    uses = used_modules(root, mods)
    graph = {m: set() for m in mods}
    for mod, used, _, _ in uses:
        graph[mod].add(used)
    if "--mermaid" in argv:
        print("graph BT")
        for mod in sorted(graph):
            for used in sorted(graph[mod]):
                print(f"  {mod} --> {used}")
        return 0
    bad = [(mod, used, f, line) for mod, used, f, line in uses
           if used not in closure(mods, mod)]
    for mod, used, f, line in bad:
        declared = " ".join(sorted(mods[mod])) or "nothing"
        print(f"{f}:{line}: module '{mod}' includes mpmcd/{used}/ but declares only "
              f"{declared} (CMakeLists.txt: mpmcd_module({mod} DEPS ...))")
    cycle = find_cycle(graph)
    if cycle:
        print("cycle among the modules' includes: " + " -> ".join(cycle))
    if bad or cycle:
        return 1
    for mod in sorted(graph):
        print(f"{mod}: uses {' '.join(sorted(graph[mod])) or '-'}")
    print(f"{len(uses)} includes across {len(mods)} modules: all declared, no cycle")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
