#!/usr/bin/python3
"""structure_check: the shape of the code, checked: no circle of calls among the solver library's files, and no
function longer than a reader can hold.

  tools/structure_check.py --library build/libsurge_sim.a --sources sim stream render apps \\
      [--allow tests/structure_allow.txt] [--graph-dot graph.dot] [--root .] [--max-lines 100]

1. Calls between files. The library's member objects are read with `nm -P` (binutils): each undefined symbol of a
   member that another member defines is an edge from the first file to the second (calls and data references
   alike). Strongly connected components of more than one file are cycles: a set of files that all reach each
   other, none of which can be read, tested or moved without the others. The tool prints the edge list (with how
   many symbols each edge carries), each cycle's files and the edges inside it with their symbols, and with
   --graph-dot the graph as Graphviz dot text (cycles' files and edges drawn red).
   A member is named by its source file when the source folders hold exactly one file of its name (sim/src/run.c
   for run.c.o), or, where several do, the one whose functions the member defines; otherwise by its own name less
   ".o" (run.c; a second member of the same name is run.c#2).

2. Function length. Every .c and .h file under the source folders (or named as a file) is read for function
   definitions in the code's style: the signature starts at column 0 with the return type (static inline helpers
   in headers too) and the body ends with a `}` at column 0. A function's length counts its lines from the
   signature line to the closing brace, both included. One over --max-lines (100) is a violation unless the
   comment directly above it (no blank line between) says why, with the marker `long function:` and a reason:

       /* long function: one pass over the pairs; splitting it would re-read every neighbour list */

3. Known violations. --allow names a file of violations that do not fail the check, one a line (`#` starts a
   comment):

       cycle sim/src/run.c sim/src/sim.c          (a cycle's files, any order: exactly that component)
       function sim/src/run.c:run_simulation      (file:function)

   The check fails on a violation the file does not name, and on a line that names no violation any more: the
   list can only shrink as the code is restructured, and says exactly what is left.

Files are named relative to --root (default: the current folder). Exit status: 0 all well, 1 a violation (or a
stale line of the allow file), 2 bad input (named on stderr). Standard library and `nm` only.
"""
import argparse
import os
import re
import subprocess
import sys

PROGRAM = "structure_check"
MARKER = "long function:"
SOURCE_SUFFIXES = (".c", ".h")
# nm's letters for symbols a member defines (uppercase: global; u: GNU unique) and for those it needs
DEFINED_TYPES = set("ABCDGRSTVWiu") - {"U"}
UNDEFINED_TYPES = {"U", "w", "v"}
NOT_FUNCTION_NAMES = {"if", "for", "while", "switch", "return", "sizeof", "__attribute__", "__declspec",
                      "_Alignas", "alignas", "_Static_assert", "static_assert", "defined", "void", "char", "short",
                      "int", "long", "float", "double", "signed", "unsigned", "const", "volatile", "static", "inline",
                      "extern", "struct", "union", "enum", "_Bool", "restrict"}


class BadInput(Exception):
    """Input the tool cannot check: exit status 2 with this message."""


# ----------------------------------------------------------------------------------------------------------------
# The library's members and the file-level graph


def read_members(library):
    """[(member name, defined global symbols, undefined symbols, local text symbols)] of a static library, in
    archive order (two members of the same name stay apart), from `nm -P`."""
    if not os.path.isfile(library):
        raise BadInput("%s: no such library file" % library)
    try:
        done = subprocess.run(["nm", "-P", library], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True)
    except OSError as error:
        raise BadInput("cannot run nm (binutils): %s" % error)
    if done.returncode != 0:
        raise BadInput("%s: nm failed: %s" % (library, done.stderr.strip() or "exit status %d" % done.returncode))
    members = []
    header = re.compile(r"^.*\[([^\]]+)\]:\s*$")
    current = None
    for line in done.stdout.splitlines():
        if not line.strip():
            continue
        found = header.match(line)
        if found:
            current = (found.group(1), set(), set(), set())
            members.append(current)
            continue
        fields = line.split()
        if current is None or len(fields) < 2:
            if line.endswith(":"):
                raise BadInput("%s: not a static library (nm lists no archive members)" % library)
            continue
        name, kind = fields[0], fields[1]
        if kind in UNDEFINED_TYPES:
            current[2].add(name)
        elif kind in DEFINED_TYPES:
            current[1].add(name)
        elif kind == "t":
            current[3].add(name.split(".")[0])
    if not members:
        raise BadInput("%s: not a static library with object members" % library)
    return members


def build_graph(members):
    """(edges {(from index, to index): sorted symbols}, symbols defined by more than one member) of the members:
    an edge for every undefined symbol of one member that another defines."""
    definer = {}
    duplicates = {}
    for index, (_, defined, _, _) in enumerate(members):
        for symbol in defined:
            if symbol in definer and definer[symbol] != index:
                duplicates.setdefault(symbol, {definer[symbol]}).add(index)
            else:
                definer[symbol] = index
    edges = {}
    for index, (_, _, undefined, _) in enumerate(members):
        for symbol in undefined:
            target = definer.get(symbol)
            if target is not None and target != index:
                edges.setdefault((index, target), []).append(symbol)
    return {edge: sorted(symbols) for edge, symbols in edges.items()}, duplicates


def strongly_connected(count, edges):
    """The strongly connected components of the graph on nodes 0..count-1 (Tarjan's algorithm, iterative)."""
    successors = [[] for _ in range(count)]
    for source, target in sorted(edges):
        successors[source].append(target)
    index_of, low, on_stack, stack, components = {}, {}, set(), [], []
    counter = 0
    for root in range(count):
        if root in index_of:
            continue
        work = [(root, 0)]
        while work:
            node, position = work.pop()
            if position == 0:
                index_of[node] = low[node] = counter
                counter += 1
                stack.append(node)
                on_stack.add(node)
            descended = False
            for next_position in range(position, len(successors[node])):
                successor = successors[node][next_position]
                if successor not in index_of:
                    work.append((node, next_position + 1))
                    work.append((successor, 0))
                    descended = True
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index_of[successor])
            if descended:
                continue
            if low[node] == index_of[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                components.append(component)
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
    return components


# ----------------------------------------------------------------------------------------------------------------
# Source files and their functions


def source_files(paths, root):
    """Sorted (shown name, path) of the .c and .h files under the given folders and of the files given."""
    found = {}
    for path in paths:
        if os.path.isfile(path):
            if not path.endswith(SOURCE_SUFFIXES):
                raise BadInput("%s: not a .c or .h file" % path)
            found[os.path.normpath(path)] = True
        elif os.path.isdir(path):
            for folder, subfolders, files in os.walk(path):
                subfolders.sort()
                for name in files:
                    if name.endswith(SOURCE_SUFFIXES):
                        found[os.path.normpath(os.path.join(folder, name))] = True
        else:
            raise BadInput("%s: no such source folder or file" % path)
    return sorted((shown_name(path, root), path) for path in found)


def shown_name(path, root):
    """path relative to root, with forward slashes."""
    return os.path.relpath(os.path.abspath(path), os.path.abspath(root)).replace(os.sep, "/")


def strip_comments(text):
    """(code lines, comment-only flags, comment text per line): the text with comments, string and character
    literals blanked (line breaks kept), whether each line holds a comment and no code, and each line's comment
    text."""
    code, comments, touched = [], [], []
    line_code, line_comment = [], []
    state = None  # None, "block", "line", '"', "'"
    line_touched = False  # the line holds (part of) a comment
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        nxt = text[i + 1] if i + 1 < n else ""
        if c == "\n":
            code.append("".join(line_code))
            comments.append("".join(line_comment))
            touched.append(line_touched)
            line_code, line_comment = [], []
            if state == "line":
                state = None
            line_touched = state == "block"
            i += 1
            continue
        if state is None:
            if c == "/" and nxt == "*":
                state, i, line_touched = "block", i + 2, True
                line_code.append("  ")
                continue
            if c == "/" and nxt == "/":
                state, i, line_touched = "line", i + 2, True
                line_code.append("  ")
                continue
            if c in "\"'":
                state = c
            line_code.append(c)
        elif state == "block":
            if c == "*" and nxt == "/":
                state, i = None, i + 2
                line_code.append("  ")
                continue
            line_comment.append(c)
            line_code.append(" ")
        elif state == "line":
            line_comment.append(c)
            line_code.append(" ")
        else:  # inside a string or character literal
            if c == "\\" and nxt and nxt != "\n":
                line_code.append("  ")
                i += 2
                continue
            if c == state:
                state = None
                line_code.append(c)
            else:
                line_code.append(" ")
        i += 1
    code.append("".join(line_code))
    comments.append("".join(line_comment))
    touched.append(line_touched)
    comment_only = [t and not c.strip() for c, t in zip(code, touched)]
    return code, comment_only, comments


def function_name(signature):
    """The name of the function a signature defines: the identifier before the first '(' that opens the parameters
    (past attributes)."""
    for found in re.finditer(r"([A-Za-z_]\w*)\s*\(", signature):
        if found.group(1) not in NOT_FUNCTION_NAMES:
            return found.group(1)
    return None


def reason_above(lines, comment_only, comments, start):
    """The reason given with the long-function marker in the comment directly above line index start, or None."""
    block = []
    index = start - 1
    while index >= 0 and comment_only[index]:
        block.append(comments[index])
        index -= 1
    if not block:
        return None
    text = " ".join(part.strip(" *\t") for part in reversed(block))
    at = text.find(MARKER)
    if at < 0:
        return None
    reason = text[at + len(MARKER):].strip(" *\t")
    return reason if re.search(r"\w", reason) else None


def functions_in(path):
    """[(name, first line, last line, reason or None)] of the function definitions of a C file (lines from 1)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            text = handle.read()
    except OSError as error:
        raise BadInput("%s: cannot read: %s" % (path, error.strerror))
    code, comment_only, comments = strip_comments(text)
    found = []
    index = 0
    while index < len(code):
        line = code[index]
        if not line or not (line[0].isalpha() or line[0] == "_") or "(" not in line:
            index += 1
            continue
        # the signature runs until its '{' (a definition) or ';' (a declaration), through at most 20 lines
        signature, end = "", index
        while end < len(code) and end < index + 20:
            signature += " " + code[end]
            if "{" in code[end] or ";" in code[end]:
                break
            end += 1
        head = signature.split("{")[0]
        # a signature holds no '=' (an initialised table does) and is no typedef, struct, union or enum
        is_definition = ("{" in signature and ";" not in head and "=" not in head
                         and not re.match(r"\s*(typedef|struct|union|enum)\b[^(]*\{", signature))
        name = function_name(head) if is_definition else None
        if name is None:
            index += 1
            continue
        close = end
        if not code[end].rstrip().endswith("}") or code[end].count("{") != code[end].count("}"):
            close = end + 1
            while close < len(code) and not code[close].startswith("}"):
                close += 1
            if close == len(code):
                raise BadInput("%s:%d: function %s has no closing '}' at column 0" % (path, index + 1, name))
        found.append((name, index + 1, close + 1, reason_above(code, comment_only, comments, index)))
        index = close + 1
    return found


# ----------------------------------------------------------------------------------------------------------------
# The allow file


def read_allow(path):
    """({frozenset of files: line number} of allowed cycles, {(file, function): line number} of allowed long
    functions) from an allow file."""
    cycles, functions = {}, {}
    try:
        with open(path, encoding="utf-8") as handle:
            lines = handle.read().splitlines()
    except OSError as error:
        raise BadInput("%s: cannot read the allow file: %s" % (path, error.strerror))
    for number, line in enumerate(lines, 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "cycle" and len(words) >= 3 and len(set(words[1:])) == len(words) - 1:
            cycles[frozenset(words[1:])] = number
        elif words[0] == "function" and len(words) == 2 and re.match(r"^[^:]+:[A-Za-z_]\w*$", words[1]):
            functions[tuple(words[1].rsplit(":", 1))] = number
        else:
            raise BadInput("%s:%d: expected 'cycle FILE FILE...' (two files or more) or 'function FILE:NAME', got "
                           "'%s'" % (path, number, line.strip()))
    return cycles, functions


# ----------------------------------------------------------------------------------------------------------------
# Naming members by their source files


def member_names(members, sources, functions_by_file):
    """A name per member: its source file where the source folders tell which, else the member's own name."""
    by_base = {}
    for shown, _ in sources:
        by_base.setdefault(os.path.basename(shown), []).append(shown)
    names = []
    for member, defined, _, local in members:
        base = member[:-2] if member.endswith(".o") else member
        candidates = by_base.get(base, []) or by_base.get(base + ".c", [])
        name = None
        if len(candidates) == 1:
            name = candidates[0]
        elif candidates:
            symbols = defined | local
            scores = sorted(((len(symbols & functions_by_file.get(c, set())), c) for c in candidates), reverse=True)
            if scores[0][0] > 0 and scores[0][0] > scores[1][0]:
                name = scores[0][1]
        names.append(name or base)
    seen = {}
    for index, name in enumerate(names):
        seen[name] = seen.get(name, 0) + 1
        if seen[name] > 1:
            names[index] = "%s#%d" % (name, seen[name])
    return names


# ----------------------------------------------------------------------------------------------------------------


def dot_text(names, edges, in_cycle):
    """The file-level graph as Graphviz dot text; the files and edges of cycles in red."""
    out = ["digraph surge_sim_files {", "  rankdir=LR;", "  node [shape=box, fontname=\"Helvetica\"];"]
    for index, name in sorted(enumerate(names), key=lambda item: item[1]):
        style = ", color=red, fontcolor=red" if index in in_cycle else ""
        out.append("  \"%s\" [label=\"%s\"%s];" % (name, name, style))
    for (source, target), symbols in sorted(edges.items(), key=lambda item: (names[item[0][0]], names[item[0][1]])):
        red = in_cycle.get(source) is not None and in_cycle.get(source) == in_cycle.get(target)
        out.append("  \"%s\" -> \"%s\" [label=\"%d\"%s];" % (names[source], names[target], len(symbols),
                                                             ", color=red" if red else ""))
    out.append("}")
    return "\n".join(out) + "\n"


def main():
    parser = argparse.ArgumentParser(prog=PROGRAM, description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--library", required=True, help="the solver's static library (build/libsurge_sim.a)")
    parser.add_argument("--sources", nargs="+", required=True, metavar="DIR",
                        help="source folders (searched for .c and .h files) or single source files")
    parser.add_argument("--allow", metavar="FILE", help="known violations, one a line (see above)")
    parser.add_argument("--graph-dot", metavar="FILE", help="write the file-level graph as Graphviz dot text")
    parser.add_argument("--root", default=".", help="files are named relative to this folder (default: .)")
    parser.add_argument("--max-lines", type=int, default=100, help="longest function without a reason (100)")
    args = parser.parse_args()
    if args.max_lines < 1:
        parser.error("--max-lines: expected a whole number >= 1, got %d" % args.max_lines)
    if not os.path.isdir(args.root):
        raise BadInput("%s: --root is no folder" % args.root)

    allowed_cycles, allowed_functions = read_allow(args.allow) if args.allow else ({}, {})
    sources = source_files(args.sources, args.root)
    functions = {shown: functions_in(path) for shown, path in sources}
    members = read_members(args.library)
    names = member_names(members, sources, {f: {d[0] for d in defs} for f, defs in functions.items()})
    edges, duplicates = build_graph(members)
    cycles = sorted((sorted(names[i] for i in component), component)
                    for component in strongly_connected(len(members), edges) if len(component) > 1)
    in_cycle = {node: number for number, (_, component) in enumerate(cycles) for node in component}

    violations, stale = [], []
    print("%s: %s, %d files, %d edges (file -> file it calls: symbols)" % (PROGRAM, shown_name(args.library, args.root),
                                                                       len(members), len(edges)))
    for (source, target), symbols in sorted(edges.items(), key=lambda item: (names[item[0][0]], names[item[0][1]])):
        print("  %s -> %s: %d" % (names[source], names[target], len(symbols)))
    linked = {node for edge in edges for node in edge}
    alone = sorted(names[i] for i in range(len(members)) if i not in linked)
    if alone:
        print("  files with no edge: %s" % " ".join(alone))
    for symbol, definers in sorted(duplicates.items()):
        print("note: %s is defined by %s" % (symbol, ", ".join(sorted(names[i] for i in definers))))

    print("cycles (files that all reach each other): %d" % len(cycles))
    for number, (files, component) in enumerate(cycles, 1):
        key = frozenset(files)
        allowed = key in allowed_cycles
        if not allowed:
            violations.append("cycle " + " ".join(files))
        print("  cycle %d (%d files)%s: %s" % (number, len(files), ", allowed" if allowed else "", " ".join(files)))
        members_in = set(component)
        for (source, target), symbols in sorted(edges.items(), key=lambda item: (names[item[0][0]], names[item[0][1]])):
            if source in members_in and target in members_in:
                print("    %s -> %s: %s" % (names[source], names[target], " ".join(symbols)))
    found_cycles = {frozenset(files) for files, _ in cycles}
    for key, line in sorted(allowed_cycles.items(), key=lambda item: item[1]):
        if key not in found_cycles:
            stale.append("%s:%d: cycle %s is no longer a cycle (of exactly these files)"
                         % (args.allow, line, " ".join(sorted(key))))

    long_functions, justified, found_long = [], [], set()
    for shown, _ in sources:
        for name, first, last, reason in functions[shown]:
            length = last - first + 1
            if length <= args.max_lines:
                continue
            if reason:
                justified.append((shown, first, name, length, reason))
                continue
            found_long.add((shown, name))
            long_functions.append((shown, first, name, length, (shown, name) in allowed_functions))
    print("functions over %d lines without a reason ('%s' in the comment above): %d"
          % (args.max_lines, MARKER, len(long_functions)))
    for shown, first, name, length, allowed in long_functions:
        print("  %s:%d: %s, %d lines%s" % (shown, first, name, length, ", allowed" if allowed else ""))
        if not allowed:
            violations.append("function %s:%s" % (shown, name))
    if justified:
        print("functions over %d lines with a reason: %d" % (args.max_lines, len(justified)))
        for shown, first, name, length, reason in justified:
            print("  %s:%d: %s, %d lines: %s" % (shown, first, name, length, reason))
    for key, line in sorted(allowed_functions.items(), key=lambda item: item[1]):
        if key not in found_long:
            stale.append("%s:%d: function %s:%s is no longer over %d lines without a reason (or no longer there)"
                         % (args.allow, line, key[0], key[1], args.max_lines))

    if args.graph_dot:
        try:
            with open(args.graph_dot, "w", encoding="utf-8") as handle:
                handle.write(dot_text(names, edges, in_cycle))
        except OSError as error:
            raise BadInput("%s: cannot write the dot file: %s" % (args.graph_dot, error.strerror))
        print("graph: %s" % args.graph_dot)

    print("summary: %d files in the library, %d edges, %d cycles, %d functions over %d lines (%d with a reason), "
          "%d source files read" % (len(members), len(edges), len(cycles), len(long_functions), args.max_lines,
                                    len(justified), len(sources)))
    for violation in violations:
        print("VIOLATION: %s" % violation)
    for line in stale:
        print("STALE ALLOW LINE (remove it): %s" % line)
    if violations or stale:
        print("%s: FAILED, %d violations not in the allow file, %d stale allow lines"
              % (PROGRAM, len(violations), len(stale)))
        return 1
    print("%s: ok%s" % (PROGRAM, " (the violations above are in %s)" % args.allow
                        if allowed_cycles or allowed_functions else ""))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BadInput as error:
        print("%s: %s" % (PROGRAM, error), file=sys.stderr)
        sys.exit(2)
