#!/usr/bin/env python3
"""No tracked text file talks about how the project is developed or names a machine's absolute path.

Usage: words_test.py SOURCE_DIR ALLOWED_WORDS_FILE [--also FILE]

Greps every file `git ls-files` lists (text files only: a file with a NUL byte or that is not UTF-8 is
skipped) for development-process words (session, issue N, acceptance, product owner, budget, disclosure, the
CEO) and absolute machine paths (/work/, /home/, /tmp/, /root/, /Users/). A hit is allowed when a line of
ALLOWED_WORDS_FILE, `FILE_GLOB | REGEX | REASON`, matches its file and its line. Exits 1 naming each hit as
file:line, 77 (skipped) when git or the repository is not there. --also checks one more file (relative to
SOURCE_DIR) as if it were tracked and not allowed: the test's check that it notices a planted word.
"""
import fnmatch
import re
import subprocess
import sys

PATTERNS = [
    ("session", r"\bsessions?\b"),
    ("issue", r"\bissues?\s*#?\d+|\bissue's\b|\bthe issues?\b"),
    ("acceptance", r"\bacceptance\b"),
    ("product owner", r"\bproduct\s+owners?\b"),
    ("budget", r"\bbudgets?\b"),
    ("disclosure", r"\bdisclosures?\b"),
    ("the CEO", r"\bthe\s+ceo\b"),
    ("machine path", r"(?<![\w.~$/])/(?:work|home|tmp|root|Users)/"),
]
SKIP = 77


def read_allowed(path):
    allowed = []
    for n, line in enumerate(open(path, encoding="utf-8"), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = [p.strip() for p in line.split(" | ")]
        if len(parts) != 3 or not all(parts):
            raise SystemExit(f"{path}:{n}: expected 'FILE_GLOB | REGEX | REASON', found '{line}'")
        allowed.append((parts[0], re.compile(parts[1], re.IGNORECASE)))
    return allowed


def main():
    args = sys.argv[1:]
    also = None
    if len(args) == 4 and args[2] == "--also":
        also, args = args[3], args[:2]
    if len(args) != 2:
        print(__doc__)
        return 2
    root, allowed = args[0], read_allowed(args[1])
    try:
        files = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"SKIP: cannot list the tracked files of {root}: {e}")
        return SKIP
    compiled = [(name, re.compile(rx, re.IGNORECASE)) for name, rx in PATTERNS]
    hits, checked = [], 0
    listed = [f for f in files.decode().split("\0") if f and f != also]
    for rel in listed + ([also] if also else []):
        try:
            data = open(f"{root}/{rel}", "rb").read()
        except OSError:
            continue  # listed but deleted in the work tree
        if b"\0" in data:
            continue
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            continue
        checked += 1
        for n, line in enumerate(text.splitlines(), 1):
            for name, rx in compiled:
                exempt = rel != also and any(fnmatch.fnmatch(rel, g) and a.search(line) for g, a in allowed)
                if rx.search(line) and not exempt:
                    hits.append(f"{rel}:{n}: {name}: {line.strip()[:160]}")
    for h in hits:
        print(h)
    print(f"{checked} text files checked, {len(hits)} hits not in {args[1]}")
    return 1 if hits else 0


if __name__ == "__main__":
    sys.exit(main())
