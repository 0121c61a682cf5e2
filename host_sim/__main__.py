"""`python -m host_sim COMMAND ...` (also `micropython -m host_sim ...`): the desktop tools'
runner, desktop/__main__.py, under the name the docs use. The simulator itself never imports
desktop/ or firmware/; this file is the one exception, and only forwards."""
import sys

from desktop.__main__ import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]) or 0)
