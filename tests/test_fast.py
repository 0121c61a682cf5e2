"""firmware/fast.py: the viper mirrors give the plain functions' bits over the int16 extremes,
a small-int generator and the real logs, allocate nothing, and are absent (the plain path
runs) where there is no native emitter."""
import ast
import os

from tests import mp
from tests.mp import json_lines

SCENARIO = "tests/scenarios/fast_parity.py"
MIRRORS = {"correct": "calibration", "apply": "axes", "atan2": "trig", "sin": "trig",
           "cos": "trig", "norm14": "trig", "isqrt": "fixedpoint", "orient": "compass",
           "level": "compass", "tilt": "compass", "derotate": "compass", "magnitude": "compass",
           "dip": "compass", "judge": "compass", "measure": "compass", "screen": "calibrate.samples",
           "int16x3_into": "i2cdevice"}
UNCALLED = {"cos", "level", "tilt", "derotate", "judge"}  # reached through orient or
#                                                          measure, or trivial


def _run(micro):
    return json_lines(mp.run([SCENARIO], micro=micro, timeout=300))[-1]


def test_viper_mirrors_match_the_plain_functions_on_micropython():
    r = _run(True)
    assert r["fast"] is True  # the unix port has the emitter: the kernels are in use
    assert r["mismatches"] == []
    for name in set(MIRRORS) - UNCALLED:
        assert r["cases"].get(name, 0) > 1000, name
    assert r["cases"]["state"] > 1000  # orient leaves the same working state
    assert r["cases"]["pipeline"] > 3000
    assert r["cases"]["buffer"] == 5  # the buffers screened each way hold the same samples
    assert r["log_samples"] >= 2347  # the shipped logs at least (datasets/): 2000 + 347 rows


def test_viper_mirrors_allocate_nothing_not_even_a_call_frame():
    alloc = _run(True)["allocation"]
    assert sorted(alloc) == sorted(set(MIRRORS) - UNCALLED)
    assert all(v == 0 for v in alloc.values()), alloc


def test_cpython_has_no_kernels_and_runs_the_plain_path():
    from firmware import compass
    from firmware.compat import kernels
    assert kernels() is None and compass.KERNELS is None
    assert _run(False)["fast"] is False


def test_every_mirror_has_the_signature_of_its_plain_function():
    src = open(os.path.join(mp.ROOT, "firmware", "fast.py")).read()
    fast = {f.name: [a.arg for a in f.args.args] for f in ast.parse(src).body
            if isinstance(f, ast.FunctionDef) and not f.name.startswith("_")}
    assert set(fast) == set(MIRRORS)
    for name, home in MIRRORS.items():
        plain = open(os.path.join(mp.ROOT, "firmware", *home.split(".")) + ".py").read()
        sig = [f for f in ast.parse(plain).body
               if isinstance(f, ast.FunctionDef) and f.name == name]
        assert sig, (home, name)
        assert len(sig[0].args.args) == len(fast[name]), name
