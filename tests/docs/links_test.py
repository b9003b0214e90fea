#!/usr/bin/env python3
"""Every relative link in README.md, CHANGELOG.md and docs/*.md reaches a file, and every #anchor a heading.

Usage: links_test.py SOURCE_DIR [FILE.md ...]

Links are Markdown links and images, [text](target) and ![alt](target), outside code blocks and code spans.
http(s) and mailto links are not followed. An anchor must be the GitHub slug of a heading in the target
Markdown file (or in the same file for a bare #anchor): lower case, punctuation other than - and _ removed,
spaces turned into -, a repeated heading numbered -1, -2, ... Exits 1 naming each broken link as file:line.
"""
import pathlib
import re
import sys

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def prose_lines(text):
    """Yields (line number, line) outside fenced code blocks, with code spans blanked."""
    inside = False
    for n, line in enumerate(text.splitlines(), 1):
        if line.strip().startswith("```"):
            inside = not inside
            continue
        if not inside:
            yield n, re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), line)


def slug(heading):
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link keeps its text
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, result = {}, set()
        inside = False
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.strip().startswith("```"):
                inside = not inside
                continue
            m = None if inside else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m:
                s = slug(m.group(1))
                n = seen.get(s, 0)
                seen[s] = n + 1
                result.add(s if n == 0 else f"{s}-{n}")
        cache[path] = result
    return cache[path]


def check(root, md):
    text = md.read_text(encoding="utf-8")
    for n, line in prose_lines(text):
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                continue  # http:, https:, mailto:
            where = f"{md.relative_to(root)}:{n}"
            file, _, anchor = target.partition("#")
            dest = md if not file else (md.parent / file)
            if file.startswith("/"):
                yield f"{where}: absolute link '{target}'"
                continue
            if not dest.exists():
                yield f"{where}: '{target}': {file} does not exist"
                continue
            if anchor:
                if dest.suffix != ".md":
                    yield f"{where}: '{target}': an anchor into a file that is not Markdown"
                elif anchor not in anchors(dest.resolve()):
                    yield f"{where}: '{target}': no heading with the anchor #{anchor} in {dest.name}"


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    root = pathlib.Path(sys.argv[1]).resolve()
    files = [root / f for f in sys.argv[2:]] or [root / "README.md", root / "CHANGELOG.md",
                                                  *sorted((root / "docs").glob("*.md"))]
    bad = [p for md in files for p in check(root, md)]
    for p in bad:
        print(p)
    print(f"{len(files)} files checked, {len(bad)} broken links")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
