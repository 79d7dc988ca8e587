"""Checks of the tools' command-line values, shared so that each tool refuses a bad one the same way: argparse
types (a bad value is a usage error naming the option, exit status 2, before any work starts) and fail() for the
errors found later.

    parser.add_argument("--end-s", type=cli_checks.positive)
    parser.add_argument("--png", type=cli_checks.png_file)
    cli_checks.fail("stability_map", "runs/x/diagnostics.csv: no rows")   # one line on stderr, exit status 2
"""
import argparse
import math
import os
import sys


def fail(program, message):
    """One-line error on stderr, exit status 2 (bad input)."""
    print("%s: %s" % (program, message), file=sys.stderr)
    sys.exit(2)


def number(text):
    """A finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected a number, got '%s'" % text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError("expected a finite number, got '%s'" % text)
    return value


def positive(text):
    """A finite number > 0."""
    value = number(text)
    if value <= 0:
        raise argparse.ArgumentTypeError("expected a number > 0, got '%s'" % text)
    return value


def non_negative(text):
    """A finite number >= 0."""
    value = number(text)
    if value < 0:
        raise argparse.ArgumentTypeError("expected a number >= 0, got '%s'" % text)
    return value


def positive_int(text):
    """An integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected an integer, got '%s'" % text)
    if value < 1:
        raise argparse.ArgumentTypeError("expected an integer >= 1, got '%s'" % text)
    return value


def names(choices):
    """A type for comma-separated names, each one of choices; gives the list."""
    def parse(text):
        values = [v.strip() for v in text.split(",") if v.strip()]
        unknown = [v for v in values if v not in choices]
        if not values or unknown:
            raise argparse.ArgumentTypeError("expected comma-separated names among %s, got '%s'"
                                             % (", ".join(choices), text))
        return values
    return parse


def executable(text):
    """An executable file (a program such as build/surge)."""
    if not (os.path.isfile(text) and os.access(text, os.X_OK)):
        raise argparse.ArgumentTypeError("'%s' is not an executable file (build first: sh tools/setup.sh)" % text)
    return text


def folder(text):
    """A folder, existing or to be made: not something else already there."""
    if os.path.lexists(text) and not os.path.isdir(text):
        raise argparse.ArgumentTypeError("'%s' exists and is not a folder" % text)
    return text


def output_file(text):
    """A file to write (a CSV table): its folder exists and it is not itself a folder."""
    parent = os.path.dirname(text) or "."
    if not os.path.isdir(parent):
        raise argparse.ArgumentTypeError("'%s': no folder '%s' to write it in" % (text, parent))
    if os.path.isdir(text):
        raise argparse.ArgumentTypeError("'%s' is a folder" % text)
    return text


def png_file(text):
    """A PNG file to write: its name ends in .png and its folder exists."""
    if not text.lower().endswith(".png"):
        raise argparse.ArgumentTypeError("'%s' does not end in .png" % text)
    return output_file(text)


def endpoint(text):
    """A ZeroMQ endpoint, TRANSPORT://ADDRESS; a bare port means tcp://127.0.0.1:PORT."""
    if text.isdigit():
        return "tcp://127.0.0.1:%s" % text
    if "://" not in text:
        raise argparse.ArgumentTypeError("expected a port or TRANSPORT://ADDRESS (e.g. tcp://127.0.0.1:5555), got "
                                         "'%s'" % text)
    return text


def add_curve_options(parser):
    """--server-key and --key, for a run secured with CURVE (docs/protocol.md)."""
    parser.add_argument("--server-key", metavar="RUN.pub",
                        help="the run's public key file, when it was started with --curve-key")
    parser.add_argument("--key", metavar="CLIENT.key",
                        help="this client's key file (surge keygen); its .pub must be in the run's --curve-clients")


def curve_of(parser, args):
    """The keys of add_curve_options' options for surge_client, or None when neither is given."""
    from . import client as surge_client
    if (args.server_key is None) != (args.key is None):
        parser.error("--server-key and --key go together")
    if args.server_key is None:
        return None
    try:
        return surge_client.curve_keys(args.server_key, args.key)
    except ValueError as e:
        parser.error(str(e))


def run(main):
    """Runs a tool's main() and gives the exit status it returns (None: 0). A reader that stops early (| head)
    ends the tool quietly with status 1: no BrokenPipe traceback, and none again when Python flushes at exit.

    if __name__ == "__main__":
        sys.exit(cli_checks.run(main))
    """
    try:
        status = main()
        sys.stdout.flush()
        return status
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
