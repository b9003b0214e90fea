#!/usr/bin/env python3
"""Every ```sh code block in docs/*.md is run by a test or says why not.

Usage: shell_blocks_test.py DOCS_DIR [RUN_LIST]

A block passes when the non-blank line above its opening fence is `<!-- not run: REASON -->` with a reason,
or when it is listed in RUN_LIST (lines `docs/<page>.md:<line of the fence>`, the blocks a test runs).
Exits 1 naming each unmarked block as file:line.
"""
import pathlib
import re
import sys

MARK = re.compile(r"^<!-- not run: \S.*-->\s*$")


def unmarked(path, listed):
    lines = path.read_text(encoding="utf-8").splitlines()
    inside = False
    for i, line in enumerate(lines):
        fence = line.strip().startswith("```")
        if fence and not inside:
            inside = True
            if line.strip() in ("```sh", "```bash", "```shell"):
                prev = next((l for l in reversed(lines[:i]) if l.strip()), "")
                where = f"{path.parent.name}/{path.name}:{i + 1}"
                if not MARK.match(prev.strip()) and where not in listed:
                    yield where
        elif fence:
            inside = False


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__)
        return 2
    listed = set()
    if len(sys.argv) == 3:
        listed = {l.strip() for l in open(sys.argv[2], encoding="utf-8") if l.strip() and not l.startswith("#")}
    bad = [w for p in sorted(pathlib.Path(sys.argv[1]).glob("*.md")) for w in unmarked(p, listed)]
    for w in bad:
        print(f"{w}: shell block neither run by a test nor marked '<!-- not run: reason -->'")
    print(f"{len(bad)} unmarked shell blocks")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
