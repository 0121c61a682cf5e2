"""What `make bench` runs on each interpreter (desktop/bench.py drives them).

Each module is a script: `python -m desktop.benchmarks.NAME [--smoke]` and
`micropython -m desktop.benchmarks.NAME [--smoke]` print ONE JSON object on stdout.
  hot        item 1: the per-sample path (driver decode, correct, axes, heading) against the
             float path of the heading guide, time and bytes per sample
  collector  item 2: Calibrator.add per raw sample, empty and full buffer
  solver     item 3: solve time per model, the time-sliced solve's longest step
  memory     item 4: heap in use after importing the firmware and with a full buffer
  yardstick  item 6: reference loops whose per-iteration cost is published for the boards
CPython only (numpy / exact op counts): accuracy (item 5), intcount (item 6's long-int share).
"""
