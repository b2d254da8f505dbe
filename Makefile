# The two commands a newcomer needs: `make demo` and `make test`.
# Everything else is a convenience around CMake presets (see CMakePresets.json).

PRESET ?= release
BUILD_DIR := build/$(PRESET)
JOBS ?= $(shell nproc)

.PHONY: all setup configure build demo test bench golden format clean

all: build

setup:
	@./.ci/install-deps

configure: setup
	@cmake --preset $(PRESET) >/dev/null

build: configure
	@cmake --build --preset $(PRESET) -j $(JOBS)

demo: build
	@mkdir -p out
	@$(BUILD_DIR)/apps/cuberille render demo --width 1280 --height 720 --msaa 4 --out out/demo.png --stats out/demo-stats.json

test: build
	@ctest --preset $(PRESET) -j $(JOBS)

bench: build
	@$(BUILD_DIR)/bench/raster_bench --threads 1
	@$(BUILD_DIR)/bench/raster_bench

# Regenerate reference_images/ from the current renderer (review the diff before committing).
golden: build
	@CUBERILLE_UPDATE_GOLDEN=1 ctest --preset $(PRESET) -L golden

format:
	@clang-format -i $$(git ls-files '*.h' '*.cpp')

clean:
	@rm -rf build out
