"""`make datasets`: fetch the real magnetometer logs the repository may not ship, pinned.

Seven of the ten logs the tests use (datasets/README.md) come from repositories that publish
no licence, so the repository carries only their provenance (datasets/fetched/NAME.json:
repository, path, commit) and this script fetches each file at that commit:

    raw URL  https://raw.githubusercontent.com/REPO/COMMIT/PATH
    -> its sha256 checked against SOURCE_SHA256 (the file as published at that commit)
    -> the three numeric columns kept as text (metadata, header and trailer lines dropped,
       tab/space/comma separators to commas, CRLF to LF) under the header mx,my,mz
    -> that CSV's sha256 checked against CSV_SHA256
    -> build/datasets/NAME.csv, with NAME.json beside it.

A file whose hash differs is not written. Offline, the script says so and exits 1.

    python tools/fetch_datasets.py              # download what is missing
    python tools/fetch_datasets.py --from DIR   # copy NAME.csv files from DIR instead (each
                                                # checked against CSV_SHA256); also the
                                                # environment variable ECOMPASS_DATASETS_FROM
    python tools/fetch_datasets.py --check      # exit 0 when every log is in place, else 1

Standard library only (CPython 3).
"""
import argparse
import hashlib
import json
import os
import shutil
import sys
import urllib.error
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROVENANCE = os.path.join(ROOT, "datasets", "fetched")
DEST = os.path.join(ROOT, "build", "datasets")
RAW_URL = "https://raw.githubusercontent.com/%s/%s/%s"
TIMEOUT_S = 30

# name: (sha256 of the source file at the recorded commit, sha256 of the CSV made from it)
PINS = {
    "fxos8700_michaelwro": (
        "30faa023b086c616257fd1d6b7e4e1131eb51f14cf33147a15b9e1af9797c1bd",
        "5c2ce68f4b929f575523c4bf09f550385529c0aaca8ba37557630452262e3773"),
    "hmc5883l_nliaudat_windvane_planar": (
        "664f4cbdbeee29220f37f10fbeacaf924524c9dba7a85741864ebbde2cebd627",
        "d631170144e54300f5cd907e5bd1c6aa1b885a62b38c210a116d0df3678a7b58"),
    "hmc5883l_rohankatreddy_3d": (
        "1a0738fc218bb27587d33488297f9a951ccd17cec2bd0c92ecdec78d2a685320",
        "006be2a82d283940e6aed0f2512760cfd61b4cd7f118b34d5d0f1017a720e956"),
    "icm20948_ak09916_jremington": (
        "0262da2ab3e20358618936679210678c274429c0eac76b627e368b79d205d2fb",
        "57cb2356d9ea00503d0c0a2bf1272feeabd55c49bc8b52991e01e362b4562945"),
    "lsm303_altimu10v3_jremington": (
        "7d951953496b6b4b97d6ad29433f51187471194494723d2c0dc646e6c98b091c",
        "119a91bc0769e4ee763880027944ed5461981f4ebb76504fc91c560942094065"),
    "lsm9ds1_jremington": (
        "7c40697304cb49a736461e615a38a345dd1387d752f02794cce2822061e47c33",
        "d5ecc1ed4a6fd018151dc17ac7b814252859fd3b5c774a71d4cd7b5af2af91b6"),
    "mag3_jremington_large_offset": (
        "c48747db24d9b6e6256bd4066d3d725b4353c6254833f939f645f3a8b21d208f",
        "c7ce4d9bd5701f4f8e6c2f9aedba97334bb4f0aa4167b4b81436e4532b3446e2"),
}


class Failure(Exception):
    offline = False


def sha256(data):
    return hashlib.sha256(data).hexdigest()


def provenance(name):
    with open(os.path.join(PROVENANCE, name + ".json")) as f:
        return json.load(f)


def url_of(name):
    meta = provenance(name)
    return RAW_URL % (meta["repo"], meta["commit"], urllib.request.quote(meta["path"]))


def to_csv(data):
    """The published file's x, y, z rows as text, under the header mx,my,mz: every line of
    exactly three numbers (commas, tabs or spaces between them) is kept; metadata, header and
    trailer lines (other field counts, or words) are not."""
    out = ["mx,my,mz"]
    for line in data.decode("utf-8").splitlines():
        fields = line.replace(",", " ").split()
        if len(fields) != 3:
            continue
        try:
            [float(v) for v in fields]
        except ValueError:
            continue
        out.append(",".join(fields))
    return ("\n".join(out) + "\n").encode()


def download(name):
    url = url_of(name)
    try:
        with urllib.request.urlopen(url, timeout=TIMEOUT_S) as r:
            data = r.read()
    except (urllib.error.URLError, OSError) as e:
        reason = getattr(e, "reason", e)
        f = Failure("%s: cannot download %s (%s): offline? Run `make datasets` with network "
                      "access, or `make datasets DATASETS_FROM=DIR` with a folder holding the "
                      "CSV files" % (name, url, reason))
        f.offline = True
        raise f
    want = PINS[name][0]
    if sha256(data) != want:
        raise Failure("%s: %s has sha256 %s, expected %s: not written"
                      % (name, url, sha256(data), want))
    return to_csv(data)


def copy_from(name, folder):
    path = os.path.join(folder, name + ".csv")
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise Failure("%s: cannot read %s (%s)" % (name, path, e.strerror or e))


def install(name, csv, dest):
    want = PINS[name][1]
    if sha256(csv) != want:
        raise Failure("%s: the CSV has sha256 %s, expected %s: not written"
                      % (name, sha256(csv), want))
    os.makedirs(dest, exist_ok=True)
    tmp = os.path.join(dest, name + ".csv.part")
    with open(tmp, "wb") as f:
        f.write(csv)
    os.replace(tmp, os.path.join(dest, name + ".csv"))
    shutil.copyfile(os.path.join(PROVENANCE, name + ".json"), os.path.join(dest, name + ".json"))


def present(name, dest):
    try:
        with open(os.path.join(dest, name + ".csv"), "rb") as f:
            return sha256(f.read()) == PINS[name][1] and os.path.exists(
                os.path.join(dest, name + ".json"))
    except OSError:
        return False


def main(argv=None):
    p = argparse.ArgumentParser(prog="fetch_datasets.py", description=__doc__.split("\n")[0])
    p.add_argument("--from", dest="source", metavar="DIR",
                   default=os.environ.get("ECOMPASS_DATASETS_FROM") or None,
                   help="copy NAME.csv from DIR instead of downloading (sha256 checked)")
    p.add_argument("--dest", default=DEST, help="where the logs go (default build/datasets)")
    p.add_argument("--check", action="store_true", help="only say whether every log is there")
    a = p.parse_args(argv)
    missing = [n for n in sorted(PINS) if not present(n, a.dest)]
    if a.check:
        for n in missing:
            print("missing: %s" % n)
        return 1 if missing else 0
    failed = 0
    for name in missing:
        try:
            csv = copy_from(name, a.source) if a.source else download(name)
            install(name, csv, a.dest)
            print("%s: %s" % (name, os.path.relpath(os.path.join(a.dest, name + ".csv"))))
        except Failure as e:
            print("make datasets: error: %s" % e, file=sys.stderr)
            failed += 1
            if e.offline:  # the others would wait for the same network
                failed = len(missing)
                break
    have = sum(1 for n in PINS if present(n, a.dest))
    print("%d of %d fetched logs in %s" % (have, len(PINS), os.path.relpath(a.dest)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
