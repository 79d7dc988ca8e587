"""The parameter set of a surge run folder: RUN_DIR/params.ini, the full resolved parameters that `surge run` writes
next to its outputs (it reloads as a case file), with '# derived:' header lines (h_m, c0_mps, particle counts).

    params = RunParams(run_dir)          # ParamsError if missing or unreadable
    dp = params.real("numerics", "dp_m")  # ParamsError naming the file, section and key if absent or not a number
    params.positive("numerics", "ch"); params.flag("walls", "upstream"); params.derived("c0_mps")

Shared by the analysis tools so that each reads the file the same way and fails with the same clear message."""
import configparser
import math
import os
import re


class ParamsError(ValueError):
    """params.ini is missing or unreadable, or lacks a value the tool needs; the message names file and key."""


class RunParams:
    def __init__(self, run_dir_or_file):
        """A run folder (its params.ini is read) or any case file."""
        self.path = run_dir_or_file
        if os.path.isdir(run_dir_or_file):
            self.path = os.path.join(run_dir_or_file, "params.ini")
            if not os.path.isfile(self.path):
                raise ParamsError("%s: no params.ini (not a surge run folder?)" % run_dir_or_file)
        try:
            with open(self.path) as f:
                self.text = f.read()
        except (OSError, UnicodeDecodeError) as e:
            raise ParamsError("cannot read %s: %s" % (self.path, e))
        self.ini = configparser.ConfigParser(interpolation=None, inline_comment_prefixes=("#", ";"))
        try:
            self.ini.read_string(self.text, source=self.path)
        except configparser.Error as e:
            raise ParamsError("cannot read %s: %s" % (self.path, str(e).splitlines()[0]))

    def has(self, section, key):
        return self.ini.has_option(section, key)

    def _text(self, section, key, default):
        if self.ini.has_option(section, key):
            return self.ini.get(section, key)
        if default is None:
            raise ParamsError("%s: missing [%s] %s" % (self.path, section, key))
        return None

    def real(self, section, key, default=None):
        """[section] key as a finite float; default (when given) where the key is absent."""
        text = self._text(section, key, default)
        if text is None:
            return float(default)
        try:
            value = float(text)
        except ValueError:
            raise ParamsError("%s: [%s] %s = %r is not a number" % (self.path, section, key, text))
        if not math.isfinite(value):
            raise ParamsError("%s: [%s] %s = %r is not finite" % (self.path, section, key, text))
        return value

    def positive(self, section, key):
        """[section] key as a finite float > 0."""
        value = self.real(section, key)
        if value <= 0:
            raise ParamsError("%s: [%s] %s = %g must be > 0" % (self.path, section, key, value))
        return value

    def word(self, section, key, default=None):
        """[section] key as text (an enumeration's value, say: 'implicit'); default where the key is absent."""
        text = self._text(section, key, default)
        return default if text is None else text.strip()

    def flag(self, section, key, default=None):
        """[section] key as a boolean (true/false, 1/0, yes/no, on/off); default where the key is absent."""
        text = self._text(section, key, default)
        if text is None:
            return bool(default)
        word = text.strip().lower()
        if word not in ("true", "false", "1", "0", "yes", "no", "on", "off"):
            raise ParamsError("%s: [%s] %s = %r is not a boolean" % (self.path, section, key, text))
        return word in ("true", "1", "yes", "on")

    def derived(self, name):
        """A value of the '# derived:' header lines (e.g. 'c0_mps', 'h_m', 'fluid particles') as a float."""
        for line in self.text.splitlines():
            if line.startswith("# derived:"):
                found = re.search(r"[:,]\s*%s = ([-+0-9.eE]+)" % re.escape(name), line)
                if found:
                    return float(found.group(1))
        raise ParamsError("%s: no derived value '%s' in the header" % (self.path, name))
