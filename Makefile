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

.PHONY: help run test fuzz bench bench-smoke deploy mpy package-json clean venv quality-pg wmm wasm test-arm web soak tiers postgres datasets

# make help: every target with one line (the `##` comment after its name)
help:  ## list the targets
	@sed -n 's/^\([a-z0-9-]*\):.*## \(.*\)/  \1\t\2/p' $(MAKEFILE_LIST) | expand -t 16

venv: $(STAMP)  ## create .venv from requirements.txt (every target does it)

$(STAMP): requirements.txt
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	@rm -f $(VENV)/.installed-*
	@touch $@

run: $(STAMP)  ## the compass on the simulated board; writes build/calibration.png and docs/design.md's excerpt of it
	$(PY) -m host_sim run --update-doc

# -rs: one line per skip reason (each says what to run or install to run those tests too)
test: $(STAMP) wasm web tiers postgres  ## the whole test suite on CPython and MicroPython
	$(PY) -m pytest -q -rs

# --- 32-bit test tiers (tests/mp.py) -------------------------------------------------------
# wasm: the MicroPython WebAssembly port from npm (tests/wasm/package.json), installed into
# build/npm/node_modules (outside the sources) once per package-lock.json; without node or npm
# the tier's tests skip.
WASM_DIR   := tests/wasm
NPM_DIR    := build/npm
WASM_STAMP := $(NPM_DIR)/node_modules/.installed-$(shell cksum < $(WASM_DIR)/package-lock.json | cut -d' ' -f1)

wasm:  ## install the WebAssembly test tier from npm (skips without node)
	@if ! command -v node >/dev/null 2>&1; then echo "wasm tier skipped: node not found on PATH (install Node.js and npm, then make wasm)"; \
	elif ! command -v npm >/dev/null 2>&1; then echo "wasm tier skipped: npm not found on PATH (install npm, then make wasm)"; \
	elif [ ! -f $(WASM_STAMP) ]; then \
	  mkdir -p $(NPM_DIR) && cp $(WASM_DIR)/package.json $(WASM_DIR)/package-lock.json $(NPM_DIR)/ && \
	  if npm ci --prefix $(NPM_DIR) --no-audit --no-fund --loglevel=error; then touch $(WASM_STAMP); \
	  else echo "wasm tier skipped: npm ci failed ($(NPM_DIR)/node_modules not installed)"; fi; \
	fi

# web: the browser calibrator (docs/web.md): vendors the WebAssembly port into web/vendor/
# (git-ignored) with bundle.js, what web/index.html opened from file:// loads, and, as root,
# installs Debian's chromium for tests/test_web.py when missing.
web: $(STAMP) wasm  ## vendor the WebAssembly port into web/ for the browser calibrator; chromium for its test
	@if [ ! -x /usr/bin/chromium ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
	      || echo "browser tier will skip: apt-get install chromium failed"; \
	  else echo "browser tier will skip: /usr/bin/chromium missing (as root: apt-get install -y chromium)"; fi; \
	fi
	@if [ -d $(NPM_DIR)/node_modules/@micropython ]; then $(PY) -m host_sim web --vendor; \
	else echo "web/vendor not made: $(NPM_DIR)/node_modules missing (make wasm needs node and npm)"; fi

# tiers: the 32-bit interpreters of the x86-32 and arm tiers, in build/tools (tests/mp.py).
# The registries carry none, so tools/build-micropython-tiers.sh builds them from a MicroPython
# source tree at the pinned tag, v1.28.0 (`make tiers` without one prints the three commands:
# clone it into build/micropython, its micropython-lib submodule, MICROPYTHON_SRC=... make
# tiers; gcc-multilib, about 2 min on 2 cores); PREBUILT_TOOLS=DIR copies prebuilt ones from DIR
# (no default: .ci/run passes where CI keeps them). Without either, those tiers skip and say why.
TOOLS_DIR      := build/tools
PREBUILT_TOOLS ?=
TIER_FILES     := micropython-x86-32 mpy-cross-x86-32 micropython-qemu-mps2-an385-armv6m.elf
# the tag tools/build-micropython-tiers.sh pins (PIN_TAG)
MICROPYTHON_TAG := v1.28.0
tiers:  ## the 32-bit tiers' MicroPython builds in build/tools (MICROPYTHON_SRC=DIR: a v1.28.0 checkout)
	@if [ -x $(TOOLS_DIR)/micropython-x86-32 ]; then :; \
	elif [ -n "$(MICROPYTHON_SRC)" ]; then \
	  MICROPYTHON_SRC="$(MICROPYTHON_SRC)" tools/build-micropython-tiers.sh all \
	    || echo "x86-32/arm tiers will skip: tools/build-micropython-tiers.sh failed (it needs MicroPython v1.28.0 with lib/micropython-lib, gcc-multilib for x86-32, gcc-arm-none-eabi for arm)"; \
	elif [ -n "$(PREBUILT_TOOLS)" ] && [ -x "$(PREBUILT_TOOLS)/micropython-x86-32" ]; then \
	  mkdir -p $(TOOLS_DIR) && for f in $(TIER_FILES); do \
	    [ -f $(PREBUILT_TOOLS)/$$f ] && cp -p $(PREBUILT_TOOLS)/$$f $(TOOLS_DIR)/; done; \
	  echo "x86-32/arm tiers: prebuilt interpreters copied from $(PREBUILT_TOOLS) into $(TOOLS_DIR)"; \
	else echo "x86-32/arm tiers will skip: no build in $(TOOLS_DIR). To build them (gcc-multilib; about 2 min):"; \
	  echo "  git clone --depth 1 --branch $(MICROPYTHON_TAG) https://github.com/micropython/micropython build/micropython"; \
	  echo "  git -C build/micropython submodule update --init lib/micropython-lib"; \
	  echo "  MICROPYTHON_SRC=build/micropython make tiers"; fi

# arm: the parity scenarios on the Cortex-M qemu firmware (build/tools, make tiers; minutes;
# not in `make test`). Installs qemu-system-arm from Debian when missing and run as root.
test-arm: $(STAMP) tiers  ## parity scenarios on the qemu Cortex-M tier (minutes)
	@if ! command -v qemu-system-arm >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    apt-get update -qq && apt-get install -y -qq qemu-system-arm >/dev/null || exit 1; \
	  else echo "arm tier skipped: qemu-system-arm missing (as root: apt-get install -y qemu-system-arm)"; exit 0; fi; \
	fi; \
	ARM_TIER=1 $(PY) -m pytest -q -p no:randomly tests/test_tiers.py -k arm

fuzz: $(STAMP)  ## hypothesis properties with many more examples
	HYPOTHESIS_PROFILE=fuzz $(PY) -m pytest -q tests

bench: $(STAMP) tiers  ## speed, memory, accuracy; writes docs/benchmarks.md
	$(PY) -m host_sim bench

soak: $(STAMP)  ## the seeded fault campaign (writes its table into docs/faults.md), then the mounting check's: minutes; fails on a missed goal
	rc=0; \
	$(PY) -m host_sim soak --sessions 600 --seconds 60 --seed 1 --doc docs/faults.md || rc=$$?; \
	$(PY) -m desktop.mounting --sessions 600 --seconds 40 --seed 1 || rc=$$?; \
	exit $$rc

bench-smoke: $(STAMP)  ## a quick run of the benchmarks
	$(PY) -m host_sim bench --smoke

# `host_sim quality` on a throwaway PostgreSQL server (docs/quality.md, tests/test_quality.py
# starts and stops it): Debian's postgresql is installed when its binaries are missing and we
# are root, as `web` installs chromium; otherwise those tests skip and say this command.
postgres:  ## install Debian's postgresql for the quality database tests (root; skips otherwise)
	@if ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq postgresql >/dev/null) \
	    || echo "postgresql tests will skip: apt-get install postgresql failed"; \
	else echo "postgresql tests will skip: no server binaries (as root: apt-get install -y postgresql)"; fi

quality-pg: $(STAMP) postgres  ## the quality database test on a throwaway PostgreSQL
	$(PY) -m pytest -q -rs tests/test_quality.py -k postgresql

# --- deploy to a board -------------------------------------------------------------------
# make deploy BOARD=rp2040 PORT=/dev/ttyACM0   (make -n deploy ... prints the commands)
ARCH_rp2040 := armv6m
ARCH_esp32  := xtensawin
ARCH        := $(ARCH_$(BOARD))
MPREMOTE    := $(VENV)/bin/mpremote connect $(PORT)

mpy: $(STAMP)  ## compile firmware/ to .mpy for BOARD=rp2040|esp32 into build/
	@test -n "$(ARCH)" || { echo "unknown BOARD=$(BOARD): use rp2040 or esp32"; exit 2; }
	rm -rf $(BUILD) && mkdir -p $(BUILD)/lib/firmware
	for f in $$(cd firmware && find . -name '*.py' | sort); do \
	  mkdir -p $(BUILD)/lib/firmware/$$(dirname $$f) && \
	  $(VENV)/bin/mpy-cross -march=$(ARCH) -o $(BUILD)/lib/firmware/$${f%.py}.mpy firmware/$$f || exit 1; \
	done
	cd firmware && find . -name '*.bin' -exec cp --parents {} ../$(BUILD)/lib/firmware/ \;
	cp boards/$(BOARD)/board.py boards/main.py $(BUILD)/

deploy: mpy  ## copy firmware, board.py, main.py to the board at PORT
	$(MPREMOTE) fs mkdir :lib || true
	$(MPREMOTE) fs cp -r $(BUILD)/lib/firmware :lib/
	$(MPREMOTE) fs cp $(BUILD)/board.py :board.py
	$(MPREMOTE) fs cp $(BUILD)/main.py :main.py
	$(MPREMOTE) reset

# the real logs whose licences keep them out of the repository (datasets/README.md), pinned by
# sha256, into build/datasets; DATASETS_FROM=DIR copies them from a folder instead
datasets:  ## fetch the real logs the repository does not ship into build/datasets (pinned)
	$(PYTHON) tools/fetch_datasets.py $(if $(DATASETS_FROM),--from $(DATASETS_FROM))

# the board's World Magnetic Model table (committed; docs/field_model.md)
wmm: $(STAMP)  ## regenerate firmware/field/wmm2025.bin
	$(PY) -m host_sim wmm

package-json: $(STAMP)  ## regenerate package.json and the parts package-PART.json (mip install)
	$(PY) -m desktop.packaging --write

clean:  ## remove build/ and test caches
	rm -rf build .pytest_cache .hypothesis
