# eCompass firmware: two commands do everything on a fresh machine with python3 (3.11).
#   make run    the compass on the simulated board
#   make test   the whole test suite, on CPython and on the MicroPython unix port
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
MPY    := $(VENV)/bin/micropython
STAMP  := $(VENV)/.installed-$(shell cksum < requirements.txt | cut -d' ' -f1)
BOARD  ?= rp2040
PORT   ?= /dev/ttyACM0
BUILD  := build/$(BOARD)

.PHONY: run test fuzz bench bench-smoke deploy mpy clean venv

venv: $(STAMP)

$(STAMP): requirements.txt
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	@rm -f $(VENV)/.installed-*
	@touch $@

run: $(STAMP)
	$(PY) -m host_sim run

test: $(STAMP)
	$(PY) -m pytest -q

fuzz: $(STAMP)
	HYPOTHESIS_PROFILE=fuzz $(PY) -m pytest -q tests

bench: $(STAMP)
	$(PY) -m host_sim bench

bench-smoke: $(STAMP)
	$(PY) -m host_sim bench --smoke

clean:
	rm -rf build .pytest_cache .hypothesis
