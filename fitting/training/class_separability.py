#!/usr/bin/python3
"""Measures whether KITTI's vegetation, trunks and poles differ from façades and cars in the
local-geometry features a label-free classifier would rely on, per point and pooled over voxels.

A study, not part of the pipeline: nothing here runs at build or test time. It needs
python3-numpy and python3-scipy and the labelled KITTI frames of the shared data folder
(kitti00/velodyne + kitti00/labels). It reads the test frames themselves, so it sets no threshold:
it only asks whether any threshold could separate the classes.

Per point, for points more than 0.25 m above the ground (height_above_ground of
point_class_transfer.py) and 2-80 m from the sensor:
  roughness   square root of the smallest eigenvalue of the 20 nearest neighbours' covariance, m
  voxel roughness, voxel normal scatter
              the mean roughness of the points in the point's voxel (0.5 and 1 m), and
              1 - the largest eigenvalue of the mean n n^T of their normals (0: all parallel)
  column top  the highest point above the ground in the point's 0.5 m column, m
  intensity   the scan's remission (KITTI's fourth float, 0-1)
Each is printed as the 10/25/50/75/90th percentiles per class (SemanticKITTI classes mapped as in
point_class_transfer.py: other, vegetation, trunk, pole incl. traffic sign, vehicle) and for the
building and fence labels inside "other".

Then a bound: for vegetation, trunks and poles, and for each feature above and the height above the
ground, the best rule `low <= feature <= high` that keeps 80% of the class's points (the recall the
acceptance asks for), over every point 2-80 m from the sensor, with low and high chosen on the frame
itself; printed with its precision. A rule set on the test frame is an upper bound for any
threshold on that feature, not a classifier. Results are recorded in docs/modelling.md ("Classes
from geometry: what transfers").
"""

import argparse
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from point_class_transfer import CLASSES, height_above_ground, semantic_kitti_class  # noqa: E402

BUILDING, FENCE = 50, 51


def local_geometry(points, neighbours=20):
    """Roughness (m) and unit normal of every point from its nearest neighbours' covariance."""
    _, index = cKDTree(points).query(points, k=neighbours)
    centred = points[index] - points[index].mean(1, keepdims=True)
    values, vectors = np.linalg.eigh(np.einsum('nki,nkj->nij', centred, centred) / neighbours)
    return np.sqrt(np.maximum(values[:, 0], 0.0)), vectors[:, :, 0]


def voxel_pooled(points, roughness, normals, size):
    """Mean roughness and normal scatter of each point's voxel, and the voxel's point count."""
    keys = np.floor(points / size).astype(np.int64)
    _, voxel, count = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    voxel = voxel.ravel()
    mean_roughness = np.bincount(voxel, roughness) / count
    outer = np.einsum('ni,nj->nij', normals, normals).reshape(-1, 9)
    mean_outer = np.stack([np.bincount(voxel, outer[:, k]) for k in range(9)], 1) / count[:, None]
    scatter = 1.0 - np.linalg.eigvalsh(mean_outer.reshape(-1, 3, 3))[:, 2]
    return mean_roughness[voxel], scatter[voxel], count[voxel]


def column_top(points, height, size=0.5):
    """Highest height above the ground in each point's column of `size` metres."""
    keys = np.floor(points[:, :2] / size).astype(np.int64)
    _, column = np.unique(keys, axis=0, return_inverse=True)
    column = column.ravel()
    top = np.full(column.max() + 1, -np.inf)
    np.maximum.at(top, column, height)
    return top[column]


def precision_at_recall(values, members, recall=0.8, steps=21):
    """The best band [low, high] of `values` holding `recall` of the members: (precision, low, high)."""
    best = (0.0, 0.0, 0.0)
    for start in np.linspace(0.0, 1.0 - recall, steps):
        low, high = np.quantile(values[members], [start, start + recall])
        admitted = (values >= low) & (values <= high)
        precision = (admitted & members).sum() / max(admitted.sum(), 1)
        best = max(best, (precision, low, high))
    return best


def percentiles(values):
    return ' '.join(f'{v:6.3f}' for v in np.percentile(values, [10, 25, 50, 75, 90]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--data', default=os.path.join(os.path.dirname(__file__), '../../../shared/data'),
                        help='the shared data folder (holds kitti00/)')
    parser.add_argument('--frames', nargs='+', default=['000052', '000088'])
    args = parser.parse_args()
    for frame in args.frames:
        scan = np.fromfile(os.path.join(args.data, 'kitti00/velodyne', frame + '.bin'), np.float32).reshape(-1, 4)
        labels = np.fromfile(os.path.join(args.data, 'kitti00/labels', frame + '.label'), np.uint32)
        points = scan[:, :3].astype(np.float64)
        distance = np.linalg.norm(points[:, :2], axis=1)
        kept = (distance > 2.0) & (distance < 80.0)
        points, labels, intensity = points[kept], labels[kept], scan[kept, 3].astype(np.float64)
        classes, semantic = semantic_kitti_class(labels), labels & 0xFFFF
        height = height_above_ground(points)
        roughness, normals = local_geometry(points)
        features = {'roughness': roughness, 'column top': column_top(points, height), 'intensity': intensity}
        for size in (0.5, 1.0):
            pooled_roughness, scatter, _ = voxel_pooled(points, roughness, normals, size)
            features[f'voxel {size} m roughness'] = pooled_roughness
            features[f'voxel {size} m normal scatter'] = scatter
        groups = [(name, classes == k) for k, name in enumerate(CLASSES)]
        groups += [('  building', semantic == BUILDING), ('  fence', semantic == FENCE)]
        above = height > 0.25
        print(f'frame {frame}: percentiles 10/25/50/75/90 of points > 0.25 m above the ground')
        for feature, values in features.items():
            print(f'  {feature}')
            for name, members in groups:
                chosen = members & above
                if chosen.any():
                    print(f'    {name:12s} {chosen.sum():6d}  {percentiles(values[chosen])}')
        features['height above ground'] = height
        print(f'frame {frame}: the best band of one feature holding 80% of a class (all points 2-80 m), its precision')
        for index in (1, 2, 3):
            members = classes == index
            if not members.any():
                continue
            for feature, values in features.items():
                precision, low, high = precision_at_recall(values, members)
                print(f'  {CLASSES[index]:10s} {feature:28s} {low:7.3f} .. {high:7.3f}  precision {precision:.3f}')


if __name__ == '__main__':
    main()
