# Stager: `make demo` sets everything up, solves the sample and furnishes a sample photo; `make test` runs the suite.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Mesa's EGL/OSMesa for the renderer; Chromium for the web app's browser test.
APT_PACKAGES := libegl1 libgl1-mesa-dri libegl-mesa0 libosmesa6 chromium

.PHONY: setup test demo clean system-packages

setup: $(STAMP)

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
	$(PY) -m pip install -q -e '.[dev]'
	# pyrender pins PyOpenGL 3.1.0, with which OSMesa fails; 3.1.10 makes EGL and OSMesa work.
	$(PY) -m pip install -q 'PyOpenGL==3.1.10'
	touch $(STAMP)

test: setup
	$(PY) -m pytest

demo: setup
	$(VENV)/bin/layout solve samples/living_room.toml --suggestions 4 --seed 0 --out out/demo
	$(PY) -m augment.synth --count 4 --seed 2026 --size 640x480 --out out/demo/photos --sheet out/demo/photos.png --quiet
	@echo "plans written to $(CURDIR)/out/demo (plan_1.png ... plan_4.png, layout_K.json)"
	@echo "synthetic room photos with ground truth in $(CURDIR)/out/demo/photos (contact sheets photos.png, photos_truth.png)"
	$(VENV)/bin/stage furnish samples/photos/room_4.jpg --room living_room --suggestions 4 --seed 0 --out out/demo/furnished
	@echo "sample photos for the image stage: $(CURDIR)/samples/photos/room_1.jpg ... room_4.jpg"
	@echo "staged images of samples/photos/room_4.jpg in $(CURDIR)/out/demo/furnished (staged_1.jpg ... staged_4.jpg, side by side in staged_all.jpg; report.json, scene_K.glb, overlays)"

clean:
	rm -rf $(VENV) out .pytest_cache
