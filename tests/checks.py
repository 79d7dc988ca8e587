"""The checks ledger the Python tests share.

    from checks import check, finish
    check("toe advances", speed > 0, "speed %g m/s" % speed)   # one line: "NAME: ok", or "NAME: FAILED" and why
    sys.exit(finish())                                          # prints the count; exit status 1 if any failed
"""
failures = []


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
