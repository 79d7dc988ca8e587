#!/usr/bin/python3
"""Checks that the python3 the tests run imports surgepy from this tree's python/surgepy, as tools/setup.sh installs
it (editable), and not another checkout's copy, or none.

    /usr/bin/python3 tests/test_surgepy_installed.py SOURCE_DIR
"""
import os
import sys

from checks import check, finish

source = sys.argv[1]
want = os.path.join(source, "python", "surgepy")
try:
    import surgepy
    where = os.path.dirname(os.path.abspath(surgepy.__file__))
    found = "imports it from %s" % where
except ImportError as e:
    where, found = None, "cannot import it (%s)" % e
check("surgepy is this tree's python/surgepy", where is not None and os.path.samefile(where, want),
      "%s %s; run sh tools/setup.sh from %s" % (sys.executable, found, source))
sys.exit(finish())
