"""Memory budgets that fail the build (tests/test_budgets.py) and that `make bench` prints beside
the measured figures (docs/benchmarks.md). Bytes, measured on a 32-bit MicroPython (the x86-32
unix build: 4-byte words, 31-bit small ints, a collector that runs as a board's does), with the
board profiles of benchmarks/profiles.py (boot as boards/main.py boots). A budget is the
figure measured when it was set plus a small margin: a change that costs more heap than that
has to say so here, in the same commit. The issue's goals are in bench.py GOALS; where a goal
is not met yet, the budget holds the line at what is.
"""
KB = 1024

BUDGETS = {
    # a calibrated board, .mpy files: live heap after boot + 1000 headings (55.7 KB measured
    # once the trig tables were held once; 57.2 KB once the app's state had owners: Health
    # holds the drivers' fault handling, the constants one home each; 58.4 KB once the
    # objects a step calls keep spare slots in their attribute tables, firmware/compat.py
    # room: the app's step a fifth faster on the unix port, docs/design.md, memory)
    # 59,728 B in every lone run; one process of a whole `make test` read 60,800 B (what a
    # conservative collector keeps alive can differ from process to process)
    "heading_live_mpy": 60 * KB,
    # the same from frozen / ROMFS bytecode
    "heading_live_romfs": 35 * KB,
    # a first calibration session that has ended, minus the line above (.mpy): the names the
    # calibration machinery interned stay in the qstr pool when its modules are dropped
    "after_session_slack_mpy": 5 * KB,  # 3.0 KB measured with calibration mode's names
    # the live heap at the solving peak of the calibration program (.mpy,
    # bench.PROGRAM_PROFILE_KB of heap): 93.6-95.5 KB measured (calibration mode's, which it
    # replaced, was 115.8 KB)
    "program_peak_mpy": 100 * KB,
    # a heap from which the calibration program completes (10 elements saved and read back),
    # in it and in each of the 7 KB above (the recorded session's bytes and the ROMFS
    # image's not counted). Not monotone: in another heap the collector runs at other
    # moments. .mpy: 128.7 KB measured when set (calibration mode's first calibration needed
    # 140 KB)
    "min_heap_calibrate_mpy": 136 * KB,
    "min_heap_calibrate_romfs": 100 * KB,
    # the gyro-aided heading (use_gyro(), .mpy): live heap after boot + 1000 headings, minus
    # the heading line above (docs/gyro.md's goal: 8 KB). 7,056 B measured once the figures
    # stopped depending on where the checkout is (the .mpy files compiled as `make mpy` does,
    # naming their source "firmware/X.py"; each run in a folder of its own, with relative
    # names): the 8,240 B measured before held each module's absolute source name. 8,256 B
    # once the filter's modules sit in their part's folder (firmware/gyro/: the folder's
    # module object, ~0.3 KB)
    "gyro_extra_mpy": 8 * KB + 512,
    # boards/main.py itself over the replayed figure-8 (benchmarks/boardrun.py, the status
    # line printed every 0.5 s): the smallest heap from which every larger heap of the sweep
    # completes (tests/test_heap_sweep.py, 32 KB steps), for a first calibration and for a
    # board booting on a stored one, from .mpy files and from .py sources. In 4 KB steps when
    # set: 144, 200, 92 and 104 KB; the calibration program's first calibration, restart
    # and headings: 124-128 and 152 KB (make bench writes the figures of its run to
    # docs/install.md)
    "board_calibrate_mpy": 160 * KB,
    "board_calibrate_py": 192 * KB,
    "board_heading_mpy": 96 * KB,
    "board_heading_py": 128 * KB,
    # bytes allocated per sample once the board shows headings
    "bytes_per_sample": 0,
}
