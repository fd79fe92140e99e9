# Stager: `make demo` sets everything up, solves the sample and furnishes a sample photo; `make test` runs the suite.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
COMPILED := $(VENV)/.compiled
# The suite runs in this many processes, a test file each at a time (a file's fixtures are shared).
TEST_WORKERS ?= 2
# numba compiles these files' kernels on their first use (1-2 minutes) and caches them.
KERNELS := layout/_kernels.py layout/metrics.py augment/render/staged.py
# Mesa's EGL/OSMesa for the renderer; Chromium for the web app's browser test.
APT_PACKAGES := libegl1 libgl1-mesa-dri libegl-mesa0 libosmesa6 chromium

.PHONY: setup test demo clean system-packages

setup: $(STAMP) $(COMPILED)

# The renderer needs Mesa's EGL/OSMesa libraries; install them only when missing.
system-packages:
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi

$(STAMP): pyproject.toml | system-packages
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	@# pyrender2 installs the same `pyrender` package as the unmaintained pyrender an older
	@# .venv holds: that one goes first, or removing it later would take pyrender2's files.
	@if $(PY) -m pip show -q pyrender >/dev/null 2>&1; then $(PY) -m pip uninstall -q -y pyrender; fi
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

# Compile the solver's and the renderer's kernels into numba's cache now, by furnishing a
# sample photo once, so that the first `stage furnish` a user runs is as quick as any
# other; again whenever a kernel's source changes. Python's bytecode too: with
# PYTHONDONTWRITEBYTECODE set (as in many containers) every command would compile it again.
$(COMPILED): $(STAMP) $(KERNELS)
	@echo "compiling the layout solver and the renderer (numba, once: 1-2 minutes)"
	$(PY) -m compileall -q augment layout
	@tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && \
	  $(VENV)/bin/stage furnish samples/photos/room_4.jpg --suggestions 1 --out "$$tmp/out" --quiet \
	    >"$$tmp/log" 2>&1 || { cat "$$tmp/log"; exit 1; }
	touch $(COMPILED)

test: setup
	$(PY) -m pytest -n $(TEST_WORKERS) --dist loadfile

demo: setup
	$(VENV)/bin/layout solve samples/living_room.toml --suggestions 4 --seed 0 --out out/demo
	$(PY) -m augment.synth --count 4 --seed 2026 --size 640x480 --out out/demo/photos --sheet out/demo/photos.png --quiet
	@echo "plans written to $(CURDIR)/out/demo (plan_1.png ... plan_4.png, layout_K.json)"
	@echo "synthetic room photos with ground truth in $(CURDIR)/out/demo/photos (contact sheets photos.png, photos_truth.png)"
	$(VENV)/bin/stage furnish samples/photos/room_4.jpg --room living_room --suggestions 4 --seed 0 --out out/demo/furnished
	@echo "sample photos for the image stage: $(CURDIR)/samples/photos/room_1.jpg ... room_4.jpg"
	@echo "staged images of samples/photos/room_4.jpg in $(CURDIR)/out/demo/furnished (staged_1.jpg ... staged_4.jpg, side by side in staged_all.jpg; report.json, scene_K.glb, overlays)"
	@echo
	@echo "To run Stager yourself, in a new shell here:"
	@echo "  . .venv/bin/activate"
	@echo "  stage furnish YOUR_PHOTO.jpg --room living_room --out out/mine"
	@echo "  stage --help        (every command; the web app: stage serve)"
	@echo "or without activating: $(CURDIR)/.venv/bin/stage furnish YOUR_PHOTO.jpg"

clean:
	rm -rf $(VENV) out .pytest_cache
