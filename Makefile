# The two commands a newcomer needs: `make demo` and `make test`.
# Everything else is a convenience around CMake presets (see CMakePresets.json).

PRESET ?= release
BUILD_DIR := build/$(PRESET)
JOBS ?= $(shell nproc)

.PHONY: all setup configure build examples demo test bench golden pipeline-docs cli-docs sanitize asan asan-gcc tsan fuzz format clean

all: build examples

# The README's example inputs (examples/README.md), made from formulas; not checked in.
examples: setup
	@python3 examples/make_examples.py

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
golden: build pipeline-docs
	@CUBERILLE_UPDATE_GOLDEN=1 ctest --preset $(PRESET) -L golden

# docs/cli-reference.md from the tool's own --help (checked by Cli.ReferenceIsTheToolsOwnHelp).
cli-docs: build
	@CUBERILLE_UPDATE_CLI_DOCS=1 build/$(PRESET)/tests/cuberille_tests --gtest_filter=Cli.ReferenceIsTheToolsOwnHelp --gtest_brief=1

# The pictures of docs/pipeline.md, drawn by `cuberille explain` for apps::kExplainTriangle (the same
# triangle; golden-tested as reference_images/explain_*).
pipeline-docs: build
	@build/$(PRESET)/apps/cuberille explain --triangle "1.3 1.7 14.6 4.2 5.1 12.8" --out-dir docs/images/pipeline --quiet

# The whole suite under AddressSanitizer + UndefinedBehaviorSanitizer (`make asan`, in CI), and
# the threaded and streaming tests under ThreadSanitizer (`make tsan`, in CI) (docs/robustness.md).
# `make asan` builds in the fuzz preset's tree (clang, ASan + UBSan, every finding fatal, libFuzzer
# coverage), so the suite and the fuzz targets share one sanitizer build; `make asan-gcc` is the
# same suite under GCC's sanitizers. Only what the tests need is built.
# The ThreadSanitizer subset, a ctest regex over the discovered test names; ctest runs them a
# process each, JOBS at a time (serially in one process they took half as long again). The
# instruction-set comparison is left out: it draws on the same threads as the thread-count tests, once
# per instruction set, and took 229 s under TSan, the longest of the subset.
TSAN_TESTS := ^(Determinism\.SameImage(For|Across).*|.*\.SameVoxelsForAnyThreadCount|Simplify\.SerialAndParallelGiveIdenticalPyramids|VoxelDeterminism\..*|BlockLoader\..*|BlockPool\..*|Streaming\..*|LazyRefit\..*|BvhBuild\.SameTreeForAnyThreadCount|BvhRefit\.SameBoxesAndDegradationForAnyThreadCount|WideBvh\.TheSameTreeAtAnyThreadCount|Shadows\.SameMasksForAnyThreadCount|AmbientOcclusion\.TheSameMaskAtAnyThreadCount)$$
sanitize: asan tsan

# The suites' environment under ASan (clang's and GCC's): clang 14's and GCC 12's runtimes take a
# dynamic TLS block whose address happens to lie one header's size into a page for glibc 2.19's
# layout and read a bogus range from before it, so the leak check at exit crashes ("Tracer caught
# signal 11") by the luck of malloc's layout, after a test has passed (google/sanitizers#1322;
# seen when a test process had loaded the OpenImageIO module's libraries). Not intercepting
# __tls_get_addr stops it. Its cost: dynamic TLS is no longer scanned for pointers, which can
# only add leak reports (a block held from there alone), never hide one.
ASAN_ENV := ASAN_OPTIONS=intercept_tls_get_addr=0$${ASAN_OPTIONS:+:$$ASAN_OPTIONS}

asan: setup
	@cmake --preset fuzz >/dev/null
	@cmake --build --preset fuzz -j $(JOBS) --target cuberille cuberille_tests cuberille_golden_tests
	@$(ASAN_ENV) ctest --test-dir build/fuzz -j $(JOBS) --output-on-failure

asan-gcc: setup
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan -j $(JOBS) --target cuberille cuberille_tests cuberille_golden_tests
	@$(ASAN_ENV) ctest --preset asan -j $(JOBS)

tsan: setup
	@cmake --preset tsan >/dev/null
	@cmake --build --preset tsan -j $(JOBS) --target cuberille cuberille_tests
	@ctest --test-dir build/tsan -j $(JOBS) --output-on-failure --no-tests=error -R '$(TSAN_TESTS)'

# Fuzz every reader (fuzz/, docs/robustness.md): FUZZ_SECONDS each, corpora kept in build/fuzz/corpus.
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := fuzz_tri fuzz_ply fuzz_obj fuzz_gltf fuzz_cgs fuzz_cvox fuzz_cvox_blocks fuzz_camera_path fuzz_raw_volume fuzz_hdr fuzz_partial_voxelization fuzz_pyramid_range
fuzz: setup
	@cmake --preset fuzz >/dev/null
	@cmake --build --preset fuzz -j $(JOBS)
	@build/fuzz/fuzz/make_seeds build/fuzz/seeds
	@set -e; for t in $(FUZZ_TARGETS); do \
	  mkdir -p build/fuzz/corpus/$$t; \
	  echo "fuzz: $$t for $(FUZZ_SECONDS) s"; \
	  build/fuzz/fuzz/$$t build/fuzz/corpus/$$t build/fuzz/seeds/$$t -max_total_time=$(FUZZ_SECONDS) -seed=1 \
	    -rss_limit_mb=4096 -timeout=20 -print_final_stats=1 -artifact_prefix=build/fuzz/$$t- 2>&1 | \
	    grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==|SUMMARY|ERROR|Done)" || true; \
	  if ls build/fuzz/$$t-* >/dev/null 2>&1; then echo "fuzz: $$t found a crash: $$(ls build/fuzz/$$t-*)"; exit 1; fi; \
	done

format:
	@clang-format -i $$(git ls-files '*.h' '*.cpp')

clean:
	@rm -rf build out
