"""The checks ledger the Python tests share.

    from checks import check, finish
    check("toe advances", speed > 0, "speed %g m/s" % speed)   # one line: "NAME: ok", or "NAME: FAILED" and why
    sys.exit(finish())                                          # prints the count; exit status 1 if any failed

The tests import `surgepy` as tools/setup.sh installs it (python/surgepy, editable) and load a tool in tools/ or a
study's driver by its path (load_module); by hand: `/usr/bin/python3 tests/test_x.py ...`.
"""
import importlib.util
import os
import sys

failures = []


def load_module(path):
    """The Python file at path as a module: a study's driver or a tool in tools/, which live outside any package."""
    name = os.path.splitext(os.path.basename(path))[0]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def check(name, ok, detail="", show_detail=False):
    """Prints the check's line (and on failure, or always with show_detail, the detail, indented); records a
    failure; gives ok back."""
    shown = detail and (show_detail or not ok)
    print("%s: %s%s" % (name, "ok" if ok else "FAILED", "\n    " + str(detail).replace("\n", "\n    ") if shown else ""))
    if not ok:
        failures.append(name)
    return bool(ok)


def finish():
    """Prints how many checks failed (naming them) and gives the exit status: 1 if any failed, else 0."""
    if failures:
        print("%d check(s) failed: %s" % (len(failures), ", ".join(failures)))
        return 1
    print("all checks passed")
    return 0
