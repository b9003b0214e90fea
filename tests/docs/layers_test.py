#!/usr/bin/env python3
"""No include runs up a layer: every #include <handemo/...> under include/ against docs/layout.md's floor table.

Usage: layers_test.py SOURCE_DIR [LAYOUT.md]

The table's rows are `| floor | modules | ... |`; floor is a number or `entry`. A module is a folder of
include/handemo/ (its header include/handemo/NAME.hpp belongs to it). A header may include its own module and
modules on lower floors; entry headers may include anything and nothing may include them. Exits 1 naming each
include that runs up or sideways (file:line), each module the table does not place, and each module it places
that does not exist.
"""
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*<handemo/([A-Za-z0-9_]+)(/|\.hpp>)')


def floors(layout):
    table, entry = {}, set()
    for line in layout.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 2 or not (cells[0].isdigit() or cells[0] == "entry"):
            continue
        names = [n.strip() for n in cells[1].split(",") if n.strip()]
        if cells[0] == "entry":
            entry.update(names)
        else:
            for n in names:
                table[n] = int(cells[0])
    return table, entry


def module_of(root, path):
    rel = path.relative_to(root / "include")
    parts = rel.parts
    if parts == ("handemo.hpp",):
        return None, "handemo.hpp"
    if len(parts) == 2 and parts[1].endswith(".hpp"):
        name = parts[1][:-4]
        return name, "handemo/" + parts[1]
    return parts[1], None


def main():
    root = pathlib.Path(sys.argv[1])
    layout = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else root / "docs" / "layout.md"
    table, entry = floors(layout)
    errors = []
    if not table:
        errors.append(f"{layout}: no floor table (| floor | modules | ... |)")
    modules = {p.name for p in (root / "include" / "handemo").iterdir() if p.is_dir()}
    for m in sorted(modules - set(table)):
        errors.append(f"include/handemo/{m}/: module '{m}' has no floor in {layout.name}")
    for m in sorted(set(table) - modules):
        errors.append(f"{layout.name}: module '{m}' has a floor but no folder include/handemo/{m}/")
    for path in sorted((root / "include").rglob("*.hpp")):
        module, header = module_of(root, path)
        is_entry = header in entry or (header == "handemo.hpp")
        if not is_entry and module not in table:
            if module not in modules:
                errors.append(f"{path.relative_to(root)}: header outside every module and not an entry header")
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            target = m.group(1)
            if m.group(2) == ".hpp>" and f"handemo/{target}.hpp" in entry:
                if not is_entry:
                    errors.append(f"{path.relative_to(root)}:{n}: includes the entry header handemo/{target}.hpp")
                continue
            if is_entry or target == module:
                continue
            if target not in table:
                errors.append(f"{path.relative_to(root)}:{n}: includes unknown module '{target}'")
            elif table[target] >= table[module]:
                way = "sideways" if table[target] == table[module] else "up"
                errors.append(f"{path.relative_to(root)}:{n}: {module} (floor {table[module]}) includes {target} "
                              f"(floor {table[target]}): runs {way}")
    for e in errors:
        print(e)
    if errors:
        return 1
    print(f"{sum(1 for _ in (root / 'include').rglob('*.hpp'))} headers, {len(table)} modules on "
          f"{len(set(table.values()))} floors: no include runs up or sideways")
    return 0


if __name__ == "__main__":
    sys.exit(main())
