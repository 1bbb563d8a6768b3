# The two commands a new user types: `make run` and `make test`.
JOBS ?= $(shell nproc)
BUILD ?= build
ASAN_BUILD ?= build-asan
CMAKE_FLAGS ?=

.PHONY: all deps configure build run test test-asan test-main bench clean format

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo $(CMAKE_FLAGS)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The demo: the 7-dof arm of examples/arm7.urdf tracking sine trajectories with stiff drives,
# under PGS and then TGS; trajectories and plots go to out/.
run: build
	@mkdir -p out
	@echo
	@./$(BUILD)/tools/featherdrive simulate examples/arm7_pgs.yaml --out out/arm7_pgs.csv --plot out/arm7_pgs.png
	@echo
	@./$(BUILD)/tools/featherdrive simulate examples/arm7_tgs.yaml --out out/arm7_tgs.csv --plot out/arm7_tgs.png

$(ASAN_BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFEATHERDRIVE_SANITIZE=ON \
	  -DFEATHERDRIVE_PEER_TESTS=OFF $(CMAKE_FLAGS)

# The sanitizer build runs first so that the suite's last lines are the main build's ctest summary.
test-asan: deps $(ASAN_BUILD)/CMakeCache.txt
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ctest --output-on-failure -j $(JOBS)

test-main: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test: deps
	$(MAKE) test-asan
	$(MAKE) test-main

bench: deps
	cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DFEATHERDRIVE_BENCH=ON $(CMAKE_FLAGS)
	cmake --build build-bench -j $(JOBS) --target featherdrive_bench
	./build-bench/bench/featherdrive_bench

format:
	find include src tests tools bench -name '*.hpp' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) build-bench
