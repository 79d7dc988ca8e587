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


TEXT_SUFFIXES = (".c", ".h", ".py", ".md", ".txt", ".ini", ".cmake", ".sh", ".toml", ".csv")
SKIP_DIRS = {".git", "build", "__pycache__", "runs"}


def text_files(root, suffixes=TEXT_SUFFIXES):
    """Every text file of the source tree at root whose name ends with one of suffixes (and the CMakeLists.txt files
    and the extensionless scripts run and surgectl), skipping .git, build folders, caches and runs/."""
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith("build")]
        for name in files:
            if name.endswith(suffixes) or name in ("CMakeLists.txt", "run", "surgectl"):
                yield os.path.join(folder, name)
