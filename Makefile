# The two commands of the README: `make demo` and `make test`. Both install what is missing first.
BUILD_DIR ?= build
JOBS ?= 2
CMAKE_ARGS ?=

.PHONY: all setup configure build test demo clean train-fitter papers study-refiners study-fitters fuzz fuzz-build fuzz-smoke test-sanitize

all: build

setup:
	bash .ci/install-dependencies

configure: setup
	cmake -S . -B $(BUILD_DIR) $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

# Every ctest test, the fuzz harnesses' seeds and crash reproducers included (fuzz_replay_<name>).
# The sanitised libFuzzer runs are a second, clang build of every library (about 6 minutes on two
# idle cores): `make fuzz-smoke` or `make fuzz`, run by hand, so that CI stays within its 40 minutes.
test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS)

# The demo needs only the `quadrix` executable: no tests, baselines or micro-benchmarks are compiled.
demo: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target quadrix
	bash experiments/command_line/demo.sh $(BUILD_DIR)

clean:
	rm -rf $(BUILD_DIR)

# Fuzzing (docs/reliability.md): a separate clang build in $(FUZZ_DIR) with libFuzzer, ASan and
# UBSan that compiles only the four libraries and the harnesses of tests/fuzz, then runs each
# harness for $(SECONDS) s (and at most $(RUNS) executions when set) with seeds cut from $(DATA_DIR),
# and writes $(FUZZ_DIR)/fuzz-summary.md. Fails when a harness crashed, leaked, hung or ran out of memory.
# `make fuzz-smoke` is the same with 3 s a harness (by hand: `make test` replays the seeds only).
FUZZ_DIR ?= build-fuzz
SECONDS ?= 60
RUNS ?= 0
fuzz-build: setup
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=Debug -DQUADRIX_FUZZ=ON \
	  -DQUADRIX_BUILD_TESTS=OFF -DQUADRIX_BUILD_BENCHMARKS=OFF -DQUADRIX_BUILD_PYTHON=OFF \
	  -DCGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE=TRUE
	cmake --build $(FUZZ_DIR) -j$(JOBS) --target fuzz_harnesses

fuzz: fuzz-build
	/usr/bin/python3 tests/fuzz/run_fuzz.py --build $(FUZZ_DIR) --seconds $(SECONDS) --runs $(RUNS) --data $(DATA_DIR)

fuzz-smoke:
	$(MAKE) fuzz SECONDS=3 RUNS=0

# The whole suite under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer, built
# with gcc at -O1 in $(SANITIZE_DIR); a report fails the test that triggered it. Not part of `make
# test` (a second full build: see docs/reliability.md for its time). The Python module is left out
# (Debian's python3 would need libasan preloaded) and so is package_find_package, whose outside
# project links the installed libraries without the sanitizer runtime.
# EIGEN_MALLOC_ALREADY_ALIGNED=1: Eigen switches to its own offset-pointer allocator when it sees
# __SANITIZE_ADDRESS__, while Debian's PCL and Open3D were compiled without ASan and use plain
# malloc; an Eigen buffer allocated on one side and freed on the other is then a false heap overflow
# (or a free of a pointer malloc never returned). The define keeps our allocator the libraries' one.
SANITIZE_DIR ?= build-sanitize
SANITIZE_FLAGS = -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer \
  -DEIGEN_MALLOC_ALREADY_ALIGNED=1
test-sanitize: setup
	cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -g -DNDEBUG" \
	  "-DCMAKE_C_FLAGS_RELEASE=-O1 -g -DNDEBUG" "-DCMAKE_CXX_FLAGS=$(SANITIZE_FLAGS)" "-DCMAKE_C_FLAGS=$(SANITIZE_FLAGS)" \
	  "-DCMAKE_EXE_LINKER_FLAGS=$(SANITIZE_FLAGS)" "-DCMAKE_SHARED_LINKER_FLAGS=$(SANITIZE_FLAGS)" \
	  -DQUADRIX_BUILD_BENCHMARKS=OFF -DQUADRIX_BUILD_PYTHON=OFF
	cmake --build $(SANITIZE_DIR) -j$(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j$(JOBS) -E '^package_find_package$$'

# Regenerates the committed refiner study (papers/studies/refiners.{md,csv,svg}) with its
# fixed seeds; needs ../shared/data for the KITTI part (skipped with a note when absent).
study-refiners: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target quadrix
	$(BUILD_DIR)/bin/quadrix compare-refiners --out papers/studies

# Regenerates the committed fitter study (papers/studies/fitters.{md,csv,svg}) with its fixed seeds;
# needs ../shared/data for the real segments (skipped with a note when absent).
study-fitters: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target quadrix
	$(BUILD_DIR)/bin/quadrix compare-fitters --out papers/studies

# Trains the learned fitter (fitting/training/train_learned_fitter.py) on segments cut from simulated
# scans (`quadrix fitter-segments`, fixed seed) plus analytic ones, and exports its weights into
# fitting/models/learned_fitter/ and its loss curves into papers/studies/learned_fitter_training.svg.
# Training only: build and tests never run it. Uses Debian's python3-torch/python3-numpy via
# /usr/bin/python3 (installed here when missing). About 6 CPU-minutes of simulation and 17 of training
# (two single-thread worker processes; every type stops early, at 29-45 epochs).
FITTER_SEGMENTS_DIR = $(BUILD_DIR)/fitter_segments
train-fitter: configure
	@/usr/bin/python3 -c "import torch, numpy" 2>/dev/null || \
	  (apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3-torch python3-numpy)
	cmake --build $(BUILD_DIR) -j$(JOBS) --target quadrix
	$(BUILD_DIR)/bin/quadrix fitter-segments --seed 101 --scans 400 --object-scans 3000 --crops 2 --out $(FITTER_SEGMENTS_DIR)
	/usr/bin/python3 fitting/training/train_learned_fitter.py --scan-segments $(FITTER_SEGMENTS_DIR) \
	  --loss-svg papers/studies/learned_fitter_training.svg

# Regenerates papers/quadricsreg/ (results/ and the page README.md) from a clean build: `quadrix bench`
# on every pair of $(DATA_DIR)/pairs.tsv with every method, the six KITTI loop closures under random yaw
# (--yaw-range 180 --trials 10), one run per row of the paper's ablation table, the synthetic
# loop-closure validation set (HDL-64E, and the same streets scanned by a VLP-16), the shared KITTI
# frames paired 20-50 m apart under random yaw, and the labelled KITTI pair with and without
# classes, then `quadrix paper`.
# Several CPU-minutes on 2 cores.
DATA_DIR ?= ../shared/data
PAPER_DIR = papers/quadricsreg
PAPER_METHODS = quadrix,open3d-ransac,open3d-fgr,pcl-prerejective
PAPER_TRIALS ?= 10
# The baselines take about a minute per pair on 2 loaded cores, so the yaw trials run Quadrix only by
# default (FPFH features are rotation invariant; the baselines run on every unperturbed pair above).
PAPER_YAW_METHODS ?= quadrix
ABLATION_TRIALS ?= 3
# The synthetic loop-closure validation set (docs/benchmark.md), generated into the build tree, and
# the one real pair that has labels on both sides, both run without and with the given classes.
LOOP_CLOSURE_SET = $(BUILD_DIR)/loop_closures/validation
# The same streets scanned by a simulated VLP-16: the verification's thresholds were set on
# HDL-64E-like scans, and this run shows what they let through on a sparse sensor.
LOOP_CLOSURE_SET_VLP16 = $(BUILD_DIR)/loop_closures/validation-vlp16
# The shared KITTI-00 frames as a KITTI layout (links, no copies), so `quadrix bench --kitti` can pair
# every two of them 20-50 m apart with the ground truth of the shared poses.
KITTI_LAYOUT = $(BUILD_DIR)/kitti_layout
LABELLED_PAIRS = $(BUILD_DIR)/loop_closures/labelled_pairs.tsv
PAPER_ABLATIONS = default no-semantics no-central no-linear-center no-planar-center no-augmented-points \
  ke30 ke40 ke60 ks15 ks25 dm-0.2 dm-0.8 dm-0.2-0.8 dm-0.2-0.6-0.8 dm-0.2-0.4-0.6-0.8-1.0 \
  no-er no-et no-augmented-factors no-refinement
papers: build
	$(BUILD_DIR)/bin/quadrix bench --pairs $(DATA_DIR)/pairs.tsv --method $(PAPER_METHODS) --jobs $(JOBS) \
	  --title "Every shared pair, every method" --out $(PAPER_DIR)/results/pairs
	$(BUILD_DIR)/bin/quadrix bench --pairs $(DATA_DIR)/pairs.tsv --ids '^kitti00_lc' --method $(PAPER_YAW_METHODS) \
	  --yaw-range 180 --trials $(PAPER_TRIALS) --seed 1 --jobs $(JOBS) \
	  --title "KITTI-00 loop closures, random yaw in [-180, 180] deg" --out $(PAPER_DIR)/results/kitti-lc-yaw180
	for ablation in $(PAPER_ABLATIONS); do \
	  $(BUILD_DIR)/bin/quadrix bench --pairs $(DATA_DIR)/pairs.tsv --ids '^kitti00_lc' --method quadrix \
	    --yaw-range 180 --trials $(ABLATION_TRIALS) --seed 2 --jobs $(JOBS) --no-progress --ablation $$ablation \
	    --title "Ablation $$ablation: KITTI-00 loop closures, random yaw" --out $(PAPER_DIR)/results/ablation-$$ablation || exit 1; \
	done
	mkdir -p $(KITTI_LAYOUT)/sequences/00 $(KITTI_LAYOUT)/poses
	ln -sfn $(abspath $(DATA_DIR))/kitti00/velodyne $(KITTI_LAYOUT)/sequences/00/velodyne
	ln -sfn $(abspath $(DATA_DIR))/kitti_poses/00.txt $(KITTI_LAYOUT)/poses/00.txt
	$(BUILD_DIR)/bin/quadrix bench --kitti $(KITTI_LAYOUT) --seq 00 --calib $(DATA_DIR)/kitti_poses/calib_Tr_velo_to_cam.txt \
	  --mode lc --t-lc 0 --bins 20-30,30-40,40-50 --method quadrix --yaw-range 180 --trials $(PAPER_TRIALS) --seed 5 \
	  --jobs $(JOBS) --no-progress --title "KITTI-00 pairs 20-50 m apart (every pair of the shared frames), random yaw" \
	  --out $(PAPER_DIR)/results/kitti-far-yaw180
	$(BUILD_DIR)/bin/quadrix synth loop-closures --seed 2001 --streets 5 --pairs-per-bin 20 --out $(LOOP_CLOSURE_SET)
	$(BUILD_DIR)/bin/quadrix bench --pairs $(LOOP_CLOSURE_SET)/pairs.tsv --method quadrix --yaw-range 180 --seed 3 \
	  --jobs $(JOBS) --no-progress --title "Synthetic loop closures (validation set, seeds 2001-2005), random yaw, no labels" \
	  --out $(PAPER_DIR)/results/lc-validation-geometry
	$(BUILD_DIR)/bin/quadrix bench --pairs $(LOOP_CLOSURE_SET)/pairs.tsv --method quadrix --yaw-range 180 --seed 3 --labels \
	  --jobs $(JOBS) --no-progress --title "Synthetic loop closures (validation set, seeds 2001-2005), random yaw, simulator labels" \
	  --out $(PAPER_DIR)/results/lc-validation-labels
	$(BUILD_DIR)/bin/quadrix synth loop-closures --seed 2001 --streets 5 --pairs-per-bin 20 --sensor vlp16 --out $(LOOP_CLOSURE_SET_VLP16)
	$(BUILD_DIR)/bin/quadrix bench --pairs $(LOOP_CLOSURE_SET_VLP16)/pairs.tsv --method quadrix --jobs $(JOBS) --no-progress \
	  --title "Synthetic loop closures scanned by a VLP-16 (validation seeds 2001-2005), no labels" \
	  --out $(PAPER_DIR)/results/lc-validation-vlp16
	printf 'id\tsource\ttarget\tgt\tgt_quality\tsensor\tkind\tt_m\trot_deg\tsource_labels\ttarget_labels\n' > $(LABELLED_PAIRS)
	awk -F'\t' -v data=$(abspath $(DATA_DIR)) 'BEGIN { OFS = "\t" } $$1 == "kitti00_odo_52_88" { \
	  $$2 = data "/" $$2; $$3 = data "/" $$3; $$4 = data "/" $$4; \
	  print $$1, $$2, $$3, $$4, $$5, $$6, $$7, $$8, $$9, data "/kitti00/labels/000052.label", data "/kitti00/labels/000088.label" }' \
	  $(DATA_DIR)/pairs.tsv >> $(LABELLED_PAIRS)
	$(BUILD_DIR)/bin/quadrix bench --pairs $(LABELLED_PAIRS) --method quadrix --no-progress \
	  --title "KITTI-00 52 -> 88 (29.9 m), no labels" --out $(PAPER_DIR)/results/kitti-52-88-geometry
	$(BUILD_DIR)/bin/quadrix bench --pairs $(LABELLED_PAIRS) --method quadrix --labels --no-progress \
	  --title "KITTI-00 52 -> 88 (29.9 m), SemanticKITTI labels" --out $(PAPER_DIR)/results/kitti-52-88-labels
	$(BUILD_DIR)/bin/quadrix paper --results $(PAPER_DIR)/results --tables $(PAPER_DIR)/tables --out $(PAPER_DIR)/README.md
