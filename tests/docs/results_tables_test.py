#!/usr/bin/env python3
"""scripts/results_tables.py on a small report of its own must print exactly fixtures/report/expected.md.
Usage: results_tables_test.py SCRIPT REPORT_DIR"""
import subprocess
import sys

script, report = sys.argv[1], sys.argv[2]
got = subprocess.run([sys.executable, script, report, "hand, 7 folds"], capture_output=True, text=True, check=True).stdout
want = open(f"{report}/expected.md").read()
if got != want:
    print("results_tables.py printed:\n" + got + "\nexpected:\n" + want)
    sys.exit(1)
print("results_tables.py: the expected table")
