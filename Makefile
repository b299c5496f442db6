# dxboard: the two commands are `make run` and `make test` (see README.md).
# Both create or reuse .venv and install the project with what it needs first.

PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test check lint pytest mpytest bench browser prometheus docs clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,ros]'
	touch $(STAMP)

# The main job on the emulated board: the daemon keeps the virtual TEDUSAR robot healthy,
# its nodes real ROS 2 nodes (DXBOARD_MIDDLEWARE=zenoh make run: plain Zenoh instead).
# A development key lets a person switch channels too (see docs/getting-started.md).
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

# pytest-xdist: most tests wait on processes they start, so more workers than cores pay off;
# --dist loadfile keeps a file's tests (and its module fixtures) on one worker.
PYTEST_WORKERS ?= 4

# Every part runs even when an earlier one fails (a red pytest must not hide the MicroPython
# run); the exit status is a failure if any part failed.
test: $(STAMP)
	@status=0; \
	$(MAKE) --no-print-directory lint || status=1; \
	$(MAKE) --no-print-directory pytest || status=1; \
	$(MAKE) --no-print-directory mpytest || status=1; \
	if [ $$status -ne 0 ]; then echo "make test: a part failed (see above)" >&2; fi; \
	exit $$status

# The fast tier: lint and the tests that start no process (a test that would start one is
# skipped there; `make test` runs it). Minutes, not tens of minutes.
check: $(STAMP) lint
	$(BIN)/pytest --in-process -n $(PYTEST_WORKERS) --dist loadfile

lint: $(STAMP)
	$(BIN)/ruff check protocol firmware emulator host tests benchmarks scripts hardware ros
	$(BIN)/mypy
	$(BIN)/python scripts/layers.py
	$(BIN)/python scripts/names.py --check

pytest: $(STAMP) browser prometheus
	$(BIN)/pytest -n $(PYTEST_WORKERS) --dist loadfile

# Debian's Prometheus and Alertmanager, for the fleet's tests (installed when root and missing).
prometheus:
	scripts/ensure-prometheus

# Debian's headless Chromium, for the web page's tests (installed when root and missing).
browser:
	scripts/ensure-chromium

# The protocol and firmware tests again, under the real MicroPython interpreter.
mpytest: $(STAMP)
	$(BIN)/micropython tests/mpy_run.py

# The docs site (mkdocs-material) into site/: the reference pages are made from the code as it
# builds (scripts/gen_docs.py); --strict fails on a broken link or a missing page (tests/docs/
# check the same).
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

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
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache site
