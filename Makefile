# Thin front door. Every target is idempotent and usable alone; the real work lives in CMake,
# tools/deps.sh and the CLIs. `make help` lists the targets.
SHELL := /bin/bash
.DEFAULT_GOAL := help
JOBS ?= $(shell nproc)

.PHONY: help deps build release cm4 test demo bench bench-target bench-gap soak fuzz coverage format flash flash-params flash-all package lock clean

help: ## list targets
	@grep -E '^[a-z0-9-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  make %-12s %s\n", $$1, $$2}'

# installs and builds report on stderr: a bench target's stdout is its JSON alone
# (make bench-gap > out.json)
deps: ## install Debian packages and the pinned Python venv (.venv)
	@bash tools/deps.sh >&2

build: deps ## host Debug build with ASan+UBSan; CLIs in build/host/bin
	@cmake --preset host >/dev/null
	@cmake --build --preset host -j $(JOBS) >&2

release: deps ## host -O2 build in build/release
	@cmake --preset release >/dev/null
	@cmake --build --preset release -j $(JOBS) >&2

cm4: deps ## cross-compile firmware/ and link the Cortex-M4 image in build/cm4
	@cmake --preset cm4 >/dev/null
	@cmake --build --preset cm4 -j $(JOBS) >&2

test: build ## run every test (ctest: Unity, Check, pytest, lint, Cortex-M4 cross build)
	@ctest --preset host -j $(JOBS)

demo: build ## run the main job on built-in sample data
	@bash tools/demo/demo.sh

bench: release ## print benchmark figures as JSON (-O2 build: build/release/bin/odo-bench --json)
	@build/release/bin/odo-bench --json

bench-target: release cm4 ## Cortex-M4 figures as JSON: instructions per tick (emulated), flash, RAM, stack
	@.venv/bin/odo-bench-target --build-dir build/release --cm4-dir build/cm4

bench-gap: build ## odo-gap diagnosis time on dev cases as JSON; REF=<git rev> adds the ratio against it, CASES=S:K,... other cases, WORLD=sim the simulator's
	@.venv/bin/python -m odo_tools.gap.bench $(if $(REF),--ref $(REF)) $(if $(CASES),--cases $(CASES)) $(if $(WORLD),--world $(WORLD))

flash: cm4 ## program the image with openocd, never its parameter sector (odo-flash code)
	@.venv/bin/odo-flash code --image build/cm4/bin/odo_image.elf

flash-params: cm4 ## program only the parameter block: make flash-params PARAMS=fw.elf|fw.hex|block.bin
	@.venv/bin/odo-flash params --image build/cm4/bin/odo_image.elf --params "$(PARAMS)"

flash-all: cm4 ## program image and its default parameter block (erases a calibrated block)
	@.venv/bin/odo-flash all --image build/cm4/bin/odo_image.elf

soak: release ## frame loss at speed and the 24 h fault soak, JSON (build/release/bin/odo-soak --json)
	@build/release/bin/odo-soak --json

fuzz: deps ## long libFuzzer campaigns, 10^7 execs per harness (FUZZ_RUNS=N to change), JSON (fuzz/README.md)
	@python3 fuzz/campaign.py --runs $(or $(FUZZ_RUNS),10000000)

coverage: deps ## firmware/ line and branch coverage from the Unity tests (gcovr; build/coverage)
	@cmake --preset coverage >/dev/null
	@cmake --build --preset coverage -j $(JOBS) --target $(notdir $(basename $(wildcard tests/unit/test_*.c)))
	@find build/coverage -name '*.gcda' -delete
	@ctest --test-dir build/coverage -R '^unit[.]' -j $(JOBS) --output-on-failure >/dev/null
	@gcovr --root . --filter 'firmware/' --exclude-unreachable-branches --print-summary \
	  --txt build/coverage/coverage.txt build/coverage | tail -n 3
	@echo "per file: build/coverage/coverage.txt"

format: ## reformat every C file by .clang-format (the folders: tests/lint/clang_format.py); ctest lint.format checks it
	@python3 tests/lint/clang_format.py . --fix

package: release ## the .deb (CPack, release build) and the wheel, in build/release/package
	@cd build/release && cpack -G DEB -B package >/dev/null && ls package/*.deb
	@bash tools/python/wheel.sh build/release/package

lock: ## re-compile tools/python/requirements.txt (hash-pinned) from pyproject.toml; needs PyPI
	@bash tools/python/lock.sh

clean: ## remove build output (keeps .venv)
	rm -rf build
