#!/usr/bin/python3
"""Every citation of a documentation page's section leads somewhere: where a text file of the source tree (code,
comments, tests, docs, cases, tools) cites `PAGE.md, "Title"` (or several titles in a row, a section and its
part), the page exists (beside the citing file, from the tree's root, or under docs/ or docs/validation/) and has a
heading, or a paragraph's bold lead (`**Title ...**`), that starts with each title. Whitespace, line breaks with
their comment marks (#, //, *) and backticks are ignored, so a title may be split over two comment lines.

usage: test_doc_citations.py SOURCE_DIR
"""
import os
import re
import sys

from checks import check, finish, text_files

DOC_SUFFIXES = (".c", ".h", ".py", ".md", ".txt", ".ini", ".cmake", ".sh", ".toml")  # not the data CSVs
# PAGE.md, then one or more quoted titles separated by commas; C strings escape their quotes
CITATION = re.compile(r'([\w./-]+\.md)\\?"?,\s*((?:\\?"[^"\\]{2,200}\\?"(?:,\s*)?)+)')
TITLE = re.compile(r'\\?"([^"\\]{2,200})\\?"')


def normal(text):
    """Text with line breaks (and the comment marks after them), runs of spaces and backticks made one space."""
    text = re.sub(r"\s*\n\s*(?:#|//|\*)?\s*", " ", text)
    return re.sub(r"\s+", " ", text.replace("`", "")).strip()


def anchors(path, cache={}):
    """(headings, bold leads) of a Markdown page, normalised."""
    if path not in cache:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        cache[path] = ([normal(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", text, re.M)],
                       [normal(m.group(1)) for m in re.finditer(r"\*\*([^*]{2,300})\*\*", text)])
    return cache[path]


def broken_citations(root, relpath, text):
    """(citations read, ["FILE:LINE: what is wrong", ...]) for one file's text."""
    read, wrong = 0, []
    for m in CITATION.finditer(text):
        page, line = m.group(1), text.count("\n", 0, m.start()) + 1
        places = [os.path.normpath(os.path.join(root, os.path.dirname(relpath), page))] + \
                 [os.path.join(root, folder, page) for folder in ("", "docs", os.path.join("docs", "validation"))]
        target = next((p for p in places if os.path.isfile(p)), None)
        if target is None:
            wrong.append("%s:%d: cites %s, which is not in the tree" % (relpath, line, page))
            continue
        headings, leads = anchors(target)
        for title in TITLE.findall(m.group(2)):
            read += 1
            title = normal(title)
            if not any(a.startswith(title) for a in headings + leads):
                wrong.append('%s:%d: %s has no heading or bold lead starting "%s"' % (relpath, line, page, title))
    return read, wrong


def main():
    root = os.path.abspath(sys.argv[1])
    # the check itself: a made-up title is caught, a real one (split over comment lines, in a C string) is not
    _, caught = broken_citations(root, "x.c", '(docs/method.md, "A section no page has")')
    check("a citation of a missing section is caught", len(caught) == 1, str(caught))
    read, caught = broken_citations(root, "x.c", '(docs/architecture.md, \\"Threads and\n * determinism\\")')
    check("a citation of a real section passes", read == 1 and not caught, str(caught))
    read, wrong = 0, []
    for path in text_files(root, DOC_SUFFIXES):
        if os.path.abspath(path) == os.path.abspath(__file__):
            continue  # its own examples
        with open(path, encoding="utf-8", errors="replace") as f:
            n, w = broken_citations(root, os.path.relpath(path, root), f.read())
        read, wrong = read + n, wrong + w
    check("citations read (%d)" % read, read > 50, "the source tree at %s cites too few sections" % root)
    check("every cited section exists", not wrong, "\n".join(wrong[:40]))
    return finish()


if __name__ == "__main__":
    sys.exit(main())
