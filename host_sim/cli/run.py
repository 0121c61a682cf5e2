"""`python -m host_sim run` (what `make run` shows): the demo on a GY-271 (QMC5883L) with a
separate MPU6050, seed 1, human-readable, with the PNG in build/calibration.png.

Options are the demo's (its defaults are this board and seed), e.g. `--no-plot`, `--seed 7`.
"""
from host_sim.cli import demo


def main(argv):
    p = demo.parser("run", "The demo (make run): a GY-271 (QMC5883L) and an MPU6050, seed 1, "
                           "with the plot;\nthe options below apply.")
    return p.main(argv, demo.body)
