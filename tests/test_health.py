"""firmware/fieldwatch.py's field checks on their own: the dip reference (DipCheck) and the spells
of FieldWatch (shift, jump, hold, and the evidence that ends one), driven with hand-made
compass states so each rule is seen alone. The app-level scenarios are in
tests/test_faults.py and the campaign in tests/test_soak.py."""
from array import array

from hypothesis import given
from hypothesis import strategies as st

from firmware import compass, fieldwatch
from firmware.calibration import Calibration
from firmware.compass import Compass
from firmware.fieldwatch import DipCheck, FieldWatch
from firmware.health import DIP_TOL_KANG, SPELL_FIELD, SPELL_JUMP, SPELL_SHIFT

DEG = 65536 / 360.0
DIP60 = 10923
PERIOD = 20000  # us, 50 Hz


def k(deg):
    return int(round(deg * DEG))


def test_dip_check_learns_a_steady_stretch_then_flags_beyond_3_deg():
    d = DipCheck()
    assert not d.off(0)                         # nothing known: nothing flagged
    armed = [d.learn(DIP60 + (i % 3) * 20, PERIOD) for i in range(30)]
    assert armed.index(True) == 25              # 0.5 s at 50 Hz (and >= 8 samples)
    assert abs(d.ref - (DIP60 + 20)) <= 1
    assert not d.off(d.ref + DIP_TOL_KANG) and d.off(d.ref + DIP_TOL_KANG + 1)
    assert d.off(d.ref - DIP_TOL_KANG - 1)
    assert not d.learn(0, PERIOD)               # armed: held, not learned further


def test_dip_check_restarts_on_a_sample_off_the_stretch():
    d = DipCheck()
    for _ in range(20):
        d.learn(DIP60, PERIOD)
    d.learn(DIP60 + k(2), PERIOD)               # 2 deg off the mean: a new stretch begins
    assert not d.armed
    got = [d.learn(DIP60 + k(2), PERIOD) for _ in range(30)]
    assert True in got and d.ref == DIP60 + k(2)


class Board:
    """A Compass whose state is written by hand (the fields FieldWatch reads) and a body
    field; field 4527 counts as the simulated GY-271's calibration."""

    def __init__(self, fit_error=38, dip=None):
        self.c = Compass()
        self.body = array("h", (2263, 0, 3920))
        self.w = FieldWatch(self.c, self.body)
        self.cal = Calibration(model=10, field=6122, field_out=4527, fit_error=fit_error,
                               dip_kang=dip)
        self.w.use(self.cal)
        self.set(4527, DIP60, 0)

    def set(self, mag, dip, heading, pitch=0, roll=0, body=None):
        c = self.c
        st = c.st                               # the compass's results live in its state
        st[compass._MAG] = mag
        st[compass._DIP] = dip
        c.heading_kang = heading & 0xFFFF
        st[compass._PITCH] = pitch
        st[compass._ROLL] = roll
        st[compass._FLAGS] = 0
        if body is not None:
            for i in range(3):
                self.body[i] = body[i]

    def run(self, n, dt=PERIOD, **kw):
        out = []
        for _ in range(n):
            self.set(**kw)
            out.append(self.w.sample(True, dt))
        return out

    def turn(self, start, step, n, dt=PERIOD):
        """n samples whose heading moves by `step` deg each, from `start`: their flags."""
        return [self.run(1, dt, mag=4527, dip=DIP60, heading=k(start + step * (i + 1)))[0]
                for i in range(n)]


def test_a_calibration_saved_with_its_dip_arms_the_check_at_once():
    b = Board(dip=DIP60)
    assert b.w.dip.armed and b.w.dip.ref == DIP60
    assert b.run(1, mag=4527, dip=DIP60 + k(4), heading=0) == [SPELL_FIELD]
    assert b.c.interference and b.c.flags & 1   # the compass's flag, as for |B|


def test_the_dip_tolerance_widens_with_the_fit_error_like_the_field_window():
    assert Board(fit_error=38).w.dip.tol == DIP_TOL_KANG          # 3 deg floor
    assert Board(fit_error=1000).w.dip.tol == 3 * 1000 * 10430 // 10000  # 3 x 10 %: 17.9 deg


def test_a_fast_change_of_field_strength_is_a_shift_and_a_still_field_is_not():
    b = Board(dip=DIP60)
    assert b.run(20, mag=4527, dip=DIP60, heading=100) == [0] * 20
    assert b.run(1, mag=4527 * 103 // 100, dip=DIP60, heading=100) == [0]  # 3 %: noise
    b.run(20, mag=4527, dip=DIP60, heading=100)
    b.w.spell = 0
    assert b.run(1, mag=4527 * 95 // 100, dip=DIP60, heading=100) == [SPELL_SHIFT]
    assert b.w.spell == SPELL_SHIFT


def test_a_jump_needs_a_still_level_tilt():
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.run(1, mag=4527, dip=DIP60, heading=k(3.5)) == [0]
    assert b.run(1, mag=4527, dip=DIP60, heading=k(8)) == [SPELL_JUMP]
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0, pitch=k(10))
    assert b.run(1, mag=4527, dip=DIP60, heading=k(8), pitch=k(12)) == [0]  # tilting: no
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0, pitch=k(60))
    assert b.run(1, mag=4527, dip=DIP60, heading=k(8), pitch=k(60)) == [0]  # steep: no


def test_a_drift_under_4_deg_a_step_is_a_jump_once_two_steps_pass_4_deg_and_25_deg_per_s():
    # a magnet moving in over several samples: 3.8 deg a step passes the one-step limit, but
    # two steps are 7.6 deg, beyond 4 deg plus 25 deg/s x 40 ms = 5 deg (docs/faults.md)
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 3.8, 2) == [0, SPELL_JUMP]
    # a steady turn of 2 deg a step (100 deg/s at 50 Hz) is 4 deg over two: no flag
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 2.0, 30) == [0] * 30
    # the allowance is a turn rate: at 15 Hz two steps of 3.5 deg (52 deg/s) are within
    # 4 + 25 x 0.133 = 7.3 deg; at 50 Hz (175 deg/s) they are not
    b = Board(dip=DIP60)
    b.run(5, 66667, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 3.5, 10, dt=66667) == [0] * 10
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 3.5, 2) == [0, SPELL_JUMP]


def test_above_50_hz_a_ramp_of_small_steps_is_a_jump_on_its_third_step():
    # at 100 Hz two steps span 20 ms: 2 deg a step is 4 deg over two, within 4 + 0.5 deg, and
    # 6 deg over three, beyond 4 + 0.75 (a magnet brought near, docs/faults.md); at 50 Hz
    # three steps span 60 ms and only the one- and two-step checks judge them
    b = Board(dip=DIP60)
    b.run(20, 10000, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 2.0, 3, dt=10000) == [0, 0, SPELL_JUMP]
    b = Board(dip=DIP60)
    b.run(20, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 2.0, 3) == [0, 0, 0]


def test_one_step_is_judged_against_the_recent_turn_per_step():
    # at 15 Hz a steady 30 deg/s turn is 2 deg a step: a step of 5 deg is 3 deg off it (and
    # 7 deg over two, within 4 + 25 x 0.133 = 7.3), not a jump; from a board held still the
    # same step is one
    b = Board(dip=DIP60)
    b.run(5, 66667, mag=4527, dip=DIP60, heading=0)
    assert b.turn(0, 2.0, 20, dt=66667) == [0] * 20
    h = b.c.heading_kang
    assert b.run(1, 66667, mag=4527, dip=DIP60, heading=h + k(5)) == [0]
    b = Board(dip=DIP60)
    b.run(20, 66667, mag=4527, dip=DIP60, heading=0)
    assert b.run(1, 66667, mag=4527, dip=DIP60, heading=k(5)) == [SPELL_JUMP]


def test_two_steps_count_only_still_unflagged_ones():
    # a step that tilted, or that was itself flagged, does not count towards the next one
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.run(1, mag=4527, dip=DIP60, heading=k(3.5), pitch=k(2)) == [0]  # tilting
    assert b.run(1, mag=4527, dip=DIP60, heading=k(7), pitch=k(2)) == [0]    # 3.5 still
    b = Board(dip=DIP60)
    b.run(5, mag=4527, dip=DIP60, heading=0)
    assert b.run(1, mag=4527, dip=DIP60, heading=k(30)) == [SPELL_JUMP]
    assert b.run(1, mag=4527, dip=DIP60, heading=k(32)) == [0]  # the jump is not counted again


def test_a_spell_ends_when_the_field_is_back_where_it_was():
    b = Board(dip=DIP60)
    here = (2263, 0, 3920)
    b.run(10, mag=4527, dip=DIP60, heading=0, body=here)
    b.run(1, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))  # a jump
    assert b.w.spell == SPELL_JUMP
    b.run(5, mag=4527, dip=DIP60, heading=0, body=here)  # back (a jump again), 0.08 s clean
    assert b.w.spell == SPELL_JUMP
    b.run(1, mag=4527, dip=DIP60, heading=0, body=here)  # 0.1 s of clean samples
    assert b.w.spell == 0


def test_a_spell_ends_after_2_s_over_a_turn_or_10_s_still():
    b = Board(dip=DIP60)
    b.run(10, mag=4527, dip=DIP60, heading=0, body=(2263, 0, 3920))
    b.run(1, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))
    b.run(100, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))  # 2 s, still
    assert b.w.spell == SPELL_JUMP
    # the body field moves by B / 4 (a turn of ~29 deg about the vertical)
    b.run(1, mag=4527, dip=DIP60, heading=k(33), body=(1131, 1960, 3920))
    assert b.w.spell == 0
    b = Board(dip=DIP60)
    b.run(10, mag=4527, dip=DIP60, heading=0, body=(2263, 0, 3920))
    b.run(1, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))
    b.run(499, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))  # 9.98 s
    assert b.w.spell == SPELL_JUMP
    b.run(1, mag=4527, dip=DIP60, heading=k(30), body=(1960, 1131, 3920))  # 10 s
    assert b.w.spell == 0


def test_a_spell_begun_by_a_run_of_repeats_is_forgotten():
    b = Board(dip=DIP60)
    b.run(10, mag=4527, dip=DIP60, heading=0)
    b.set(0, 0, 0)
    b.c.mark_interference()
    b.w.sample(True, PERIOD)                    # the first zero sample: |B| off
    assert b.w.spell == SPELL_FIELD
    b.w.forget(1)                               # the next one was a repeat: stale data
    assert b.w.spell == 0
    b.c.mark_interference()
    b.w.sample(True, PERIOD)
    b.run(3, mag=4527, dip=DIP60, heading=0)
    b.w.forget(1)                               # an older spell stays
    assert b.w.spell == SPELL_FIELD


def test_the_field_differences_stay_small_ints():
    # the largest body difference (int16 extremes), held, squared and summed, at every field
    # size; a small field (an AKM chip's ~330 counts) keeps its every count
    for f in (200, 411, 4527, 16000, 32767):
        b = Board()
        b.w.use(Calibration(model=10, field=f, field_out=f))
        for i in range(3):
            b.body[i] = 32767
        assert b.w._d2(array("h", (-32768,) * 3)) <= 3 * 16383 ** 2 < 2 ** 30
        assert (f >> b.w.shift) < 2 ** 11 and (f < 2 ** 11) == (b.w.shift == 0)


@given(st.integers(0, 2 ** 31 - 1), st.integers(-32768, 32767), st.integers(-32768, 32767))
def test_the_two_step_jump_limit_stays_a_small_int(us, d, s):
    # any two steps' time (the app caps each at 4 sample periods; here anything) and any two
    # wrapped heading changes
    t = fieldwatch._turn(us)
    assert 0 <= t <= 8000 * 4551 // 1000 and abs(d + s) < 2 ** 17
    assert fieldwatch._turn(40000) == 182     # 25 deg/s x 40 ms: 1 deg


def noisy(b, n, sd_deg, seed=1, turn_deg=0.0, dt=PERIOD):
    """n still samples whose heading turns by turn_deg a step plus Gaussian noise: flags."""
    import random
    g = random.Random(seed)
    return [b.run(1, dt, mag=4527, dip=DIP60,
                  heading=k(turn_deg * i + g.gauss(0.0, sd_deg)))[0] for i in range(n)]


def test_the_jump_limit_is_3_5_x_the_headings_measured_noise_within_4_to_8_deg():
    # a noisier chip moves its heading more between samples: the limit follows 3.5 x the
    # mean change of step (~5 sigma of a step's noise)
    b = Board(dip=DIP60)
    assert b.w.jump == k(4)
    assert noisy(b, 600, 0.8, turn_deg=0.9) == [0] * 600    # 1.1 deg a step (LIS3MDL at 20 Hz)
    assert k(5) < b.w.jump < k(6)
    assert b.run(1, mag=4527, dip=DIP60, heading=b.c.heading_kang + k(7)) == [SPELL_JUMP]
    # a quiet one keeps 4 deg, and a steady turn is no noise (the change of step cancels it)
    b = Board(dip=DIP60)
    assert noisy(b, 600, 0.3, turn_deg=1.0) == [0] * 600
    assert b.w.jump == k(4)
    assert b.run(1, mag=4527, dip=DIP60, heading=b.c.heading_kang + k(5)) == [SPELL_JUMP]
    # however noisy, 8 deg at most
    b = Board(dip=DIP60)
    noisy(b, 2000, 5.0)
    assert b.w.jump == k(8)


@given(st.lists(st.tuples(st.integers(-32768, 32767), st.booleans(), st.integers(0, 8000000)),
                max_size=300))
def test_the_measured_noise_and_the_jump_limit_stay_small_ints(steps):
    # any headings, still or tilting, any step times: .noise (2**6 x the mean change of step,
    # each at most 2**16) stays below 2**22, the limit within 4..8 deg
    b = Board(dip=DIP60)
    h = 0
    for d, tilting, dt in steps:
        h += d
        b.run(1, dt, mag=4527, dip=DIP60, heading=h, pitch=k(2) if tilting else 0)
        assert 0 <= b.w.noise < 2 ** 22 and abs(b.w.rate) < 2 ** 18 and k(4) <= b.w.jump <= k(8)
