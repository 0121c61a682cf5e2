"""Where the board is: the field model's answer at one place and date, in the units the app
works in, and what the app does with it (automatic declination, the field-strength check of a
new calibration, the interference window, quick calibration's expected field vector).
"""
#     from firmware.field.location import Location
#     loc = Location(-339000000, 1512000000, year_e3=2026160)   # Sydney, 2026-03-01
#     if loc.usable:
#         print(loc.declination_cdeg, loc.field_counts(12000))  # cdeg east, |B| in counts
#     else:
#         print(loc.status)                                   # e.g. "no field model: missing: ..."
#
# CompassApp.set_location(lat_e7, lon_e7, year_e3=None) builds one and applies it (apply()).
# Units, errors, statuses and what apply() changes: docs/design.md (module notes, location).
from firmware.compat import const, drop
from firmware.fixedpoint import rdiv

_LAT_MAX_E7 = 900000000
_LON_MAX_E7 = 1800000000  # a long int on a 32-bit board: compared once per set_location
_YEAR_MIN_E3 = 1900000    # a decimal year * 1000; 2026 would be a unit slip
_YEAR_MAX_E3 = 2100000
_NT_PER_GAUSS = 100000
DIP_TOL_CDEG = const(2000)  # PX4 EKF2: inclination within 20 deg of the table's
_DIP_TOL_KANG = const(3641)  # 20 deg in KANG
STATUS_NO_MODEL = "no field model"


def _check_int(v, name, unit, example):
    if type(v) is not int:
        raise TypeError("%s=%r: expected an int in %s (e.g. %s)" % (name, v, unit, example))


def check_position(lat_e7, lon_e7, year_e3=None):
    """TypeError / ValueError naming the argument and its unit; None when all are good."""
    _check_int(lat_e7, "lat_e7", "1e-7 deg, north positive", "473977000 for 47.3977 N")
    _check_int(lon_e7, "lon_e7", "1e-7 deg, east positive", "-1224194000 for 122.4194 W")
    if not -_LAT_MAX_E7 <= lat_e7 <= _LAT_MAX_E7:
        raise ValueError("lat_e7=%d: outside -900000000..900000000 (1e-7 deg, +-90 deg)"
                         % lat_e7)
    if not -_LON_MAX_E7 <= lon_e7 <= _LON_MAX_E7:
        raise ValueError("lon_e7=%d: outside -1800000000..1800000000 (1e-7 deg, +-180 deg)"
                         % lon_e7)
    if year_e3 is not None:
        _check_int(year_e3, "year_e3", "decimal years * 1000", "2026500 for mid-2026")
        if not _YEAR_MIN_E3 <= year_e3 <= _YEAR_MAX_E3:
            raise ValueError("year_e3=%d: expected decimal years * 1000 (2026500 for mid-2026)"
                             % year_e3)


class Location:
    """The field model at one place and date; see docs/design.md, module notes."""

    def __init__(self, lat_e7, lon_e7, year_e3=None, path=None):
        check_position(lat_e7, lon_e7, year_e3)
        self.lat_e7 = lat_e7
        self.lon_e7 = lon_e7
        self.year_e3 = year_e3
        self.declination_cdeg = self.inclination_cdeg = None
        self.declination_kang = self.inclination_kang = None
        self.field_nt = self.north_nt = self.east_nt = self.down_nt = None
        self.horizontal_nt = None
        self.manual_declination_kang = 0  # what apply() restores when not usable
        self.cal_mismatch = False
        self.status = self._query(path)
        self.usable = self.field_nt is not None

    def _query(self, path):
        from firmware.field.wmm import FieldModel, FieldTableError
        try:
            m = FieldModel(path)
        except FieldTableError as e:
            return "%s: %s" % (STATUS_NO_MODEL, e)
        except OSError as e:  # the filesystem failed under the header or CRC read
            return "%s: io_error %s" % (STATUS_NO_MODEL, e)
        try:
            m.at(self.lat_e7, self.lon_e7, self.year_e3)
        except FieldTableError as e:  # a record that cannot be read back
            return "%s: %s" % (STATUS_NO_MODEL, e)
        except OSError as e:
            return "%s: io_error %s" % (STATUS_NO_MODEL, e)
        finally:
            m.close()
        self.declination_cdeg = m.declination_cdeg
        self.inclination_cdeg = m.inclination_cdeg
        self.declination_kang = m.declination_kang
        self.inclination_kang = m.inclination_kang
        self.field_nt = m.field_nt
        self.north_nt = m.north_nt
        self.east_nt = m.east_nt
        self.down_nt = m.down_nt
        self.horizontal_nt = m.horizontal_nt
        return m.status

    # --- the model's field in the magnetometer's counts ---------------------------------
    @staticmethod
    def counts(nt, counts_per_gauss):
        """nT -> counts at counts_per_gauss (|nT| < 70000 and <= 15000 counts/G keep the
        product below 2**30)."""
        return rdiv(nt * counts_per_gauss, _NT_PER_GAUSS)

    def field_counts(self, counts_per_gauss):
        """|B| (F) in counts, or None when not usable or the sensitivity is unknown."""
        if not self.usable or not counts_per_gauss:
            return None
        return self.counts(self.field_nt, counts_per_gauss)

    # --- what the app does with it ---------------------------------------------------------
    def apply(self, app):
        """Put the location to work in a CompassApp (see docs/design.md, module notes); called by
        set_location and again whenever the app puts a calibration in force or starts
        collecting."""
        c = app.compass
        cal = app.calibration
        exp = None
        if self.usable:
            c.declination_kang = self.declination_kang
            exp = self.field_counts(getattr(app.mag, "counts_per_gauss", None))
        else:
            c.declination_kang = self.manual_declination_kang
        if exp is not None and cal.model is not None:
            self._window(c, cal, exp)
            c.set_dip(self.inclination_kang if app.accel is not None else None, _DIP_TOL_KANG)
            self.cal_mismatch = not _matches(cal.field, exp)
        else:
            c.set_dip(None)
            self.cal_mismatch = False
        col = app.collector
        if col is not None:
            col.calibrator.expected_field = exp
        else:  # the model's figures are kept: its table code and the field check leave
            drop("field.wmm", "calibrate.acceptance")  # (docs/design.md, memory)

    @staticmethod
    def _window(c, cal, exp):
        # the model's |B| through the calibration's InvW scale (field_out / field), and the
        # fitted one; the tolerance the app set with set_field() widens both ends
        e = rdiv(exp * cal.field_out, cal.field)
        f = cal.field_out
        lo = e if e < f else f
        hi = e if e > f else f
        tol = c.field_tol_pct
        c.set_window(lo - lo * tol // 100, hi + hi * tol // 100)


def place(app, lat_e7, lon_e7, year_e3, table):
    """CompassApp.set_location's Location: the declination given to the app stays for when
    the model cannot be used."""
    loc = Location(lat_e7, lon_e7, year_e3, table)
    prev = app.location
    loc.manual_declination_kang = (prev.manual_declination_kang if prev is not None
                                   else app.compass.declination_kang)
    return loc


def _matches(field, expected):
    from firmware.calibrate.acceptance import field_matches
    return field_matches(field, expected)
