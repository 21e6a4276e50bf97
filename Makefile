# The two commands of the README: `make demo` and `make test`. Both install what is missing first.
BUILD_DIR ?= build
JOBS ?= 2
CMAKE_ARGS ?=

.PHONY: all setup configure build test demo clean

all: build

setup:
	bash .ci/install-dependencies

configure: setup
	cmake -S . -B $(BUILD_DIR) $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS)

demo: build
	bash experiments/demo.sh $(BUILD_DIR)

clean:
	rm -rf $(BUILD_DIR)
