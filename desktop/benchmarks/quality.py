"""The calibration quality database (docs/quality.md): ingest and check time on SQLite.

ingest_benchmark() generates a simulated fleet (desktop/qualitydb/fleet.py) of about
`records` calibration records, writes them as JSON lines and times `python -m host_sim
quality ingest` into a new SQLite file (in-process: parsing, validation, duplicate look-up
and the one insert transaction; not the interpreter's start), then `check` with the learned
limits, and scores the flags against the fleet's known changes. Goal: 10,000 records
ingested in <= 5 s. CPython only (sqlite3).
"""
import contextlib
import io
import json
import os
import tempfile
import time

from desktop import quality
from desktop.qualitydb import fleet, limits, store

RECORDS_PER_DEVICE = 10      # fleet.generate draws 6..14 calibrations per device


def ingest_benchmark(records=10000, seed=1):
    """{records, ingest_s, records_per_s, check_s, flags, detection_rate,
    false_alarm_rate}: one run, wall-clock seconds."""
    recs, truth = fleet.generate(max(1, records // RECORDS_PER_DEVICE), seed)
    with tempfile.TemporaryDirectory(prefix="quality-bench-") as d:
        src = os.path.join(d, "fleet.jsonl")
        with open(src, "w") as f:
            for r in recs:
                f.write(json.dumps(r) + "\n")
        db = os.path.join(d, "bench.db")
        out = io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(out):
            rc = quality.main(["--db", db, "ingest", src])
        t_ingest = time.perf_counter() - t0
        if rc != 0:
            raise RuntimeError("ingest failed with exit status %d" % rc)
        t0 = time.perf_counter()
        s = store.Store(db)
        try:
            flags = limits.check(s.rows(), limits.Limits())
        finally:
            s.close()
        t_check = time.perf_counter() - t0
    sc = fleet.score(flags, truth)
    return {"records": len(recs), "devices": len(truth), "ingest_s": round(t_ingest, 3),
            "records_per_s": round(len(recs) / t_ingest),
            "check_s": round(t_check, 3), "flags": len(flags),
            "detection_rate": sc["detection_rate"], "false_alarm_rate": sc["false_alarm_rate"],
            "goal_ingest_s": 5.0}


def main():
    from desktop.benchmarks import common
    common.emit(ingest_benchmark(2000 if common.smoke() else 10000))


if __name__ == "__main__":
    main()
