"""What the golden checks (generator_test.py, onnx_test.py) share: finding torch, and the exit rule."""

import os
import subprocess
import sys


def import_torch():
    """None when torch imports, else the reason. Debian's python3-torch belongs to the system interpreter, which
    another python3 on PATH may hide: when that one has torch, the running script is executed again under it."""
    try:
        if os.environ.get("HANDEMO_TEST_NO_TORCH"):
            raise ImportError("HANDEMO_TEST_NO_TORCH is set")
        import torch  # noqa: F401
        return None
    except ImportError as e:
        system = "/usr/bin/python3"
        if (not os.environ.get("HANDEMO_TEST_NO_TORCH") and os.path.exists(system)
                and os.path.realpath(sys.executable) != os.path.realpath(system)
                and subprocess.run([system, "-c", "import torch"], capture_output=True).returncode == 0):
            os.execv(system, [system, os.path.abspath(sys.argv[0])] + sys.argv[1:])
        return f"python3 cannot import torch ({e}; ./setup.sh --golden installs python3-torch)"


def verdict(errors, plant):
    """The exit code of a check: each error printed as a FAIL line; without a planted fault 0 when there is none,
    1 otherwise; with one, 0 only when an error caught it (a check that misses a planted fault fails)."""
    for e in errors:
        print("FAIL:", e)
    failed = bool(errors)
    if plant:
        print(f"planted fault '{plant}': {'caught' if failed else 'NOT caught'}")
        return 0 if failed else 1
    return 1 if failed else 0
