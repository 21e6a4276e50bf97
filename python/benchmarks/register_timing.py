#!/usr/bin/env python3
"""The Python side of the overhead measurement (docs/python.md).

Reads SOURCE and TARGET once, then RUNS times calls quadrix.register on the clouds in memory, once
with (N, 3) float32 NumPy arrays and once with quadrix.Cloud objects, and prints each wall time and
the medians in ms. Compare with build/bin/quadrix_register_timing SOURCE TARGET RUNS. Each run also
prints the part of the wall time spent outside the C++ pipeline: the wall time minus the report's
"total" (which spans the argument conversion, the `auto` presets and register_clouds), i.e. the
report's JSON, its json.loads and the result object.

Usage: PYTHONPATH=build/python /usr/bin/python3 python/benchmarks/register_timing.py SOURCE TARGET [RUNS=5]
"""
import statistics
import sys
import time

import numpy as np
import quadrix


def main(argv):
    """Times quadrix.register on arrays and on Cloud objects; returns the exit code."""
    if len(argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    runs = int(argv[3]) if len(argv) == 4 else 5
    source, target = quadrix.read_cloud(argv[1]), quadrix.read_cloud(argv[2])
    inputs = {
        "arrays": (np.array(source.points), np.array(target.points)),
        "clouds": (source, target),
    }
    for name, (a, b) in inputs.items():
        times, outside = [], []
        for run in range(runs):
            start = time.perf_counter()
            result = quadrix.register(a, b)
            times.append((time.perf_counter() - start) * 1000.0)
            outside.append(times[-1] - result.timings_ms["total"])
            print(f"{name} run {run + 1}: {times[-1]:.1f} ms ({result.status}; outside C++ {outside[-1]:.2f} ms,"
                  f" conversion {result.timings_ms['load']:.2f} ms)")
        print(f"{name}: median {statistics.median(times):.1f} ms over {runs} runs,"
              f" outside C++ median {statistics.median(outside):.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
