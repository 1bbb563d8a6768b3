# The two commands a new user types: `make run` and `make test`.
JOBS ?= $(shell nproc)
BUILD ?= build
# The sanitizer build: clang with ASan and UBSan, the tests and the libFuzzer targets in one tree,
# so the library is compiled twice in all (here and in $(BUILD)), not three times (docs/testing.md).
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= $(ASAN_BUILD)
FUZZ_SECONDS ?= 60
# FUZZ_RUNS=N runs each target for N inputs from seed FUZZ_SEED instead: the same inputs every run
# (what .ci/run does, so CI never fails on a random draw; exploration is `make fuzz`).
FUZZ_RUNS ?=
FUZZ_SEED ?= 1
FUZZ_TARGETS = urdf mjcf scene step
CMAKE_FLAGS ?=
# New build directories use Ninja, which compiles a target's files while the targets it links are
# still compiling (the main build: 170 s against 183 s with Makefiles); an existing directory
# keeps the generator it was made with.
export CMAKE_GENERATOR ?= Ninja
# The main build: optimised, without debug information (a third of its compile time); make
# BUILD_TYPE=RelWithDebInfo for a debugger.
BUILD_TYPE ?= Release

.PHONY: all deps configure build run test test-asan test-fuzz test-main fuzz fuzz-build fuzz-run bench clean format physx

all: build

deps:
	@bash scripts/install-deps.sh

# The main build: clang (a third less compile time than gcc 12 on this code); every test runs
# here, against the optimised library (docs/testing.md).
MAIN_FLAGS ?= -DCMAKE_CXX_COMPILER=clang++
# The tests `make test-asan` compiles and runs in the sanitizer build (not part of `make test`):
# hostile (the command's tests and the regression replay) or all (every test but the peers' and
# Python's, under ASan and UBSan: about 20 times slower than the main build).
ASAN_TESTS ?= hostile

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(MAIN_FLAGS) $(CMAKE_FLAGS)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# No "Entering/Leaving directory" lines from the makes that cmake --build starts below.
MAKEFLAGS += --no-print-directory

# The demo: the 7-dof arm of examples/arm7.urdf tracking sine trajectories with stiff drives,
# under PGS and then TGS; trajectories, plots and the 3D viewer page (docs/viewer.md) go to out/.
run: build
	@mkdir -p out
	@echo
	@./$(BUILD)/tools/featherdrive simulate examples/arm7_pgs.yaml --out out/arm7_pgs.csv --plot out/arm7_pgs.png
	@echo
	@./$(BUILD)/tools/featherdrive simulate examples/arm7_tgs.yaml --out out/arm7_tgs.csv --plot out/arm7_tgs.png
	@echo
	@if [ -f $(BUILD)/viewer/viewer.js ]; then \
	  ./$(BUILD)/tools/featherdrive view examples/arm7_pgs.yaml --csv out/arm7_pgs.csv --out out/arm7_view.html; \
	else echo "make run: no 3D viewer page (node and npm bundle it at build time: apt-get install -y nodejs npm)"; fi

# PhysX 5.6.1 for `featherdrive compare-physx` (the tests install it themselves): the pinned npm
# package and our harness in $(BUILD)/physx. Needs node and npm (apt-get install -y nodejs npm).
physx:
	sh tests/physx/install.sh $(BUILD)/physx

# -O1 with line tables only: sanitizer reports keep file and line, at half the compile time of -g.
$(ASAN_BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" \
	  -DFEATHERDRIVE_SANITIZE=ON -DFEATHERDRIVE_FUZZ=ON -DFEATHERDRIVE_PEER_TESTS=OFF \
	  -DFEATHERDRIVE_TEST_SET=$(ASAN_TESTS) $(CMAKE_FLAGS)

test-asan: deps $(ASAN_BUILD)/CMakeCache.txt
	@grep -q '^FEATHERDRIVE_TEST_SET:STRING=$(ASAN_TESTS)$$' $(ASAN_BUILD)/CMakeCache.txt || \
	  cmake -S . -B $(ASAN_BUILD) -DFEATHERDRIVE_TEST_SET=$(ASAN_TESTS)
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/fuzz/lsan.supp \
	  ctest --output-on-failure -j $(JOBS)

test-main: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The sanitizers' half of `make test`: the fuzz targets replay their seed corpus and the inputs
# fuzzing once found wrong (tests/regression/inputs/), then fixed inputs from fixed seeds
# (TEST_FUZZ_JOBS below), the same every run (docs/testing.md, "Where CI's time goes").
test-fuzz: fuzz-build
	@$(MAKE) --no-print-directory --output-sync=target -j $(JOBS) \
	  $(addprefix fuzz-replay-,$(TEST_FUZZ_JOBS))

# The fuzzers first, so that the suite's last lines are the main build's ctest summary.
test: deps
	@$(MAKE) --no-print-directory test-fuzz
	@$(MAKE) --no-print-directory test-main

# libFuzzer targets (tests/fuzz), built in the sanitizer build $(FUZZ_BUILD); each runs for
# FUZZ_SECONDS (or FUZZ_RUNS inputs) from its seed corpus in tests/fuzz/corpus/<target>/ (read only: new inputs go to
# $(FUZZ_BUILD)/corpus/<target>/, crashes to $(FUZZ_BUILD)/artifacts/). A crash fails the target.
fuzz-build: deps $(FUZZ_BUILD)/CMakeCache.txt
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))

ifeq ($(FUZZ_RUNS),)
FUZZ_LENGTH = -max_total_time=$(FUZZ_SECONDS)
else
FUZZ_LENGTH = -runs=$(FUZZ_RUNS) -seed=$(FUZZ_SEED)
endif

# Seeds kept elsewhere in the repository, copied to $(FUZZ_BUILD)/seeds/<run>/ for a run (a corpus
# is a folder): fuzz_mjcf starts from the malformed-file tests' MJCF files too.
FUZZ_SEEDS_mjcf = $(wildcard tests/data/malformed/*.xml)

# Options of one target's runs: fuzz_mjcf's dictionary of MJCF names (MuJoCo's compiler, in
# Debian's library, gives libFuzzer no coverage to learn them from).
FUZZ_FLAGS_mjcf = -dict=tests/fuzz/mjcf.dict

# One fuzzer run: $(1) the target, $(2) its length and seed, $(3) the name of its new-input corpus
# and log. A crash fails the run.
define fuzz_one
	@mkdir -p $(FUZZ_BUILD)/corpus/$(3) $(FUZZ_BUILD)/artifacts
	$(if $(FUZZ_SEEDS_$(1)),@rm -rf $(FUZZ_BUILD)/seeds/$(3) && mkdir -p $(FUZZ_BUILD)/seeds/$(3) \
	  && cp $(FUZZ_SEEDS_$(1)) $(FUZZ_BUILD)/seeds/$(3)/)
	@echo "fuzz_$(1): $(2)"
	@LSAN_OPTIONS=suppressions=$(CURDIR)/tests/fuzz/lsan.supp \
	  ./$(FUZZ_BUILD)/tests/fuzz/fuzz_$(1) $(2) $(FUZZ_FLAGS_$(1)) -timeout=20 \
	    -rss_limit_mb=2048 -print_final_stats=1 \
	    -artifact_prefix=$(FUZZ_BUILD)/artifacts/$(3)- \
	    $(FUZZ_BUILD)/corpus/$(3) tests/fuzz/corpus/$(1) $(wildcard tests/regression/inputs/$(1)) \
	    $(if $(FUZZ_SEEDS_$(1)),$(FUZZ_BUILD)/seeds/$(3)) \
	    2>$(FUZZ_BUILD)/fuzz_$(3).log \
	  || { grep -m1 -A30 -E '==ERROR|runtime error|deadly signal|fuzz bug' $(FUZZ_BUILD)/fuzz_$(3).log; \
	       tail -n 8 $(FUZZ_BUILD)/fuzz_$(3).log; echo "fuzz_$(1) FAILED: see $(FUZZ_BUILD)/artifacts/"; exit 1; }
	@grep -E '^stat::number_of_executed_units|^Done' $(FUZZ_BUILD)/fuzz_$(3).log || true
endef

# The targets run side by side, JOBS at a time (each fuzzer is single-threaded). fuzz-run runs the
# targets already built.
fuzz: fuzz-build
	@$(MAKE) --no-print-directory fuzz-run

fuzz-run:
	@$(MAKE) --no-print-directory --output-sync=target -j $(JOBS) \
	  $(addprefix fuzz-run-,$(FUZZ_TARGETS))

fuzz-run-%:
	$(call fuzz_one,$*,$(FUZZ_LENGTH),$*)

# make test's replay, TARGET.SEED.RUNS: fuzz_step's inputs cost eight times the readers', so they
# run as two halves from two seeds, one per core, each with its own corpus (the same inputs every
# run: a run reads back only the inputs it wrote itself).
TEST_FUZZ_JOBS ?= urdf.1.15000 mjcf.1.1500 scene.1.15000 step.1.7500 step.2.7500
fuzz-replay-%:
	$(call fuzz_one,$(word 1,$(subst ., ,$*)),-runs=$(word 3,$(subst ., ,$*)) -seed=$(word 2,$(subst ., ,$*)),$*)

# Benchmarks against MuJoCo and Bullet in one run (docs/benchmarks.md), built by the main build's
# compiler (MAIN_FLAGS: clang; gcc 12's lanes ran up to a third slower): medians of 5 repetitions,
# the JSON in build-bench/bench.json, the tables printed and the plot in build-bench/.
# BENCH_ARCH: the -march of the benchmark build; empty (the default) builds for portable x86-64,
# like every other build and like the peers' Debian packages (x86-64-v3: AVX2 and FMA).
BENCH_ARCH ?=
BENCH_FLAGS ?= --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
bench: deps
	cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DFEATHERDRIVE_BENCH=ON \
	  -DFEATHERDRIVE_ARCH=$(BENCH_ARCH) $(MAIN_FLAGS) $(CMAKE_FLAGS)
	cmake --build build-bench -j $(JOBS) --target featherdrive_bench featherdrive_profile \
	  featherdrive_prototype_ratio
	./build-bench/bench/featherdrive_bench $(BENCH_FLAGS) \
	  --benchmark_out=build-bench/bench.json --benchmark_out_format=json
	/usr/bin/python3 bench/plot_benchmarks.py build-bench/bench.json \
	  --plot build-bench/benchmarks_per_dof.png
	./build-bench/bench/featherdrive_prototype_ratio

format:
	find include src tests tools bench -name '*.hpp' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD) build-fuzz build-bench
