"""desktop/args.py: the one argument parser of the host commands."""
from fractions import Fraction as Fr

import pytest
from hypothesis import given, strategies as st

from desktop import args
from desktop.args import Parser, UsageError


def parser():
    p = Parser("demo", "[options] WHERE", "A test command.", "exit status: 0 done")
    p.positional("where", "LAT,LON", "a place", required=False)
    p.option("--count", "int", default=3, lo=1, hi=10, help="how many")
    p.option("--declination", "int", default=0, lo=-18000, hi=18000, metavar="CDEG",
             help="centidegrees")
    p.option("--gain", "decimal", lo="0.01", hi=100, help="a gain")
    p.option("--mode", "choice", default="a", choices=("a", "b"), help="{choices}")
    p.option("--name", "str", help="a name")
    p.option("--out", "path", help="a file")
    p.option("--fast", "flag", help="go fast")
    p.option("--pair", lambda t: tuple(int(x) for x in t.split(":")), help="A:B")
    return p


def test_defaults_and_values():
    o = parser().parse([])
    assert o["count"] == 3 and o["declination"] == 0 and o["gain"] is None
    assert o["mode"] == "a" and o["fast"] is False and o["where"] is None and not o["help"]
    o = parser().parse(["--count", "7", "--fast", "--mode=b", "--gain", "2.5", "--name", "x",
                        "--pair", "1:2", "here"])
    assert (o["count"], o["fast"], o["mode"], o["gain"], o["name"], o["pair"], o["where"]) == \
        (7, True, "b", (25, 1), "x", (1, 2), "here")


def test_negative_numbers_are_values_and_positionals():
    o = parser().parse(["--declination", "-150", "-33.9,151.2"])
    assert o["declination"] == -150 and o["where"] == "-33.9,151.2"
    o = parser().parse(["-.5", "--declination=-18000"])
    assert o["where"] == "-.5" and o["declination"] == -18000
    assert parser().parse(["--", "--not-an-option"])["where"] == "--not-an-option"


@pytest.mark.parametrize("argv, named", [
    (["--count", "0"], "--count 0"), (["--count", "11"], "--count 11"),
    (["--count", "x"], "--count x"), (["--count", "1.5"], "--count 1.5"),
    (["--count"], "--count needs a value"), (["--declination", "-18001"], "--declination"),
    (["--gain", "0"], "--gain 0"), (["--gain", "-1"], "--gain -1"), (["--gain", "nan"], "--gain"),
    (["--gain", "1e400"], "--gain"), (["--mode", "c"], "--mode c"), (["--out", ""], "--out"),
    (["--fast=1"], "--fast takes no value"), (["--bogus"], "--bogus"),
    (["--count", "2", "--count", "3"], "--count given twice"), (["a", "b"], "'b'"),
    (["--pair", "1-2"], "--pair 1-2"),
])
def test_every_bad_value_is_a_usage_error_naming_the_option(argv, named):
    with pytest.raises(UsageError) as e:
        parser().parse(argv)
    assert named in str(e.value)


def test_main_prints_one_line_on_stderr_and_returns_2(capsys):
    p = parser()
    assert p.main(["--count", "-4"], lambda o: 0) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == "host_sim demo: error: --count -4: expected an integer " \
                                        "in 1..10\n"
    # a UsageError raised by the command itself (e.g. an unreadable file) is reported the same way
    def body(o):
        raise UsageError("x.csv: no such file")
    assert p.main([], body) == 2
    assert capsys.readouterr().err == "host_sim demo: error: x.csv: no such file\n"
    assert p.main(["--count", "4"], lambda o: o["count"]) == 4


def test_help_is_generated_from_the_declarations(capsys):
    p = parser()
    assert p.main(["--help"], lambda o: 1 / 0) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: python3 -m host_sim demo [options] WHERE\n")
    for word in ("--count COUNT", "how many", "--declination CDEG", "a, b", "--fast",
                 "LAT,LON", "-h, --help", "exit status: 0 done"):
        assert word in out, word


def test_a_required_positional_is_asked_for():
    p = Parser("x", "FILE")
    p.positional("file", "FILE", kind="path")
    with pytest.raises(UsageError, match="missing FILE"):
        p.parse([])


@given(st.integers(-10 ** 12, 10 ** 12), st.integers(0, 9), st.integers(-30, 30))
def test_decimal_text_is_exact_both_ways(m, d, e):
    s = str(abs(m)).rjust(d + 1, "0")
    text = ("-" if m < 0 else "") + (s[:-d] + "." + s[-d:] if d else s) + "e%d" % e
    v = args.parse_decimal(text)
    assert Fr(v[0], 10 ** v[1]) == Fr(m, 10 ** d) * Fr(10) ** e
    back = args.parse_decimal(args.decimal_text(v))
    assert Fr(back[0], 10 ** back[1]) == Fr(v[0], 10 ** v[1])


@pytest.mark.parametrize("bad", ["", "-", "1.2.3", "abc", "1e", "nan", "inf", "-inf", "1e31",
                                 "1e-31", "1e30000", "1e999999999", "0x10", "1e+", "1_000"])
def test_decimal_refuses_non_numbers_and_huge_exponents(bad):
    with pytest.raises(ValueError):
        args.parse_decimal(bad)


def test_many_positionals_repeatable_options_and_short_names():
    p = Parser("pts", "[LAT,LON ...]")
    p.positional("points", "LAT,LON", "places", required=False, many=True,
                  kind=lambda t: tuple(int(v) for v in t.split(",")))
    p.option("--device", "str", repeat=True, metavar="D")
    p.option("--output", "path", short="-o")
    o = p.parse(["-33,151", "--device", "a", "-o", "x.png", "51,-1", "--device", "b"])
    assert o["points"] == [(-33, 151), (51, -1)]
    assert o["device"] == ["a", "b"] and o["output"] == "x.png"
    assert p.parse([])["points"] == [] and p.parse([])["device"] == []
    with pytest.raises(UsageError, match="LAT,LON '1,x'"):
        p.parse(["1,x"])
    with pytest.raises(UsageError, match="--output given twice"):
        p.parse(["-o", "a", "--output", "b"])
    assert "-o, --output" in p.help_text()
    q = Parser("need", "FILE...")
    q.positional("files", "FILE", many=True)
    with pytest.raises(UsageError, match="missing FILE"):
        q.parse([])
