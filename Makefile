# dxboard: the two commands are `make run` and `make test` (see README.md).
# Both create or reuse .venv and install the project with what it needs first.

PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test lint pytest mpytest bench browser clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,ros]'
	touch $(STAMP)

# The main job on the emulated board: the daemon keeps the virtual TEDUSAR robot healthy,
# its nodes real ROS 2 nodes (DXBOARD_MIDDLEWARE=zenoh make run: plain Zenoh instead).
# A development key lets a person switch channels too (see README.md).
DXBOARD_MIDDLEWARE ?= ros2
CONTROL ?= 127.0.0.1:7001
WEB     ?= 127.0.0.1:8080
DEV_KEY := .dxboard-dev.key
run: $(STAMP)
	test -s $(DEV_KEY) || (umask 077; $(BIN)/python -c "import secrets; print(secrets.token_hex(32))" > $(DEV_KEY))
	@echo "dxboard: the TEDUSAR robot ($(DXBOARD_MIDDLEWARE)) on the emulated board; open the web address below."
	@echo "  try: .venv/bin/dxboard inject $(CONTROL) hokuyo hang    (Ctrl-C stops everything)"
	$(BIN)/dxboard run models/tedusar --emulate --middleware $(DXBOARD_MIDDLEWARE) \
		--control $(CONTROL) --web $(WEB) --journal dxboard-journal.sqlite --key-file $(DEV_KEY)

test: $(STAMP) lint pytest mpytest

lint: $(STAMP)
	$(BIN)/ruff check protocol firmware emulator host tests benchmarks
	$(BIN)/mypy

pytest: $(STAMP) browser
	$(BIN)/pytest

# Debian's headless Chromium, for the web page's tests (installed when root and missing).
browser:
	scripts/ensure-chromium

# The protocol and firmware tests again, under the real MicroPython interpreter.
mpytest: $(STAMP)
	$(BIN)/micropython tests/mpy_run.py

BENCH_STAMP := $(VENV)/.bench-installed
$(BENCH_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,ros,bench]'
	touch $(BENCH_STAMP)

# Every benchmark, in turn (several minutes); figures go to benchmarks/RESULTS.md by hand.
bench: $(BENCH_STAMP)
	$(BIN)/python benchmarks/codec.py
	$(BIN)/python benchmarks/board_firmware.py
	$(BIN)/python benchmarks/transport.py
	$(BIN)/python benchmarks/diagnosis.py --quick
	$(BIN)/python benchmarks/planning.py --quick
	$(BIN)/python benchmarks/journal.py
	$(BIN)/python benchmarks/plandiag.py --quick

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
