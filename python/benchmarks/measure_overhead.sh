#!/usr/bin/env bash
# The overhead of quadrix.register over the C++ call (docs/python.md): ROUNDS alternated rounds of
# RUNS runs of build/bin/quadrix_register_timing (C++) and register_timing.py (Python: arrays, then
# Cloud objects) on the KITTI pair 000000 -> 004438, both under the same glibc malloc tunables (a
# heap that keeps its memory between runs: otherwise the heap state the Python process inherits
# from NumPy's import, not the binding, decides which side is faster). Prints each round and a
# Markdown table of the medians of the round medians.
# Usage: bash python/benchmarks/measure_overhead.sh [BUILD_DIR=build] [DATA_DIR=../shared/data] [ROUNDS=5] [RUNS=5]
set -euo pipefail
build="${1:-build}"; data="${2:-../shared/data}"; rounds="${3:-5}"; runs="${4:-5}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source_cloud="$data/kitti00/velodyne/000000.bin"; target_cloud="$data/kitti00/velodyne/004438.ply"
[[ -f "$source_cloud" && -f "$target_cloud" ]] || { echo "measure_overhead: KITTI pair not found under $data" >&2; exit 2; }
export GLIBC_TUNABLES=glibc.malloc.mmap_threshold=268435456:glibc.malloc.trim_threshold=1073741824
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
for round in $(seq "$rounds"); do
  echo "round $round, load $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$log"
  "$build/bin/quadrix_register_timing" "$source_cloud" "$target_cloud" "$runs" | grep median | sed 's/^/cpp: /' | tee -a "$log"
  PYTHONPATH="$build/python" /usr/bin/python3 "$here/register_timing.py" "$source_cloud" "$target_cloud" "$runs" | grep median | tee -a "$log"
done
/usr/bin/python3 - "$log" <<'PY'
import re, statistics, sys
medians, outside = {"cpp": [], "arrays": [], "clouds": []}, []
for line in open(sys.argv[1]):
    match = re.match(r"(cpp|arrays|clouds): median ([\d.]+) ms", line)
    if match:
        medians[match[1]].append(float(match[2]))
        extra = re.search(r"outside C\+\+ median ([\d.]+) ms", line)
        if extra:
            outside.append(float(extra[1]))
cpp = statistics.median(medians["cpp"])
print("\n| call | median of round medians | vs C++ |\n|---|---|---|")
print(f"| C++ `resolve_registration_options` + `register_clouds` | {cpp:.1f} ms | |")
for name, label in (("arrays", "`quadrix.register` on float32 arrays"), ("clouds", "`quadrix.register` on `Cloud`s")):
    value = statistics.median(medians[name])
    print(f"| {label} | {value:.1f} ms | {100.0 * (value - cpp) / cpp:+.1f} % |")
print(f"\nPython time outside the C++ pipeline (wall - report total): median {statistics.median(outside):.2f} ms")
PY
