# The two commands of the README: `make demo` and `make test`. Both install what is missing first.
BUILD_DIR ?= build
JOBS ?= 2
CMAKE_ARGS ?=

.PHONY: all setup configure build test demo clean train-fitter

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

# Trains the learned fitter (fitting/training/train_learned_fitter.py) on synthetic segments and
# exports its weights into fitting/models/learned_fitter/. Training only: build and tests never run it.
# Uses Debian's python3-torch/python3-numpy via /usr/bin/python3 (installed here when missing).
train-fitter:
	@/usr/bin/python3 -c "import torch, numpy" 2>/dev/null || \
	  (apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3-torch python3-numpy)
	/usr/bin/python3 fitting/training/train_learned_fitter.py
