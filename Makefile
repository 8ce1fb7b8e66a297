# curvlab: every target does its own set-up (venv, project with extras, Debian packages when root).
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Debian packages the Qt xcb platform plugin and VTK need, plus Xvfb for a display.
DEB_PKGS := xvfb xauth libgl1 libegl1 libglx-mesa0 libgl1-mesa-dri libxkbcommon-x11-0 libxcb-cursor0 \
	libxcb-icccm4 libxcb-image0 libxcb-keysyms1 libxcb-randr0 libxcb-render-util0 libxcb-shape0 \
	libxcb-xinerama0 libxcb-xinput0 libxcb-xfixes0 libxrender1 libxi6 libdbus-1-3 libfontconfig1 \
	libxt6 libsm6 libice6

.PHONY: run test test-all venv warm sysdeps bench bench-viewer study-quick clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[gui,study,points,test,bench]'
	touch $(STAMP)

venv: $(STAMP)

# numba compiles each kernel on first use; compile them here, once per state of the sources, so
# the viewer's first estimate does not wait for it (a failure only means they compile on first use)
warm: venv
	@$(PY) -m curv.warmup --if-needed || echo "curvlab: warm-up failed; kernels will compile on first use"

sysdeps:
	@missing=$$(for p in $(DEB_PKGS); do dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
		if [ "$$(id -u)" = 0 ]; then \
			echo "installing Debian packages: $$missing"; \
			export DEBIAN_FRONTEND=noninteractive; \
			apt-get update -qq && apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
		else \
			echo "missing Debian packages (run as root or install them): $$missing"; exit 1; \
		fi; \
	fi

run: sysdeps venv warm
	@if [ -z "$$DISPLAY" ] && [ -z "$$WAYLAND_DISPLAY" ]; then \
		echo "no display: running the viewer under xvfb-run"; \
		xvfb-run -a -s '-screen 0 1600x1000x24' $(VENV)/bin/curvlab $(ARGS); \
	else $(VENV)/bin/curvlab $(ARGS); fi

test: sysdeps venv warm
	$(PY) -m pytest -q $(PYTEST_ARGS)

test-all: sysdeps venv warm
	$(PY) -m pytest -q -m '' $(PYTEST_ARGS)

bench: venv
	$(PY) benchmarks/bench_estimators.py $(ARGS)

bench-viewer: sysdeps venv
	$(PY) benchmarks/bench_viewer.py $(ARGS)

study-quick: venv
	$(VENV)/bin/curv study --preset quick --out study-out

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
