#!/usr/bin/env python3
"""Checks the include graph of src/ against the module table of docs/architecture.md.

Every `#include "X/..."` in src/M/ must name M itself or a module that M depends on, directly or
through the modules it depends on, as the table's "depends on" column states (header-only uses the
diagram allows would be listed in HEADER_ONLY; there are none). The module
graph of the table must have no cycle. Exit status 0 when the code keeps the documented direction,
1 with one line per include that breaks it.

    scripts/check_module_graph.py [REPOSITORY]
"""
import pathlib
import re
import sys

# Header-only uses that the diagram of docs/architecture.md states beside the table (none since the
# reduced model's plain data and integrator became a module of their own, which sweep depends on).
HEADER_ONLY = set()

ROW = re.compile(r"^\| `crackle(?:_(\w+))?[^`]*` \| `(?:src/)?(\w+)` \|.*\| ([^|]*) \|\s*$")
INCLUDE = re.compile(r'^[ \t]*#[ \t]*include[ \t]+"(\w+)/([^"]+)"', re.M)


def module_table(architecture):
    """{module folder: set of modules it depends on} from the table's rows."""
    table = {}
    for line in architecture.read_text().splitlines():
        match = ROW.match(line)
        if match:
            table[match.group(2)] = match.group(3)
    modules = set(table)
    depends = {}
    for module, text in table.items():
        words = set(re.findall(r"[a-z_]+", text))
        depends[module] = {m for m in words & modules if m != module}
    return depends


def closure(depends):
    """{module: every module reachable from it}; raises ValueError on a cycle."""
    reach, state = {}, {}

    def visit(module, path):
        if state.get(module) == "done":
            return reach[module]
        if state.get(module) == "open":
            raise ValueError("the module table has a cycle: " + " -> ".join(path + [module]))
        state[module] = "open"
        seen = set()
        for dep in depends.get(module, ()):
            seen |= {dep} | visit(dep, path + [module])
        state[module] = "done"
        reach[module] = seen
        return seen

    for module in depends:
        visit(module, [])
    return reach


def violations(root):
    depends = module_table(root / "docs" / "architecture.md")
    if not depends:
        return ["docs/architecture.md: no module table found"]
    try:
        reach = closure(depends)
    except ValueError as error:
        return ["docs/architecture.md: " + str(error)]
    found = []
    src = root / "src"
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".hpp", ".cpp"):
            continue
        module = path.relative_to(src).parts[0]
        if module not in depends:
            found.append(f"{path.relative_to(root)}: module '{module}' is not in the table of docs/architecture.md")
            continue
        for match in INCLUDE.finditer(path.read_text()):
            target, header = match.group(1), match.group(2)
            if target not in depends or target == module:
                continue  # not a module of src/ (a system or third-party header), or its own
            if target in reach[module] or (module, f"{target}/{header}") in HEADER_ONLY:
                continue
            line = path.read_text().count("\n", 0, match.start()) + 1
            found.append(f"{path.relative_to(root)}:{line}: includes {target}/{header}, but {module} does not "
                         f"depend on {target} (docs/architecture.md: {module} depends on "
                         f"{', '.join(sorted(depends[module])) or 'no module'})")
    return found


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
    found = violations(root)
    for line in found:
        print(line)
    if not found:
        print(f"check_module_graph: every include of src/ follows the module table ({root / 'docs/architecture.md'})")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
