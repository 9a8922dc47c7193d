# Everything a fresh machine needs: a virtual environment with the package and its
# dependencies (pyproject.toml), then the job.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test lint bench docs clean browser

# The browser tests (view, monitor) drive Debian's Chromium through Playwright; install it
# with apt-get when it is missing (root or sudo), quietly, and only once.
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  echo "installing Debian's chromium (browser tests)"; \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq >/dev/null && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
	    chromium fonts-dejavu-core >/dev/null; }

$(BIN)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[dev]'
	touch $@

demo: $(BIN)/.installed
	$(BIN)/motioncue demo

# pytest-xdist with two workers per core (-n auto, tests/conftest.py: many tests wait rather
# than compute), each test module (or class) on one worker, so that a module's fixtures are
# built once, the longest units handed out first, those that mostly wait (emulators, playback,
# a browser) beside those that compute (tests/conftest.py). No wall-clock figure is
# asserted here; those are in make bench.
# PYTEST_ARGS adds options, e.g. make test PYTEST_ARGS=--cpu-durations=40 (CPU time per test,
# tests/conftest.py: the figure to compare on a busy machine).
PYTEST_ARGS ?=
# The package is byte-compiled first: where PYTHONDONTWRITEBYTECODE is set (as on the machines
# this was measured on), every `python -m motioncue` the tests start would compile it again
# from source (about 0.25 s of CPU a start). pytest runs without PYTHONDONTWRITEBYTECODE, so
# that it keeps the test modules it rewrote for its assertion messages (tests/__pycache__,
# ignored by git): each worker collects every module, and collecting costs 10.7 s of CPU with
# the rewriting against 3.4 s from that cache (pytest --collect-only). On a fresh clone the
# four workers would each rewrite every module (43 s of CPU, about 21 s on two cores before
# the first test); so the modules are rewritten first, once, by two collections of half the
# modules each, one per core (11.5 s of CPU, about 6 s), and the workers then read the cache
# (4 x 3.4 s). Its outcome is not used: the run proper reports any collection error. Each half
# collects tests/ without the other half's modules (--ignore-glob): named one by one on the
# command line, pytest walks the whole tests/ folder again for every file named (2.7 s more).
test: $(BIN)/.installed browser
	$(BIN)/python -m compileall -q src
	-env -u PYTHONDONTWRITEBYTECODE sh -c '\
	  $(BIN)/python -m pytest --collect-only -q -p no:cacheprovider tests --ignore-glob="tests/test_[m-z]*.py" & \
	  $(BIN)/python -m pytest --collect-only -q -p no:cacheprovider tests --ignore-glob="tests/test_[a-l]*.py"; \
	  wait' >/dev/null 2>&1
	env -u PYTHONDONTWRITEBYTECODE $(BIN)/python -m pytest -n auto --dist loadscope $(PYTEST_ARGS)

lint: $(BIN)/.installed
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy

docs: $(BIN)/.installed
	$(BIN)/python -m sphinx -W -b html docs docs/_build/html

bench: $(BIN)/.installed
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV)
