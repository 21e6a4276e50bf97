#!/usr/bin/python3
"""Measures whether an overlap counted only where the target sensor looked would tell right answers
from wrong ones better than the pipeline's overlap does.

A study, not part of the pipeline: nothing here runs at build or test time. It needs
python3-numpy, python3-scipy, the `quadrix` Python module and a pairs file with ground truth (a
`quadrix synth loop-closures` set, or any pairs.tsv).

For every pair, `quadrix.register` runs as the command line does. Every transform it weighed is
scored: the answer, and each of the dense search's optima when the search ran. Each score is taken
over the source points more than 0.5 m above the source's ground (at most about 3,000, evenly
strided):
  raw      the share within 0.3 m of a target point (the pipeline's overlap, recomputed)
  visible  the same share, over only the points that land where the target sensor looked: a
           direction cell of the target's range image (0.5 deg of azimuth by 1 deg of elevation, as
           the free-space check bins them; an empty cell takes its elevation neighbours' nearest
           return, for sparse rings) with a return no nearer than the point's range minus 0.5 m
Each transform is right or wrong by the paper's rule (2 m, 5 deg). Printed per set: the spread of
both scores for right and wrong transforms, and in how many pairs a right transform scores
highest. Results are recorded in docs/registration.md ("Known failures and limits").

Usage: PYTHONPATH=build/python /usr/bin/python3 experiments/studies/visible_overlap.py PAIRS.tsv...
"""
import csv
import math
import os
import sys

import numpy as np
import quadrix
from scipy.spatial import cKDTree

AZIMUTH_CELLS, ELEVATION_CELLS = 720, 180


def direction_cells(offsets):
    """Azimuth and elevation cell of each direction from the sensor (free_space.cpp's binning)."""
    horizontal = np.hypot(offsets[:, 0], offsets[:, 1])
    azimuth = ((np.arctan2(offsets[:, 1], offsets[:, 0]) + math.pi) * AZIMUTH_CELLS / (2 * math.pi)).astype(int)
    elevation = ((np.arctan2(offsets[:, 2], horizontal) + math.pi / 2) * ELEVATION_CELLS / math.pi + 0.5).astype(int)
    return np.clip(azimuth, 0, AZIMUTH_CELLS - 1), np.clip(elevation, 0, ELEVATION_CELLS - 1)


def nearest_returns(points):
    """The target's range image: the nearest return per cell, empty cells filled from their elevation neighbours."""
    azimuth, elevation = direction_cells(points)
    image = np.full((AZIMUTH_CELLS, ELEVATION_CELLS), np.inf)
    np.minimum.at(image, (azimuth, elevation), np.linalg.norm(points, axis=1))
    filled = image.copy()
    filled[:, 1:] = np.minimum(filled[:, 1:], image[:, :-1])
    filled[:, :-1] = np.minimum(filled[:, :-1], image[:, 1:])
    return filled


def is_right(transform, truth):
    """The paper's success rule."""
    difference = np.linalg.inv(truth) @ transform
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(difference[:3, :3]) - 1) / 2))))
    return np.linalg.norm(transform[:3, 3] - truth[:3, 3]) <= 2.0 and angle <= 5.0


def scores(source, target_tree, image, transform):
    """(raw, visible) overlap of `source` moved by `transform`."""
    moved = source @ transform[:3, :3].T + transform[:3, 3]
    azimuth, elevation = direction_cells(moved)
    nearest = image[azimuth, elevation]
    looked = np.isfinite(nearest) & (np.linalg.norm(moved, axis=1) <= nearest + 0.5)
    landed = np.isfinite(target_tree.query(moved, distance_upper_bound=0.3)[0])
    return landed.mean(), landed[looked].mean() if looked.any() else 0.0


def measure(pairs_file):
    """One row per weighed transform: (pair, right, raw, visible)."""
    folder = os.path.dirname(os.path.abspath(pairs_file))
    rows = []
    for pair in csv.DictReader(open(pairs_file), delimiter='\t'):
        if pair.get('gt', '-') in ('', '-'):
            continue
        source = np.array(quadrix.read_cloud(os.path.join(folder, pair['source'])).points, np.float64)
        target = np.array(quadrix.read_cloud(os.path.join(folder, pair['target'])).points, np.float64)
        truth = np.loadtxt(os.path.join(folder, pair['gt'])).reshape(4, 4)
        result = quadrix.register(source, target)
        ground = result.source_model.ground
        if ground and ground.get('found'):
            source = source[source @ np.array(ground['normal']) + ground['offset'] > 0.5]
        source = source[::max(1, len(source) // 3000)]
        transforms = [np.array(result.transform)]
        if result.dense_search:
            transforms += [np.array(optimum['transform']) for optimum in result.dense_search['optima']]
        tree, image = cKDTree(target), nearest_returns(target)
        for transform in transforms:
            rows.append((pair['id'], is_right(transform, truth), *scores(source, tree, image, transform)))
    return rows


def main():
    for pairs_file in sys.argv[1:]:
        rows = measure(pairs_file)
        print(pairs_file)
        for column, name in ((2, 'raw'), (3, 'visible')):
            right = np.array([row[column] for row in rows if row[1]])
            wrong = np.array([row[column] for row in rows if not row[1]])
            best_is_right = 0
            pairs = sorted({row[0] for row in rows})
            for pair in pairs:
                mine = [row for row in rows if row[0] == pair]
                best_is_right += max(mine, key=lambda row: row[column])[1]
            print('  %-8s right %4d: 5th / 50th percentile %.3f / %.3f   wrong %4d: 50th / 99th / max %.3f / %.3f / %.3f'
                  '   a right transform scores highest in %d of %d pairs' % (
                      name, len(right), np.percentile(right, 5), np.median(right), len(wrong), np.median(wrong),
                      np.percentile(wrong, 99), wrong.max(), best_is_right, len(pairs)))


if __name__ == '__main__':
    main()
