# Thin front door. Every target is idempotent and usable alone; the real work lives in CMake,
# tools/deps.sh and the CLIs. `make help` lists the targets.
SHELL := /bin/bash
.DEFAULT_GOAL := help
JOBS ?= $(shell nproc)

.PHONY: help deps build release cm4 test demo bench soak clean

help: ## list targets
	@grep -E '^[a-z0-9-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  make %-8s %s\n", $$1, $$2}'

deps: ## install Debian packages and the pinned Python venv (.venv)
	@bash tools/deps.sh

build: deps ## host Debug build with ASan+UBSan; CLIs in build/host/bin
	@cmake --preset host >/dev/null
	@cmake --build --preset host -j $(JOBS)

release: deps ## host -O2 build in build/release
	@cmake --preset release >/dev/null
	@cmake --build --preset release -j $(JOBS)

cm4: deps ## cross-compile firmware/ and link the Cortex-M4 image in build/cm4
	@cmake --preset cm4 >/dev/null
	@cmake --build --preset cm4 -j $(JOBS)

test: build ## run every test (ctest: Unity, Check, pytest, lint, Cortex-M4 cross build)
	@ctest --preset host -j $(JOBS)

demo: build ## run the main job on built-in sample data
	@bash tools/demo/demo.sh

bench: release ## print benchmark figures as JSON (-O2 build: build/release/bin/odo-bench --json)
	@build/release/bin/odo-bench --json

soak: release ## frame loss at speed and the 24 h fault soak, JSON (build/release/bin/odo-soak --json)
	@build/release/bin/odo-soak --json

clean: ## remove build output (keeps .venv)
	rm -rf build
