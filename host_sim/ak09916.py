"""AK09916 register model (AKM; I2C 0x0C), the magnetometer inside the ICM-20948, reached
through the IMU's I2C bypass (host_sim/icm20948.py), from the ICM-20948 datasheet (DS-000189
rev 1.3, sections 3.3 and 13, the AK09916's register descriptions).

    chip = AK09916Sim(world, mount=(1, 2, 3), seed=1)
    i2c.attach(0x0C, chip, gate=imu.bypass_open)
    i2c.writeto_mem(0x0C, 0x31, b'\\x08')     # continuous measurement mode 4 (100 Hz)

Registers: 0x00 WIA1 0x48 (AKM), 0x01 WIA2 0x09 (the AK09916); 0x10 ST1 (bit0 DRDY, bit1
DOR); 0x11-0x16 HXL..HZH, X, Y, Z int16 LSB first, 0.15 uT/LSB, -32752..32752; 0x17 TMPS (a
dummy: reads 0); 0x18 ST2 (bit3 HOFL); 0x31 CNTL2 (MODE[4:0]: 00000 power-down, 00001
single, 00010 / 00100 / 00110 / 01000 continuous 1-4 at 10 / 20 / 50 / 100 Hz, 10000
self-test); 0x32 CNTL3 (SRST bit0). Reads auto-increment 0x00 -> 0x01 -> 0x02 -> 0x03 ->
0x10 -> ... -> 0x18 and back to 0x00, and through 0x30-0x32 back to 0x30 (the AK09916's
serial interface as its family's datasheets give it).

Behaviour as host_sim/ak8963.py models it (the same AKM family and datasheet wording): mode
changes only from power-down after 100 us, data-ready, DOR, the read lock that ST2 ends ("be
sure to read ST2 register at the end", DS-000189 13.4), HOFL beyond 4912 uT of |X| + |Y| +
|Z|, 0.3 uT RMS noise (a model choice), the fault hooks and inject_raw(). No fuse ROM: its
sensitivity is trimmed inside the chip.
"""
from host_sim.ak8963 import AKMagSim

ADDRESS = 0x0C


class AK09916Sim(AKMagSim):
    """AK09916 at 0x0C (see the module docstring)."""

    ADDRESS = 0x0C
    ID = b"\x48\x09"
    ST1 = 0x10
    DATA = 0x11
    ST2 = 0x18
    CNTL = 0x31
    SRST_REG = 0x32
    MODE_MASK = 0x1F
    HAS_BITM = False
    PERIODS = {0x02: 100000, 0x04: 50000, 0x06: 20000, 0x08: 10000}
    UT_PER_COUNT = 0.15
    LIMIT = 32752
    # no glitch_range(): why, for a test that would glitch one
    FIXED_RANGE = ("the AK09916 has one output width and sensitivity, 0.15 uT/LSB, "
                   "-32752..32752 (ICM-20948 datasheet DS-000189 3.3, 13.3): no range setting")

    def next_pointer(self, reg):
        if reg == 0x03:
            return 0x10
        if reg == 0x18:
            return 0x00
        if reg == 0x32:
            return 0x30
        return (reg + 1) & 0xFF

    def read_other(self, reg):
        if reg == 0x17:              # TMPS: a dummy, but a data register (ST1 cleared)
            self._start_read()
        if reg == 0x31:
            return self.regs[reg]
        return 0
