"""The exit code of a golden check (generator_test.py, onnx_test.py): each error printed as a FAIL line; without a
planted fault 0 when there is none, 1 otherwise; with one, 0 only when an error caught it (a check that misses a
planted fault fails)."""


def verdict(errors, plant):
    for e in errors:
        print("FAIL:", e)
    failed = bool(errors)
    if plant:
        print(f"planted fault '{plant}': {'caught' if failed else 'NOT caught'}")
        return 0 if failed else 1
    return 1 if failed else 0
