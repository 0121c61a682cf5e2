"""make bench (desktop/bench.py): the smoke run completes on both interpreters, writes a
JSON of the agreed shape, and its figures are sane. No timing assertions: times depend on the
machine; what is asserted has a reason independent of the code measured."""
import json
import math
import os
import subprocess
import sys

import pytest

from desktop import bench

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("bench") / "bench.json")
    doc = os.path.join(ROOT, "docs", "benchmarks.md")
    before = open(doc).read() if os.path.exists(doc) else None
    p = subprocess.run([sys.executable, "-m", "host_sim", "bench", "--smoke", "--json", out],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    after = open(doc).read() if os.path.exists(doc) else None
    assert after == before  # smoke numbers never reach docs/benchmarks.md
    with open(out) as f:
        return json.load(f), p.stdout


def test_smoke_writes_the_json_with_every_item_on_both_interpreters(smoke):
    d, _ = smoke
    assert d["smoke"] is True
    for k in ("date_utc", "uname_m", "cpu", "python", "micropython"):
        assert d["machine"][k]
    res = d["results"]
    for name in ("yardstick", "hot", "collector", "solver", "appbench"):
        for interp in ("cpython", "micropython"):
            r = res[name][interp]
            assert "error" not in r, (name, interp, r)
            assert r["interpreter"].startswith("CPython" if interp == "cpython" else
                                               "MicroPython")
    for name in ("accuracy", "intcount"):
        assert "error" not in res[name]["cpython"], res[name]
    assert "error" not in res["memory"]["py"] and "error" not in res["memory"]["mpy"]
    assert res["memory"]["mpy"]["frozen_or_mpy"] == "mpy"
    assert all(len(row) == 5 for row in d["table"])


def test_smoke_prints_the_table(smoke):
    d, out = smoke
    assert "ratio / goal" in out and "verdict" in out
    for row in d["table"]:
        assert row[0] in out


def test_per_sample_path_allocates_nothing_and_fast_path_gives_the_same_headings(smoke):
    d, _ = smoke
    mp = d["results"]["hot"]["micropython"]
    # proven elsewhere with heap_lock and mem_total (drivers_alloc, compass_alloc,
    # fast_parity): the measurement must agree
    for path in ("ours", "ours_fast"):
        assert mp["bytes_per_sample"][path] == {"mem_alloc": 0, "mem_total": 0}
        assert mp["heap_locked"][path] == "ok"
    # the float path boxes every float on MicroPython: the instrument does see allocation
    assert mp["bytes_per_sample"]["float"]["mem_alloc"] > 0
    assert mp["viper"] is True and d["results"]["hot"]["cpython"]["viper"] is False
    same, total = mp["fast_identical"]
    assert same == total > 0
    # both paths compute a heading from the same bytes: a real calibration each, so they
    # agree to a few degrees (min/max cannot undo the rotated soft iron entirely)
    assert mp["heading_diff_deg"]["median"] < 10


def test_times_are_positive_and_parts_add_up(smoke):
    d, _ = smoke
    for interp in ("cpython", "micropython"):
        h = d["results"]["hot"][interp]
        for k, v in h["us_per_sample"].items():
            assert v > 0, (interp, k)
        assert h["float_cpu_us"] > 0 and h["ours_cpu_us"] > 0 and h["fast_cpu_us"] > 0
        c = d["results"]["collector"][interp]
        assert c["phases"]["empty"]["us_per_raw"] > 0 and c["phases"]["full"]["us_per_raw"] > 0
        s = d["results"]["solver"][interp]
        assert all(s["solve_us"][m] > 0 for m in ("minmax", "4", "7", "10"))
        assert s["sliced_10"]["longest_us"] <= s["sliced_10"]["total_us"]
        # a real fit: more parameters, a smaller residual on the same rotated soft iron
        assert s["fit_error_x100"]["10"] < s["fit_error_x100"]["4"]
        a = d["results"]["appbench"][interp]
        assert a["solves"] > 0 and a["accepted"] > 0 and a["model"] == 10


def test_memory_figures_are_consistent(smoke):
    d, _ = smoke
    m = d["results"]["memory"]["py"]
    fb = m["firmware_bytes"]
    assert 0 < fb["imports"] < fb["app_start"] <= fb["peak_solving"]
    assert m["held"] <= m["capacity"]
    # the buffer's arrays alone: data and cells 2 x 6 bytes per slot plus the hash table
    assert m["array_bytes"] >= 12 * m["capacity"]


def test_accuracy_figures(smoke):
    d, _ = smoke
    acc = d["results"]["accuracy"]["cpython"]
    rot = acc["headings"]["rotated_soft_iron"]
    # min/max scales the axes only: it cannot undo a rotated soft-iron matrix; the
    # 10-element fit can
    assert rot["10"]["ours"]["rms_deg"] < rot["minmax_seed004_float"]["rms_deg"]
    assert rot["10"]["ratio_rms"] > 0
    logs = acc["logs"]
    assert logs and all(isinstance(v, dict) for v in logs.values())
    # the smoke run's log ships in datasets/: the calibrate command at its default settings
    # against a float64 fit of every row (docs/calibration.md's table, in full by make bench)
    from desktop.benchmarks.accuracy import COMMAND_GOAL, SMOKE_LOG
    cmd = acc["commands"][SMOKE_LOG]
    assert "refused" not in cmd and 0 < cmd["ratio"] <= COMMAND_GOAL
    row = [r for r in d["table"] if r[0].startswith("5 logs: calibrate at default settings")]
    assert len(row) == 1 and row[0][-1] == "met"


def test_yardstick_and_board_estimates(smoke):
    d, _ = smoke
    y = d["results"]["yardstick"]["micropython"]
    assert y["pi_1000_check"] == "3141592653589793238462643383279"  # pi, 30 decimals
    b = d["boards"]
    # three reads per sample at 400 kHz: 9 bits per byte, 3 address/register bytes each,
    # START + repeated START + STOP: (4 + 9 + 9) x 9 + 3 x 3 = 207 bits
    assert b["i2c_wire_us_per_sample"] == pytest.approx(207 / 400000 * 1e6)
    for board in ("rp2040_125mhz", "esp32_160mhz", "esp32_240mhz"):
        e = b[board]
        assert e["scale_int"] > 1 and e["long_int_op_us"] > 0
        assert e["solve"]["10"]["estimate_ms"] <= e["solve"]["10"]["upper_ms"]
    # the 240 MHz figure is the 160 MHz one scaled by the clock
    assert b["esp32_240mhz"]["scale_int"] == pytest.approx(b["esp32_160mhz"]["scale_int"]
                                                           * 160 / 240)


def test_merge_takes_the_median_of_each_number():
    runs = [{"a": 1, "b": [1, 5], "c": {"d": 3.0}, "s": "x"},
            {"a": 9, "b": [2, 6], "c": {"d": 1.0}, "s": "y"},
            {"a": 2, "b": [3, 4], "c": {"d": 2.0}, "s": "z"}]
    m = bench.merge(runs)
    assert m["a"] == 2 and m["b"] == [2, 5] and m["c"] == {"d": 2.0} and m["s"] == "x"
    assert m["processes"] == 3
    assert bench.merge([{"error": "boom"}]) == {"error": "boom"}


def test_the_benchmark_page_is_written_whole_with_its_generated_notice(tmp_path):
    p = tmp_path / "docs" / "benchmarks.md"
    bench.write_doc("one", str(p))
    bench.write_doc("two", str(p))
    text = p.read_text()
    assert text.startswith("# Benchmarks\n") and "make bench" in text
    assert "two" in text and "one" not in text


def test_wire_time_formula():
    assert bench.wire_us(6) == pytest.approx((9 * 9 + 3) * 2.5)
    assert not math.isnan(bench.wire_us(0))


def test_the_fault_campaign_is_in_the_bench(smoke):
    # the smoke run's campaign: tiny, but the whole path (desktop/benchmarks/soak.py)
    d, out = smoke
    q = d["results"]["soak"]["cpython"]
    assert "error" not in q, q
    assert q["exceptions"] == 0 and q["lost"] == 0 and q["wrong_but_ok"] == 0
    assert q["report"][0].startswith("soak: %d sessions" % q["sessions"])
    assert any(row[0].startswith("8 fault campaign") for row in d["table"])
    section = bench.soak_section(d["results"])
    assert section.startswith(bench.SOAK_BEGIN) and section.endswith(bench.SOAK_END)
    assert "    wrong-but-ok" not in section and "wrong-but-ok 0" in section


def test_the_soak_block_is_replaced_alone(tmp_path):
    p = tmp_path / "benchmarks.md"
    p.write_text("# Benchmarks\n\n%s\ntable\n%s\n" % (bench.BEGIN, bench.END))
    bench.splice_soak("%s\nfirst\n%s" % (bench.SOAK_BEGIN, bench.SOAK_END), str(p))
    bench.splice_soak("%s\nsecond\n%s" % (bench.SOAK_BEGIN, bench.SOAK_END), str(p))
    text = p.read_text()
    assert "second" in text and "first" not in text and "table" in text
    assert text.index(bench.SOAK_END) < text.index(bench.END)


def test_board_time_from_qemu_instruction_counts_is_repeatable_and_plausible():
    # benchmarks/boardtime.py in the Cortex-M guest under -icount shift=0: the counts are the
    # same on a second run, and the RP2040 factors they give are those of a real board
    from desktop import bench
    import shutil
    if not shutil.which("qemu-system-arm") or not os.path.exists(bench.QEMU_ELF):
        pytest.skip("qemu-system-arm or the qemu firmware is missing (make tiers; as root: "
                    "apt-get install -y qemu-system-arm)")
    a = bench.boardtime()
    b = bench.boardtime()
    assert "error" not in a, a

    def same(x, y):  # to a thousandth: the guest's clock ticks in microseconds
        return abs(x - y) <= 1 + x / 1000
    for k in ("int_add_per_1000", "pi_1000"):
        assert same(a["yardstick_kinstr"][k], b["yardstick_kinstr"][k])
    assert same(a["solve_kinstr"]["total"], b["solve_kinstr"]["total"])
    for kind in ("fast", "plain"):
        assert same(a["step_kinstr"][kind], b["step_kinstr"][kind])
    assert a["step_kinstr"]["fast"] < a["step_kinstr"]["plain"] < a["collect_kinstr"]["plain"]
    e = bench.rp2040_from_icount(a)
    # an M0+ at 125 MHz: 1 to 3 cycles for each instruction the M3 guest counts
    assert all(1.0 < k < 3.0 for k in e["cycles_per_instr"].values()), e["cycles_per_instr"]
    assert 0 < e["slices_past_5ms"] <= e["slices"] and e["solve_ms"][0] > 50


def test_the_bench_sweeps_boards_main_and_no_run_ends_in_a_traceback(smoke):
    d, _ = smoke
    bs = d["results"].get("board_sweep")
    if bs is None:
        from tests.mp import TIERS
        pytest.skip("x86-32 tier (the sweep needs its collector): %s" % TIERS["x86-32"].reason)
    assert "error" not in bs, bs
    for name in ("mpy_first", "mpy_stored", "mip_first", "mip_stored"):
        assert bs[name]["heaps"] == 3 and bs[name]["tracebacks"] == [], (name, bs[name])
    assert bs["mpy_stored"]["smallest_kb"] is not None  # 160 and 320 KB boot a calibrated board
    lines = bench.board_sweep_rows(d["results"])
    assert any(ln.startswith("| .mpy files") for ln in lines)


def test_a_run_without_every_real_log_leaves_the_log_table_alone(capsys):
    # docs/calibration.md's table lists every log (tests/test_datasets.py): a bench run on a
    # clone without `make datasets` must not cut it down to the shipped ones
    from desktop import bench as B
    path = os.path.join(ROOT, "docs", "calibration.md")
    before = open(path).read()
    res = {"accuracy": {"cpython": {"commands": {"qmc5883l_tomisuarez_filtered": {}}}}}
    assert B.splice_logs(res) is False
    assert open(path).read() == before
    assert "make datasets" in capsys.readouterr().out
