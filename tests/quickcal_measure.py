"""The quick-calibration accuracy table of docs/quick_calibration.md (long: ~1 min at the
default 100 seeds). python -m tests.quickcal_measure [seeds]"""
import math
import sys

from tests import location_world as L

SETUPS = (("QMC5883L + MPU6050, level", "qmc5883l", True, 0.0),
          ("QMC5883L + MPU6050, tilt +-20 deg", "qmc5883l", True, 20.0),
          ("QMC5883L alone, level", "qmc5883l", False, 0.0),
          ("GY-87 (HMC5883L + MPU6050), tilt +-20 deg", "gy87", None, 20.0))


def main(n=100):
    print("| setup | poses | soft iron | RMS deg | 95 % of seeds within deg | max deg |")
    print("|---|---|---|---|---|---|")
    for name, chip, accel, tilt in SETUPS:
        for poses in (1, 2):
            for dev in (0.0, 0.015, 0.02, 0.03):
                worst = []
                every = []
                for s in range(n):
                    e = L.quick_cal_errors(s, dev, chip, accel, tilt, poses)
                    worst.append(max(abs(x) for x in e))
                    every += e
                worst.sort()
                rms = math.sqrt(sum(x * x for x in every) / len(every))
                print("| %s | %d | %.1f %% | %.2f | %.2f | %.2f |" % (
                    name, poses, dev * 100, rms, worst[int(0.95 * n) - 1], worst[-1]),
                    flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100)
