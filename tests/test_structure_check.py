#!/usr/bin/python3
"""tools/structure_check.py on a small library built here: it finds a cycle of calls and the long functions (a
multi-line signature, braces in strings and comments, a static inline helper in a header), accepts a reasoned one,
names two objects of the same file name by their folders, keeps the allow file exact (a violation not in it and a
line that no longer occurs both fail), writes the dot graph, and refuses bad input with exit status 2.

usage: test_structure_check.py SOURCE_DIR C_COMPILER AR WORK_DIR
"""
import os
import shutil
import subprocess
import sys

from checks import check, finish

SOURCE, CC, AR, WORK = sys.argv[1:5]
TOOL = os.path.join(SOURCE, "tools", "structure_check.py")


def body(lines):
    """lines statements, one a line."""
    return "".join("    x += %d;\n" % i for i in range(lines))


def function(signature, length, above=""):
    """A function of exactly length lines (signature to closing brace), after the text above."""
    return above + signature + " {\n    int x = 0;\n" + body(length - 4) + "    return x;\n}\n"


FILES = {
    # a.c and b.c call each other; c.c calls a.c only
    "src/a.c": ("int b_value(void);\nint a_value(void) { return 1; }\n"
                "int a_calls_b(void)\n{\n    return b_value();\n}\n"),
    "src/b.c": "int a_value(void);\nint b_value(void) { return a_value() + 1; }\n",
    "src/c.c": "int a_value(void);\nint c_value(void) { return a_value() * 2; }\n",
    # two files named step.c: their objects carry the same member name in the archive
    "src/one/step.c": "int c_value(void);\nint step_one(void) { return c_value(); }\n",
    "src/two/step.c": "int step_two(void) { return 2; }\n",
    "src/long.c": (
        "/* not a function: { } at column 0 in a comment\n}\n*/\n"
        + function("int long_plain(int a,\n               int b)", 110).replace("int x = 0;", "int x = a + b;\n"
                                                                                "    const char *s = \"}{\";\n"
                                                                                "    (void)s;", 1)
        + "\n" + function("int exactly_limit(void)", 100)
        + "\n" + function("int long_reasoned(void)", 150,
                          "/* A table of cases, one line each.\n * long function: one line a case, read top down */\n")
        + "\n" + function("int long_gap(void)", 101, "/* long function: the blank line below parts it */\n\n")
        + "\nstatic const int table[] = {\n" + "    1,\n" * 120 + "};\n"
        + "int use_table(void) { return table[0]; }\n"),
    "src/inline.h": function("static inline int inline_long(void)", 101),
}
ALLOWED = ["cycle src/b.c src/a.c", "function src/long.c:long_plain", "function src/long.c:long_gap",
           "function src/inline.h:inline_long"]


def build():
    """The sources and libstructure.a (members a.c.o, b.c.o, c.c.o, step.c.o twice, long.c.o) in WORK."""
    shutil.rmtree(WORK, ignore_errors=True)
    objects = []
    for name, text in FILES.items():
        path = os.path.join(WORK, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as handle:
            handle.write(text)
        if name.endswith(".c"):
            obj = os.path.join(WORK, "obj", os.path.dirname(name), os.path.basename(name) + ".o")
            os.makedirs(os.path.dirname(obj), exist_ok=True)
            subprocess.run([CC, "-c", "-O1", "-o", obj, path], check=True)
            objects.append(obj)
    library = os.path.join(WORK, "libstructure.a")
    subprocess.run([AR, "qc", library] + objects, check=True)
    return library


def run(*args, allow=None):
    """(exit status, stdout, stderr) of the tool on WORK/src with the given options and allow lines."""
    command = [sys.executable, TOOL, "--root", WORK, "--sources", os.path.join(WORK, "src")] + list(args)
    if allow is not None:
        path = os.path.join(WORK, "allow.txt")
        with open(path, "w") as handle:
            handle.write("# known\n" + "\n".join(allow) + "\n")
        command += ["--allow", path]
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    return done.returncode, done.stdout, done.stderr


library = build()
dot = os.path.join(WORK, "graph.dot")
status, out, err = run("--library", library, "--graph-dot", dot)
check("violations fail", status == 1, "exit status %d\n%s%s" % (status, out, err))
check("the cycle found", "VIOLATION: cycle src/a.c src/b.c\n" in out and out.count("VIOLATION: cycle") == 1, out)
check("long functions found", all("VIOLATION: function src/%s\n" % f in out
                                    for f in ("long.c:long_plain", "long.c:long_gap", "inline.h:inline_long")), out)
# 110 lines as written by function(), one more for its second signature line, two more for the string's
check("long function lines counted", "src/long.c:4: long_plain, 113 lines" in out, out)
check("a reasoned long function passes", "long_reasoned, 150 lines: one line a case, read top down" in out
      and "VIOLATION: function src/long.c:long_reasoned" not in out, out)
check("nothing else", out.count("VIOLATION") == 4 and "exactly_limit" not in out and "table" not in out, out)
check("same-named objects told apart", "  src/one/step.c -> src/c.c: 1\n" in out
      and "files with no edge: src/long.c src/two/step.c\n" in out, out)
check("summary", "summary: 6 files in the library, 4 edges, 1 cycles, 3 functions over 100 lines (1 with a reason)"
      in out, out)
with open(dot) as handle:
    graph = handle.read()
check("dot graph", graph.startswith("digraph") and '"src/a.c" -> "src/b.c" [label="1", color=red];' in graph
      and '"src/c.c" -> "src/a.c" [label="1"];' in graph, graph)

status, out, err = run("--library", library, allow=ALLOWED)
check("the allow file exact: passes", status == 0 and out.rstrip().endswith("allow.txt)"), out + err)
status, out, err = run("--library", library, allow=ALLOWED[:-1])
check("a violation not allowed fails", status == 1 and "VIOLATION: function src/inline.h:inline_long" in out
      and out.count("VIOLATION") == 1, out + err)
status, out, err = run("--library", library, allow=ALLOWED + ["function src/long.c:exactly_limit",
                                                                "cycle src/a.c src/c.c"])
check("stale allow lines fail", status == 1 and "allow.txt:6: function src/long.c:exactly_limit is no longer" in out
      and "allow.txt:7: cycle src/a.c src/c.c is no longer a cycle" in out and "VIOLATION" not in out, out + err)

for name, args, allow, expected in [
        ("malformed allow line", ["--library", library], ["function long.c"], "allow.txt:2: expected"),
        ("a cycle of one file", ["--library", library], ["cycle src/a.c"], "allow.txt:2: expected"),
        ("no library", ["--library", os.path.join(WORK, "none.a")], None, "none.a: no such library file"),
        ("not a library", ["--library", os.path.join(WORK, "src", "a.c")], None, "a.c: nm failed"),
        ("no source folder", ["--library", library, "--sources", os.path.join(WORK, "nowhere")], None,
         "nowhere: no such source folder or file"),
        ("dot file not writable", ["--library", library, "--graph-dot", os.path.join(WORK, "no", "g.dot")], None,
         "g.dot: cannot write the dot file")]:
    status, out, err = run(*args, allow=allow)
    check("bad input: " + name, status == 2 and expected in err and "Traceback" not in err,
          "exit status %d\nstdout: %s\nstderr: %s" % (status, out[-300:], err))

sys.exit(finish())
