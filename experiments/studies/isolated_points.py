#!/usr/bin/python3
"""Measures what the isolated-point rule (geometry/voxel_cells.h) leaves out of the shared real
scans, clean and with uniform outliers added, for 1 to 3 neighbours asked for.

A study, not part of the pipeline: nothing here runs at build or test time. It needs
python3-numpy, the `quadrix` Python module (to read the clouds) and the shared data folder.

Each scan is cropped to 80 m around the sensor; outliers are drawn uniformly over its bounding box,
as `quadrix bench --corrupt outliers-P` draws them. A point is kept when at least N other points lie
in its 0.3 m cube or the 26 around it. Printed per scan and outlier share: the share of real
points left out and the share of outliers kept. Results are recorded in docs/registration.md
("Isolated points").

Usage: PYTHONPATH=build/python /usr/bin/python3 experiments/studies/isolated_points.py [DATA_DIR]
"""
import os
import sys

import numpy as np
import quadrix

SCANS = {
    "KITTI-00 frame 52": "kitti00/velodyne/000052.bin",
    "KITTI-00 frame 0": "kitti00/velodyne/000000.bin",
    "HDL-32E": "hdl32_pair/source.ply",
    "3DTK scan 1": "3dtk/scan001_RH_m.xyz",
    "3DTK scan 2": "3dtk/scan002_RH_m.xyz",
    "VLP-16 demo": "quadricsreg_demo/vlp16_source.ply",
    "Livox Avia demo": "quadricsreg_demo/avia_source.ply",
    "Livox Mid-360 demo": "quadricsreg_demo/mid360_source.ply",
}
CELL = 0.3  # m, the default of extraction.isolation_cell and ambiguity.isolation_cell
MAXIMUM_RANGE = 80.0  # m, the HDL-64E preset's crop
NEIGHBOURS = (1, 2, 3)


def cube_keys(cubes):
    """One integer per cube (21 bits an axis, offset to be non-negative)."""
    offset = 1 << 20
    return ((cubes[:, 0] + offset) << 42) + ((cubes[:, 1] + offset) << 21) + (cubes[:, 2] + offset)


def other_points_in_block(points):
    """For each point, how many other points lie in its cube of CELL or the 26 around it."""
    cubes = np.floor(points / CELL).astype(np.int64)
    keys, counts = np.unique(cube_keys(cubes), return_counts=True)
    total = np.zeros(len(points), np.int64)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                wanted = cube_keys(cubes + np.array([dx, dy, dz]))
                where = np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)
                found = keys[where] == wanted
                total[found] += counts[where[found]]
    return total - 1


def main(argv):
    """Prints the table for every scan found; returns the exit code."""
    data = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(__file__), "../../../shared/data")
    random = np.random.default_rng(1)
    for name, relative in SCANS.items():
        path = os.path.join(data, relative)
        if not os.path.exists(path):
            print(f"{name}: {path} absent, skipped")
            continue
        points = np.asarray(quadrix.read_cloud(path).points, dtype=np.float64)
        points = points[np.linalg.norm(points, axis=1) <= MAXIMUM_RANGE]
        others = other_points_in_block(points)
        print(f"{name}, clean: " + ", ".join(f"{n} neighbours: {np.mean(others < n):.2%} left out" for n in NEIGHBOURS))
        for share in (0.3, 0.5):
            low, high = points.min(axis=0), points.max(axis=0)
            outliers = low + random.random((int(share * len(points)), 3)) * (high - low)
            others = other_points_in_block(np.vstack([points, outliers]))
            real, added = others[: len(points)], others[len(points):]
            print(f"{name}, {share:.0%} outliers: " + ", ".join(
                f"{n} neighbours: {np.mean(real < n):.2%} of real points left out, {np.mean(added >= n):.1%} of outliers kept"
                for n in NEIGHBOURS))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
