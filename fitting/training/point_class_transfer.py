#!/usr/bin/python3
"""Measures whether per-point geometric features learned on simulated scans recognise vegetation,
trunks, poles and vehicles in real KITTI scans: the question behind a label-free semantic mode.

A study, not part of the pipeline: nothing here runs at build or test time. It needs the Python
module (build/python), python3-numpy, python3-scipy and python3-torch, and the labelled KITTI
frames of the shared data folder (kitti00/velodyne + kitti00/labels).

Per point (range-cropped to 2-80 m): height above the lowest point within 2 m (a 1 m grid), log
range, and at 10, 30 and 80 nearest neighbours linearity, planarity, scattering, |normal z|,
|principal axis z|, log extent, log neighbourhood radius and height span; plus the height span and
relative height of the point's 0.5 m and 1.5 m columns. A 64-64 ReLU network with class weights
(square root of inverse frequency) learns five classes: other, vegetation, trunk, pole, vehicle.

Runs (each prints recall R and precision P per class on every test cloud):
  --train sim   train on simulated street scans (seeds 11-17, two scans each), test on seed 18
                and on the labelled KITTI frames; --foliage solid|porous picks the simulator's trees
  --train kitti train on one labelled KITTI frame and test on the other (an upper bound for what
                these features can do on real data, not a result: the frames are the test set)
Results are recorded in docs/modelling.md ("Classes from geometry: what transfers").
"""

import argparse
import os
import sys

import numpy as np
from scipy.ndimage import minimum_filter
from scipy.spatial import cKDTree

CLASSES = ['other', 'vegetation', 'trunk', 'pole', 'vehicle']


def semantic_kitti_class(labels):
    """SemanticKITTI (and simulator) label ids -> index into CLASSES."""
    labels = labels & 0xFFFF
    out = np.zeros(labels.shape, int)
    for ids, index in [((10, 11, 13, 15, 16, 18, 20, 252, 253, 254, 255, 256, 257, 258, 259), 4), ((70,), 1),
                       ((71,), 2), ((80, 81), 3)]:
        out[np.isin(labels, ids)] = index
    return out


def height_above_ground(points, cell=1.0, reach=2):
    ij = np.floor(points[:, :2] / cell).astype(int)
    ij -= ij.min(0)
    lowest = np.full(ij.max(0) + 1, 1e9)
    np.minimum.at(lowest, (ij[:, 0], ij[:, 1]), points[:, 2])
    ground = minimum_filter(lowest, size=2 * reach + 1, mode='nearest')
    return points[:, 2] - ground[ij[:, 0], ij[:, 1]]


def neighbourhood_features(points, tree, k):
    distances, neighbours = tree.query(points, k=k)
    centred = points[neighbours] - points[neighbours].mean(1, keepdims=True)
    covariance = np.einsum('nki,nkj->nij', centred, centred) / k
    values, vectors = np.linalg.eigh(covariance)
    values = np.maximum(values, 1e-9)
    smallest, middle, largest = values[:, 0], values[:, 1], values[:, 2]
    span = centred[:, :, 2].max(1) - centred[:, :, 2].min(1)
    return np.stack([(largest - middle) / largest, (middle - smallest) / largest, smallest / largest,
                     np.abs(vectors[:, 2, 0]), np.abs(vectors[:, 2, 2]), np.log(np.sqrt(largest) + 1e-3),
                     np.log(distances[:, -1] + 1e-3), span], 1)


def column_features(points, height, cell):
    ij = np.floor(points[:, :2] / cell).astype(np.int64)
    _, column = np.unique(ij[:, 0] * 100003 + ij[:, 1], return_inverse=True)
    top = np.full(column.max() + 1, -np.inf)
    np.maximum.at(top, column, height)
    bottom = np.full(column.max() + 1, np.inf)
    np.minimum.at(bottom, column, height)
    span = top[column] - bottom[column]
    return np.stack([top[column], bottom[column], span, (height - bottom[column]) / np.maximum(span, 0.1)], 1)


def features(points):
    points = points.astype(np.float64)
    tree = cKDTree(points)
    height = height_above_ground(points)
    parts = [height[:, None], np.log(np.linalg.norm(points[:, :2], axis=1) + 1)[:, None]]
    parts += [neighbourhood_features(points, tree, k) for k in (10, 30, 80)]
    parts += [column_features(points, height, 0.5), column_features(points, height, 1.5)]
    return np.concatenate(parts, 1).astype(np.float32)


def cropped(points, labels):
    distance = np.linalg.norm(points, axis=1)
    keep = (distance > 2) & (distance < 80)
    return features(points[keep]), semantic_kitti_class(labels[keep])


def kitti_frame(data, frame):
    points = np.fromfile(os.path.join(data, 'kitti00/velodyne/%06d.bin' % frame), dtype=np.float32).reshape(-1, 4)
    labels = np.fromfile(os.path.join(data, 'kitti00/labels/%06d.label' % frame), dtype=np.uint32)
    return cropped(points[:, :3], labels)


def simulated_scans(quadrix, seed, foliage):
    run = quadrix.synth('street', seed=seed, sensor='hdl64', primitives=False, foliage=foliage)
    return [cropped(np.array(cloud.points), np.array(cloud.labels)) for cloud in run['clouds']]


def train(features_, classes, epochs=30, seed=0):
    import torch  # here, so class_separability.py can share this file's features with numpy and scipy alone
    torch.manual_seed(seed)
    mean, deviation = features_.mean(0), features_.std(0) + 1e-6
    inputs, targets = torch.tensor((features_ - mean) / deviation), torch.tensor(classes)
    counts = np.bincount(classes, minlength=len(CLASSES)).astype(float)
    weights = torch.tensor((counts.sum() / np.maximum(counts, 1) / len(CLASSES)) ** 0.5, dtype=torch.float32)
    network = torch.nn.Sequential(torch.nn.Linear(features_.shape[1], 64), torch.nn.ReLU(), torch.nn.Linear(64, 64),
                                  torch.nn.ReLU(), torch.nn.Linear(64, len(CLASSES)))
    optimiser = torch.optim.Adam(network.parameters(), 1e-3)
    for _ in range(epochs):
        order = torch.randperm(len(inputs))
        for start in range(0, len(inputs), 1024):
            batch = order[start:start + 1024]
            loss = torch.nn.functional.cross_entropy(network(inputs[batch]), targets[batch], weight=weights)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
    return lambda test: network(torch.tensor((test - mean) / deviation)).argmax(1).numpy()


def report(name, predicted, truth):
    cells = []
    for index in range(1, len(CLASSES)):
        recall = np.mean(predicted[truth == index] == index) if (truth == index).any() else float('nan')
        precision = np.mean(truth[predicted == index] == index) if (predicted == index).any() else 0.0
        cells.append('%s R%.2f P%.2f' % (CLASSES[index], recall, precision))
    print('%-14s %s' % (name, '  '.join(cells)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--train', choices=['sim', 'kitti'], default='sim')
    parser.add_argument('--foliage', choices=['solid', 'porous'], default='porous')
    parser.add_argument('--data', default=os.path.join(os.path.dirname(__file__), '../../../shared/data'))
    parser.add_argument('--module', default=os.path.join(os.path.dirname(__file__), '../../build/python'))
    arguments = parser.parse_args()
    kitti = {frame: kitti_frame(arguments.data, frame) for frame in (52, 88)}
    if arguments.train == 'kitti':
        for train_frame, test_frame in ((52, 88), (88, 52)):
            model = train(*kitti[train_frame])
            report('kitti %d->%d' % (train_frame, test_frame), model(kitti[test_frame][0]), kitti[test_frame][1])
        return
    sys.path.insert(0, arguments.module)
    import quadrix
    scans = [scan for seed in range(11, 18) for scan in simulated_scans(quadrix, seed, arguments.foliage)]
    model = train(np.concatenate([f for f, _ in scans]), np.concatenate([c for _, c in scans]))
    for index, (test_features, test_classes) in enumerate(simulated_scans(quadrix, 18, arguments.foliage)):
        report('sim 18 scan %d' % index, model(test_features), test_classes)
    for frame, (test_features, test_classes) in kitti.items():
        report('kitti %d' % frame, model(test_features), test_classes)


if __name__ == '__main__':
    main()
