#!/usr/bin/python3
"""The product's text speaks to its users about what holds now: no file of the source tree (code, comments, tests,
docs, cases, tools) tells how the work was organised (tracker numbers, counted work periods). How the project got
here is git's history and CHANGELOG.md's.

usage: test_history_words.py SOURCE_DIR
"""
import os
import re
import sys

from checks import check, finish, text_files

# the words, put together from parts so that this file does not hold them; \b keeps identifiers such as Python's
# start_new_session out (an underscore is a word character)
PERIOD, TRACKER = "sess" + "ion", "iss" + "ue"
WORDS = re.compile(r"\b(%ss?|%s\s*#\s*\d+)\b" % (PERIOD, TRACKER), re.IGNORECASE)


def main():
    root = os.path.abspath(sys.argv[1])
    found, scanned = [], 0
    for path in text_files(root):
        scanned += 1
        try:
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, line in enumerate(f, 1):
                    if WORDS.search(line):
                        found.append("%s:%d: %s" % (os.path.relpath(path, root), number, line.strip()[:120]))
        except OSError as e:
            found.append("%s: cannot read (%s)" % (path, e))
    check("text files read (%d)" % scanned, scanned > 100, "the source tree at %s holds too few text files" % root)
    check("no development-history words in the source tree's text", not found, "\n".join(found[:40]))
    return finish()


if __name__ == "__main__":
    sys.exit(main())
