# The README's commands. Both work as root on a bare Debian 12 / Python 3.11 machine with no display:
# they create or update the local venv from pyproject.toml and install the missing Debian packages.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.bladecam-installed
# Debian packages the Qt/VTK window needs under a virtual X server (most ship with the image).
DEBS   := xvfb xauth libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0 libxcb-xinerama0 \
          libxcb-randr0 libxcb-shape0 libxcb-cursor0 libxkbcommon-x11-0 libgl1 libegl1 libglx-mesa0 \
          libgl1-mesa-dri libxrender1 libfontconfig1 libdbus-1-3

# What pip needs to compile the Cython parts (Cython -> C): a C compiler, libc's and Python's headers.
BUILD_DEBS := gcc libc6-dev python3-dev

.PHONY: run test test-all bench sysdeps builddeps venv lint package clean

venv: $(STAMP)

# (pip builds the compiled parts from their Cython sources: a changed source is built again)
# (every compiled module: core/<package>/_<name>.pyx, listed in setup.py)
PYX    := $(wildcard core/*/_*.pyx)

$(STAMP): pyproject.toml setup.py $(PYX) | builddeps
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@echo "installing the Python packages (about a minute)"
	@$(PY) -m pip install --disable-pip-version-check -q -e '.[test]'
	@touch $(STAMP)

builddeps:
	@missing=""; for p in $(BUILD_DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages to build the CSV formatter:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO="sudo"; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

sysdeps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO="sudo"; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

# With a display: the workbench. Without one: the sample blade planned from the command line into
# out/sample, and a picture of the workbench showing it (on a virtual X server) beside it.
run: venv sysdeps
	@if [ -n "$$DISPLAY" ] || [ -n "$$WAYLAND_DISPLAY" ]; then $(PY) -m bladecam_gui; else \
	  echo "no display: planning the sample blade from the command line, then a picture of the workbench"; \
	  $(PY) -m core plan --out out/sample && \
	  xvfb-run -a -s "-screen 0 1600x1000x24" $(PY) -m bladecam_gui --screenshot out/sample-workbench.png && \
	  echo "the plan: $(CURDIR)/out/sample (re-check it: $(PY) -m core verify out/sample)" && \
	  echo "the workbench: $(CURDIR)/out/sample-workbench.png"; fi

# ruff and mypy on core (pyproject.toml's [tool.ruff] and [tool.mypy]); make test runs it first
lint: venv
	$(VENV)/bin/ruff check core
	$(VENV)/bin/mypy

test: venv sysdeps lint
	$(PY) -m pytest -q

test-all: venv sysdeps
	$(PY) -m pytest -q -m ""

bench: venv
	$(PY) tests/benchmarks/run_all.py

# The desktop bundle dist/bladecam/ (PyInstaller, packaging/bladecam.spec); the `package` extras on demand.
package: $(STAMP)
	@$(PY) -c "import PyInstaller, _pyinstaller_hooks_contrib" 2>/dev/null || \
	  $(PY) -m pip install --disable-pip-version-check -q -e '.[test,package]'
	$(VENV)/bin/pyinstaller --noconfirm --clean --distpath dist --workpath build packaging/bladecam.spec

clean:
	rm -rf $(VENV) build dist *.egg-info $(PYX:.pyx=.c) core/*/_*.so
