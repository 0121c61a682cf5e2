"""The one argument parser of the `python -m host_sim` commands (also `micropython -m host_sim`,
which has no argparse).

    P = Parser("calibrate", "FILE.csv [options]", "Calibrate a magnetometer log.")
    P.positional("file", "FILE.csv", "the log", kind="path")
    P.option("--skip", "int", default=0, lo=0, metavar="N", help="ignore the first N rows")
    return P.main(argv, body)      # body(opts) -> exit status; usage errors exit 2

Kinds of option value: "flag" (no value; True when given), "int" (lo/hi bounds), "str",
"path" (non-empty text), "choice" (one of choices=), "decimal" (exact: (mantissa, decimals),
value = mantissa / 10**decimals; lo/hi bounds as ints or decimal text), or a function
text -> value that raises ValueError with the reason. Values may be negative
(`--declination -150`, a positional `-33.9,151.2`): a word is an option only when it starts
with "-" and is not a number; after an option that takes a value the next word is its value
whatever it looks like; `--name=value` works too, and `--` ends the options.

Errors: parse() raises UsageError naming the option and the value; main() prints it as ONE
line, `host_sim <command>: error: <message>`, on stderr and returns 2 (the conventional usage
status; 0 done, 1 refused; 3 an internal error, from host_sim/__main__.py's last resort, which
also turns any other exception into one line). `-h` / `--help` prints help_text(), generated
from the declarations, on stdout and returns 0.
"""
import sys

PROG = "host_sim"
STATUS_OK = 0
STATUS_REFUSED = 1
STATUS_USAGE = 2
_MAX_EXPONENT = 30      # decimal text: a larger exponent is no measurement (1e30000 would
                        # make a 100 kbit integer, 1e999999999 hang): refused as text


class UsageError(Exception):
    """Bad usage or unreadable input: the message names the option or file and the value;
    the command prints it as one line and exits 2."""


def error_line(command, message):
    """The one line a command prints on stderr for `message`."""
    return "%s %s: error: %s" % (PROG, command, message)


def warn(command, message):
    """A warning: one line on stderr (stdout stays parseable, e.g. with --json)."""
    print("%s %s: warning: %s" % (PROG, command, message), file=sys.stderr)


def parse_decimal(text):
    """'-22.800001' -> (-22800001, 6): the exact value as mantissa / 10**decimals.
    Accepts an optional exponent ('1.5e-3', |exponent| <= 30). Raises ValueError on anything
    else (nan, inf, '', '1.2.3', '0x10')."""
    t = text.strip()
    exp = 0
    for e in ("e", "E"):
        if e in t:
            t, ex = t.split(e, 1)
            ds = ex[1:] if ex[:1] in "+-" else ex
            if not ds or not ds.isdigit() or len(ds) > 4:
                raise ValueError("not a number: %r" % text)
            exp = int(ex)
            if exp > _MAX_EXPONENT or exp < -_MAX_EXPONENT:
                raise ValueError("exponent out of range: %r" % text)
    neg = t.startswith("-")
    if t[:1] in "+-":
        t = t[1:]
    if "." in t:
        whole, frac = t.split(".", 1)
    else:
        whole, frac = t, ""
    if not (whole + frac) or not (whole + frac).isdigit():
        raise ValueError("not a number: %r" % text)
    m = int(whole + frac)
    dec = len(frac) - exp
    if dec < 0:
        m *= 10 ** (-dec)
        dec = 0
    return (-m if neg else m), dec


def decimal_text(v):
    """(mantissa, decimals) -> its shortest exact text ('-22.800001', '5', '0.25')."""
    m, d = v
    s = str(-m if m < 0 else m)
    if d:
        s = "0" * (d + 1 - len(s)) + s
        s = (s[:-d] + "." + s[-d:]).rstrip("0").rstrip(".")
    return ("-" if m < 0 else "") + s


def _cmp_decimal(a, b):
    # sign of a - b for (m, d) pairs, exactly
    am, ad = a
    bm, bd = b
    x = am * 10 ** bd - bm * 10 ** ad
    return (x > 0) - (x < 0)


def is_number(word):
    """'-150', '-33.9,151.2', '-.5': words that start like a number (not options)."""
    if word[:1] != "-" or len(word) < 2:
        return False
    c = word[1]
    return c.isdigit() or (c == "." and len(word) > 2 and word[2].isdigit())


class Option:
    def __init__(self, name, kind, default, lo, hi, choices, metavar, help, dest):
        self.name = name
        self.kind = kind
        self.default = default
        self.lo = lo
        self.hi = hi
        self.choices = choices
        self.metavar = metavar
        self.help = help
        self.dest = dest
        self.many = False
        self.short = None
        self.repeat = False

    def convert(self, text):
        """The value of `text`, or UsageError naming the option."""
        k = self.kind
        what = "%s %s" % (self.name, text) if self.name.startswith("-") else "%s %r" % (
            self.metavar, text)
        if k == "str":
            return text
        if k == "path":
            if not text:
                raise UsageError("%s: expected a path, got nothing" % self.name)
            return text
        if k == "choice":
            if text not in self.choices:
                raise UsageError("%s: expected one of %s" % (what, ", ".join(self.choices)))
            return text
        if k == "int":
            t = text.strip()
            body = t[1:] if t[:1] in "+-" else t
            if not body.isdigit():
                raise UsageError("%s: expected an integer%s" % (what, self._bounds()))
            v = int(t)
            if (self.lo is not None and v < self.lo) or (self.hi is not None and v > self.hi):
                raise UsageError("%s: expected an integer%s" % (what, self._bounds()))
            return v
        if k == "decimal":
            try:
                v = parse_decimal(text)
            except ValueError:
                raise UsageError("%s: expected a number%s" % (what, self._bounds()))
            if ((self.lo is not None and _cmp_decimal(v, self.lo) < 0)
                    or (self.hi is not None and _cmp_decimal(v, self.hi) > 0)):
                raise UsageError("%s: expected a number%s" % (what, self._bounds()))
            return v
        try:
            return k(text)
        except ValueError as e:
            raise UsageError("%s: %s" % (what, e))

    def _bounds(self):
        lo, hi = self.lo, self.hi
        if self.kind == "decimal":
            lo = decimal_text(lo) if lo is not None else None
            hi = decimal_text(hi) if hi is not None else None
        if lo is not None and hi is not None:
            return " in %s..%s" % (lo, hi)
        if lo is not None:
            return " >= %s" % lo
        if hi is not None:
            return " <= %s" % hi
        return ""


def _as_decimal(v):
    if v is None or isinstance(v, tuple):
        return v
    if isinstance(v, int):
        return (v, 0)
    return parse_decimal(v)


class Parser:
    """Declarations of one command's options and positionals; parse(argv) -> dict."""

    def __init__(self, command, usage, description="", epilog=""):
        self.command = command
        self.usage = usage
        self.description = description
        self.epilog = epilog
        self.options = []
        self.positionals = []

    def option(self, name, kind="str", default=None, lo=None, hi=None, choices=None,
               metavar=None, help="", dest=None, short=None, repeat=False):
        """Declare `--name` (and `short`, e.g. '-o'); its value goes to opts[dest] (default:
        name without dashes, '-' -> '_'). `default` is used as is (not converted) when the
        option is absent. repeat=True: it may be given again, opts[dest] is the list."""
        if dest is None:
            dest = name.lstrip("-").replace("-", "_")
        if repeat and default is None:
            default = []
        if kind == "flag" and default is None:
            default = False
        if kind == "decimal":
            lo = _as_decimal(lo)
            hi = _as_decimal(hi)
        if metavar is None:
            metavar = "" if kind == "flag" else dest.upper()
        o = Option(name, kind, default, lo, hi, choices, metavar, help, dest)
        o.short = short
        o.repeat = repeat
        self.options.append(o)
        return o

    def positional(self, dest, metavar, help="", kind="str", required=True, default=None,
                   many=False, choices=None):
        """Declare a positional; many=True (the last one only): every remaining word, each
        converted, as a list (empty when none and not required)."""
        if many and default is None:
            default = []
        o = Option(dest, kind, default, None, None, choices, metavar, help, dest)
        o.required = required
        o.many = many
        self.positionals.append(o)
        return o

    def _find(self, name):
        for o in self.options:
            if o.name == name or (o.short is not None and o.short == name):
                return o
        return None

    def parse(self, argv):
        """opts dict (every declared dest; opts['help'] True for -h/--help), or UsageError."""
        opts = {"help": False}
        for o in self.options:
            opts[o.dest] = o.default
        for o in self.positionals:
            opts[o.dest] = o.default
        given = []
        pos = []
        i = 0
        only_pos = False
        while i < len(argv):
            a = argv[i]
            i += 1
            if only_pos or not a.startswith("-") or a == "-" or is_number(a):
                pos.append(a)
                continue
            if a == "--":
                only_pos = True
                continue
            if a in ("-h", "--help"):
                opts["help"] = True
                return opts
            name, val = a, None
            if "=" in a:
                name, val = a.split("=", 1)
            o = self._find(name)
            if o is None:
                raise UsageError("unknown option %s" % name)
            if o.dest in given and not o.repeat:
                raise UsageError("%s given twice" % name)
            given.append(o.dest)
            if o.kind == "flag":
                if val is not None:
                    raise UsageError("%s takes no value (got %r)" % (name, val))
                opts[o.dest] = True
                continue
            if val is None:
                if i >= len(argv):
                    raise UsageError("%s needs a value (%s)" % (name, o.metavar))
                val = argv[i]
                i += 1
            if o.repeat:
                opts[o.dest] = opts[o.dest] + [o.convert(val)]
            else:
                opts[o.dest] = o.convert(val)
        many = self.positionals and self.positionals[-1].many
        if len(pos) > len(self.positionals) and not many:
            raise UsageError("unexpected argument %r" % pos[len(self.positionals)])
        for k, o in enumerate(self.positionals):
            if o.many:
                opts[o.dest] = [o.convert(w) for w in pos[k:]]
                if o.required and not opts[o.dest]:
                    raise UsageError("missing %s" % o.metavar)
            elif k < len(pos):
                opts[o.dest] = o.convert(pos[k])
            elif o.required:
                raise UsageError("missing %s" % o.metavar)
        opts["given"] = given
        return opts

    def help_text(self):
        lines = ["usage: python3 -m %s %s %s" % (PROG, self.command, self.usage)]
        if self.description:
            lines += ["", self.description.rstrip("\n")]
        rows = []
        for o in self.positionals:
            rows.append((o.metavar, o.help))
        if rows:
            lines += ["", "arguments:"] + _rows(rows)
        rows = []
        for o in self.options:
            head = (o.short + ", " if o.short else "") + o.name + (
                " " + o.metavar if o.metavar else "")
            text = o.help
            if o.kind == "choice" and "{choices}" in text:
                text = text.replace("{choices}", ", ".join(o.choices))
            rows.append((head, text))
        rows.append(("-h, --help", "this text"))
        lines += ["", "options:"] + _rows(rows)
        if self.epilog:
            lines += ["", self.epilog.rstrip("\n")]
        return "\n".join(lines)

    def error(self, message):
        print(error_line(self.command, message), file=sys.stderr)

    def main(self, argv, body):
        """Parse, then body(opts) -> exit status. -h: help, 0. UsageError (from parsing or
        from body, e.g. an unreadable file): one line on stderr, 2."""
        try:
            opts = self.parse(argv)
            if opts["help"]:
                print(self.help_text())
                return STATUS_OK
            return body(opts)
        except UsageError as e:
            self.error(str(e))
            return STATUS_USAGE


def wrap(text, width=60):
    """`text` with its spaces turned into line breaks so no line passes `width` (a help text
    naming a table's chips; the help column is ~60 wide)."""
    lines = []
    for para in text.split("\n"):
        line = ""
        for w in para.split(" "):
            if line and len(line) + 1 + len(w) > width:
                lines.append(line)
                line = w
            else:
                line = line + " " + w if line else w
        lines.append(line)
    return "\n".join(lines)


def _rows(rows, width=22):
    out = []
    for head, text in rows:
        parts = text.split("\n") if text else [""]
        if len(head) + 2 >= width:
            out.append("  " + head)
            first = 0
        else:
            out.append("%-*s%s" % (width, "  " + head, parts[0]))
            first = 1
        for p in parts[first:]:
            out.append(" " * width + p)
    return out
