# Entry points. `make demo` and `make test` work on a fresh Debian 12 machine:
# they install missing packages first (apt-get), then configure and build.
BUILD ?= build
JOBS ?= $(shell nproc)
GEN := $(shell command -v ninja >/dev/null 2>&1 && echo Ninja || echo "Unix Makefiles")
CMAKE_ARGS ?=

.PHONY: all deps configure build demo python test bench asan tsan fuzz format clean

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt:
	@bash scripts/install-deps.sh
	cmake -S . -B $(BUILD) -G "$(shell command -v ninja >/dev/null 2>&1 && echo Ninja || echo 'Unix Makefiles')" -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

configure: $(BUILD)/CMakeCache.txt

build: deps configure
	cmake --build $(BUILD) -j $(JOBS)

# The demo builds the CLI only (no tests, no benchmarks): about half the compile work.
demo: deps configure
	cmake --build $(BUILD) -j $(JOBS) --target atelier
	./$(BUILD)/atelier demo --out out/demo

# The Python module (docs/python.md) for Debian's python3, whose NumPy it is
# built against (a pyenv python3 first on PATH is not it): its packages,
# configure again so that CMake finds pybind11, then the module alone, in
# $(BUILD)/python/atelier. Use it with PYTHONPATH=$(BUILD)/python $(PYTHON).
PYTHON ?= /usr/bin/python3
python: configure
	@bash scripts/install-deps.sh --python
	cmake -S . -B $(BUILD) -DPython_EXECUTABLE=$(PYTHON) $(CMAKE_ARGS)
	cmake --build $(BUILD) -j $(JOBS) --target atelier_python
	@PYTHONPATH=$(BUILD)/python $(PYTHON) -c "import atelier; print('atelier', atelier.__version__, 'in', atelier.__path__[0])"
	@echo "use it: PYTHONPATH=$(BUILD)/python $(PYTHON) examples/pipeline.py   (or: cmake --install $(BUILD))"

# Test packages, then configure again so that CMake finds them.
test: configure
	@bash scripts/install-deps.sh --test
	cmake -S . -B $(BUILD) $(CMAKE_ARGS)
	cmake --build $(BUILD) -j $(JOBS)
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

bench:
	@bash scripts/install-deps.sh --bench
	cmake -S . -B $(BUILD) -DATELIER_BUILD_BENCH=ON
	cmake --build $(BUILD) -j $(JOBS) --target atelier_bench
	mkdir -p bench-results
	./$(BUILD)/bench/atelier_bench --benchmark_out=bench-results/atelier_bench.json --benchmark_out_format=json

# The ASan+UBSan build uses Debian's clang (installed with the fuzzing
# packages): GCC 12's UBSan instrumentation more than doubles the compile
# (a systems file: 175 s against 75 s with clang, ASan alone 74 s;
# docs/reliability.md), and this build is half of CI's time.
asan:
	@bash scripts/install-deps.sh --test --fuzz
	cmake -S . -B build-asan -G "$(GEN)" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DATELIER_SANITIZE=address,undefined -DATELIER_BUILD_BENCH=OFF
	cmake --build build-asan -j $(JOBS)
	ATELIER_SKIP_LONG_TESTS=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --test-dir build-asan --output-on-failure -j $(JOBS)

tsan:
	@bash scripts/install-deps.sh --test
	cmake -S . -B build-tsan -G "$(GEN)" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DATELIER_SANITIZE=thread -DATELIER_BUILD_BENCH=OFF
	cmake --build build-tsan -j $(JOBS)
	ATELIER_SKIP_LONG_TESTS=1 TSAN_OPTIONS="suppressions=$(CURDIR)/scripts/tsan.supp halt_on_error=1" ctest --test-dir build-tsan --output-on-failure -j $(JOBS)

# libFuzzer harnesses of every parser (fuzz/, docs/reliability.md), built by
# clang under ASan+UBSan in build-fuzz, each run FUZZ_SECONDS (default 15) or
# FUZZ_RUNS executions, FUZZ_JOBS harnesses at a time (default: the cores):
# `make fuzz FUZZ_RUNS=10000000`.
FUZZ_SECONDS ?= 15
FUZZ_RUNS ?=
fuzz:
	@bash scripts/install-deps.sh --fuzz
	cmake -S fuzz -B build-fuzz -G "$(GEN)" -DCMAKE_CXX_COMPILER=clang++
	cmake --build build-fuzz -j $(JOBS)
	bash scripts/fuzz.sh $(if $(FUZZ_RUNS),--runs $(FUZZ_RUNS),--seconds $(FUZZ_SECONDS)) $(FUZZ_TARGETS)

format:
	find engine storage systems io apps tests bench examples python -name '*.h' -o -name '*.cpp' | xargs clang-format -i

clean:
	rm -rf $(BUILD) build-asan build-tsan build-fuzz
