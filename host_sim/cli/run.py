"""`python -m host_sim run` (what `make run` shows): the demo on a GY-271 (QMC5883L) with a
separate MPU6050, seed 1, human-readable, with the PNG in build/calibration.png.

Options are the demo's (`python -m host_sim demo --help`), e.g. `--no-plot`, `--seed 7`.
"""
from host_sim.cli import demo

DEFAULTS = ["--chip", "qmc5883l", "--seed", "1"]


def main(argv):
    if argv and argv[0] in ("-h", "--help"):
        print("usage: python -m host_sim run [demo options]   (make run)\n\n"
              "The demo with --chip qmc5883l --seed 1 and the plot; the options below apply.\n")
    return demo.main(DEFAULTS + list(argv))
