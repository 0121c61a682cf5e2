"""firmware/fast.py: the viper kernels give the plain firmware's bits, allocate nothing, and
fall back to the plain code where there is no native emitter (CPython)."""
import os
import re

from tests import mp
from tests.mp import json_lines

SCENARIO = "tests/scenarios/fast_parity.py"


def _run(micro):
    return json_lines(mp.run([SCENARIO], micro=micro, timeout=300))[-1]


def test_viper_kernels_match_the_plain_firmware_case_by_case_on_micropython():
    r = _run(True)
    assert r["viper"] is True  # the unix port has the emitter: the kernels are in use
    assert r["mismatches"] == []
    # every kernel saw the edge cases plus thousands of LCG inputs at every scale
    assert r["cases"]["compass"] > 20000
    assert r["cases"]["pipeline"] > 10000
    assert r["cases"]["correct"] > 5000
    assert r["cases"]["axes"] == 48 * (17 + 60)  # every signed permutation


def test_viper_kernels_allocate_nothing_not_even_a_call_frame():
    alloc = _run(True)["allocation"]
    assert alloc.pop("heap_locked") == "ok"
    assert alloc and all(v == 0 for v in alloc.values()), alloc


def test_cpython_falls_back_to_the_plain_code():
    r = _run(False)
    assert r["viper"] is False
    assert r["mismatches"] == []
    from firmware import fast
    from firmware.heading import Compass
    assert fast.FastCompass.update is Compass.update


def test_kernel_thresholds_are_the_heading_modules_constants():
    # _fastv.py writes the limits as literals (viper reads module constants slowly); they
    # must be heading.py's
    from firmware import heading
    src = open(os.path.join(mp.ROOT, "firmware", "_fastv.py")).read()
    for name in ("_DIP_LIMIT_KANG", "_GIMBAL_PITCH_KANG"):
        m = re.search(r"(\d+)\s+or\s+\w+\s*<\s*-(\d+)\s+#\s*%s" % name, src)
        assert m, name
        assert int(m.group(1)) == int(m.group(2)) == getattr(heading, name)
    for name in ("FLAG_NO_FIELD", "FLAG_NO_GRAVITY", "FLAG_INTERFERENCE", "FLAG_DIP_HIGH",
                 "FLAG_GIMBAL"):
        m = re.search(r"flags \|?= (\d+)\s+#\s*%s\b" % name, src)
        assert m and int(m.group(1)) == getattr(heading, name), name
