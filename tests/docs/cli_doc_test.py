#!/usr/bin/env python3
"""docs/cli.md lists every subcommand and every option of the built `handemo` command.

Usage: cli_doc_test.py HANDEMO_EXECUTABLE DOCS_CLI_MD [--drop-line REGEX]

Runs `handemo --help` and `handemo <sub> [<subsub>] --help` for every subcommand CLI11 lists, reads the long
option names (--iters, --out, ...) from the "Options:" part of each, and checks that docs/cli.md has a heading
`handemo <sub> [<subsub>]` and that each option appears in that heading's section (up to the next heading
naming another command). Exits 1 naming what is missing, 77 (skipped) when the executable cannot run.
--drop-line leaves the lines matching REGEX out of the page first: the test's check that it notices a missing
option.
"""
import re
import subprocess
import sys

SKIP = 77


def run_help(exe, path):
    out = subprocess.run([exe, *path, "--help"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise RuntimeError(f"'{' '.join(['handemo', *path, '--help'])}' exited {out.returncode}: {out.stderr.strip()}")
    return out.stdout


def parse_help(text):
    """Returns (options, subcommands, positionals) of one CLI11 help text."""
    options, subcommands, positionals = [], [], []
    part = None
    for line in text.splitlines():
        head = line.strip()
        if head in ("Options:", "Subcommands:", "Positionals:"):
            part = head[:-1]
            continue
        if not line.startswith("  ") or line.startswith("      "):
            continue  # a continuation line of a description, or text outside a part
        first = line.split()[0]
        if part == "Options":
            options += [n for n in first.split(",") if n.startswith("--") and n not in ("--help",)]
        elif part == "Subcommands":
            subcommands.append(first)
        elif part == "Positionals":
            positionals.append(first)
    return options, subcommands, positionals


def commands(exe, path=()):
    """Yields (path, help text) for the command at path and every subcommand below it."""
    text = run_help(exe, list(path))
    yield tuple(path), text
    for sub in parse_help(text)[1]:
        yield from commands(exe, (*path, sub))


def sections(markdown):
    """Maps 'handemo rcm fit' to the text under a heading naming that command."""
    result, name, body = {}, None, []
    for line in markdown.splitlines():
        m = re.match(r"^#{1,6}\s+`?(handemo(?: [a-z0-9-]+)*)`?\s*$", line)
        if m:
            if name is not None:
                result[name] = "\n".join(body)
            name, body = m.group(1), []
        elif name is not None:
            body.append(line)
    if name is not None:
        result[name] = "\n".join(body)
    return result


def main():
    args = sys.argv[1:]
    drop = None
    if len(args) == 4 and args[2] == "--drop-line":
        drop = re.compile(args[3])
        args = args[:2]
    if len(args) != 2:
        print(__doc__)
        return 2
    exe, doc = args
    try:
        found = list(commands(exe))
    except (OSError, RuntimeError, subprocess.TimeoutExpired) as e:
        print(f"SKIP: cannot run {exe}: {e}")
        return SKIP
    markdown = open(doc, encoding="utf-8").read()
    if drop:
        markdown = "\n".join(l for l in markdown.splitlines() if not drop.search(l))
    secs = sections(markdown)
    problems = []
    for path, text in found:
        options = parse_help(text)[0]
        if not path:
            for o in options:
                if not re.search(re.escape(o) + r"(?![\w-])", markdown):
                    problems.append(f"{doc}: the option {o} of 'handemo' is not mentioned")
            continue
        name = "handemo " + " ".join(path)
        if name not in secs:
            problems.append(f"{doc}: no heading '{name}' (a subcommand of the built CLI)")
            continue
        for o in options:
            if not re.search(re.escape(o) + r"(?![\w-])", secs[name]):
                problems.append(f"{doc}: section '{name}' does not list its option {o}")
    for p in problems:
        print(p)
    print(f"{len(found)} commands checked, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
