"""Print the mip package.json: URLs relative to itself, so both installs work with mpremote
1.29 (mpremote/mip.py resolves a relative URL against the package.json's own location):

    mpremote mip install github:OWNER/REPO          # whoever publishes the repository
    mpremote mip install ./package.json             # from a clone, files read locally

Each lands in the board's lib folder as lib/firmware/NAME.

`make package-json` writes it; tests/test_packaging.py checks the committed file is current,
so a module added to firmware/ cannot be left out of the installable package.
"""
import json
import os
import sys

from host_sim.cli.args import Parser

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def package_json():
    sys.path.insert(0, ROOT)
    from firmware import __version__
    mods = sorted(f for f in os.listdir(os.path.join(ROOT, "firmware"))
                  if f.endswith(".py") or f.endswith(".bin"))  # .bin: field.py's table
    return {
        "urls": [["firmware/" + m, "firmware/" + m] for m in mods],
        "deps": [],
        "version": __version__,
    }


def main(argv=()):
    p = Parser("cli.packaging", "", "Print the mip package.json (make package-json writes it).")
    return p.main(list(argv), _body)


def _body(opts):
    print(json.dumps(package_json(), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
