"""Public API inputs fail with one clear message naming the argument and its unit."""
import pytest

from firmware.app import CompassApp
from firmware.calibrate.calibrator import Calibrator
from firmware.trig import KANG_PER_TURN, kang_to_str
from tests import mp


@pytest.mark.parametrize("value", [1.5, "150", None, 150.0])
def test_calibrator_max_fit_error_rejects_non_int_naming_the_unit(value):
    with pytest.raises(TypeError) as e:
        Calibrator(max_fit_error=value)
    assert "max_fit_error" in str(e.value) and "hundredths of a percent" in str(e.value)


def test_calibrator_max_fit_error_rejects_zero_and_negative():
    for v in (0, -5):
        with pytest.raises(ValueError, match="max_fit_error.*hundredths of a percent"):
            Calibrator(max_fit_error=v)
    assert Calibrator(max_fit_error=150).max_fit_error == 150


def test_calibrator_counts_per_gauss_rejects_a_float():
    with pytest.raises(TypeError, match="counts_per_gauss"):
        Calibrator(counts_per_gauss=1090.0)


@pytest.mark.parametrize("args,name", [((1.5, 0, 0), "x"), ((0, "7", 0), "y"),
                                       ((0, 0, 2.0), "z"), ((0, None, 0), "y")])
def test_calibrator_add_rejects_non_int_naming_the_argument(args, name):
    cal = Calibrator(model=4, counts_per_gauss=12000)
    with pytest.raises(TypeError) as e:
        cal.add(*args)
    assert ("sample %s = " % name) in str(e.value) and "int16" in str(e.value)
    assert cal.count == 0  # nothing changed


@pytest.mark.parametrize("x", [32768, -32769, 2 ** 31, 2 ** 40, -(2 ** 70)])
def test_calibrator_add_rejects_values_outside_int16(x):
    cal = Calibrator(model=4, counts_per_gauss=12000)
    with pytest.raises(ValueError, match="not int16"):
        cal.add(x, 0, 0)
    assert cal.count == 0


def test_calibrator_add_errors_are_the_same_on_micropython():
    code = ("from firmware.calibrate.calibrator import Calibrator\n"
            "c = Calibrator(model=4)\n"
            "for a in ((1.5, 0, 0), (0, 'a', 0), (40000, 0, 0), (2 ** 40, 0, 0)):\n"
            "    try:\n"
            "        c.add(*a)\n"
            "    except Exception as e:\n"
            "        print(type(e).__name__, e)\n"
            "print(c.add(5, 6, 7), c.count)\n")
    out = mp.parity(["-c", code])
    assert out.splitlines() == [
        "TypeError sample x = 1.5: expected an int (raw int16 counts)",
        "TypeError sample y = 'a': expected an int (raw int16 counts)",
        "ValueError sample (40000, 0, 0) is not int16",
        "ValueError sample (1099511627776, 0, 0) is not int16",
        "True 1"]


@pytest.mark.parametrize("value", [1.5, "150", 150.0])
def test_compass_app_declination_rejects_non_int_naming_the_unit(value):
    # the check runs before the bus is touched, so no board is needed
    with pytest.raises(TypeError) as e:
        CompassApp(None, declination_cdeg=value)
    assert "declination_cdeg" in str(e.value) and "hundredths of a degree" in str(e.value)


def _reference(kang, signed):
    # float reference: degrees rounded to one decimal, wrapped into the documented range
    d = round((kang % KANG_PER_TURN) * 3600 / KANG_PER_TURN) % 3600
    if signed and d >= 1800:
        d -= 3600
    return ("-" if d < 0 else "") + "%d.%d" % (abs(d) // 10, abs(d) % 10)


@pytest.mark.parametrize("kang", [-1, -2, -9, -10, -11, -16384, -32767, -32768, -32769, -65535,
                                  -65536, -65537, -100000, 0, 9, 10, 16384, 32767, 32768, 65535,
                                  65536, 65537, 81920, 100000, 2 ** 31, 2 ** 40 + 16384])
def test_kang_to_str_negative_and_large_inputs(kang):
    assert kang_to_str(kang) == _reference(kang, False)
    assert kang_to_str(kang, signed=True) == _reference(kang, True)


def test_kang_to_str_named_angles():
    assert kang_to_str(-1) == "0.0"           # -0.0055 deg
    assert kang_to_str(-16384) == "270.0"     # -90 deg
    assert kang_to_str(-16384, signed=True) == "-90.0"
    assert kang_to_str(65536 + 16384) == "90.0"
    assert kang_to_str(32767, signed=True) == "-180.0"  # 179.995 rounds to the range's end
    for k in range(-70000, 140000, 97):       # every output is in its documented range
        s = kang_to_str(k, signed=True)
        assert -180.0 <= float(s) <= 179.9
        assert 0.0 <= float(kang_to_str(k)) <= 359.9
