#!/usr/bin/python3
"""Measures the best per-point recall any per-segment classifier could reach on the labelled KITTI
frames: each segment is given its own true majority class (an oracle), so a real classifier of
those segments can only do worse.

A study, not part of the pipeline: nothing here runs at build or test time. It needs python3-numpy
and python3-scipy and the labelled KITTI frames of the shared data folder (kitti00/velodyne +
kitti00/labels). It reads the test frames themselves, so it sets no threshold.

Points 2-80 m from the sensor and more than 0.1 m above the ground (height_above_ground of
point_class_transfer.py) are segmented two ways:
  euclidean   connected components of the points closer than a radius (0.2, 0.3, 0.5 m)
  same shape  the same, joining two neighbours only when their 15-neighbour covariances have the
              same dominant shape (linear, planar or scattered; the largest of the three
              eigenvalue features) and, for linear and planar ones, their directions or normals
              agree within the given cosine: a segmentation that stops where a trunk meets a
              crown if their local shapes differ
Points at or below 0.1 m count as wrongly classed (any classifier of segments would see them as
ground). For trunk points it also prints where they went: the majority class of their segments.
Results are recorded in docs/modelling.md ("Classes from geometry: what transfers").
"""

import argparse
import os
import sys

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from point_class_transfer import CLASSES, height_above_ground, semantic_kitti_class  # noqa: E402

TRUNK = CLASSES.index('trunk')


def labelled_frame(data, frame):
    """KITTI-00 frame's points (2-80 m from the sensor) and their CLASSES indices."""
    points = np.fromfile(os.path.join(data, 'kitti00/velodyne/%06d.bin' % frame), dtype=np.float32).reshape(-1, 4)
    labels = np.fromfile(os.path.join(data, 'kitti00/labels/%06d.label' % frame), dtype=np.uint32)
    distance = np.linalg.norm(points[:, :3], axis=1)
    keep = (distance > 2) & (distance < 80)
    return points[keep, :3].astype(np.float64), semantic_kitti_class(labels[keep])


def local_shape(points, tree, neighbours=15):
    """Dominant shape (0 linear, 1 planar, 2 scattered), principal axis and normal of every point."""
    _, index = tree.query(points, k=neighbours)
    centred = points[index] - points[index].mean(1, keepdims=True)
    values, vectors = np.linalg.eigh(np.einsum('nki,nkj->nij', centred, centred) / neighbours)
    values = np.maximum(values, 1e-9)
    smallest, middle, largest = values[:, 0], values[:, 1], values[:, 2]
    shape = np.argmax(np.stack([(largest - middle) / largest, (middle - smallest) / largest, smallest / largest], 1), 1)
    return shape, vectors[:, :, 2], vectors[:, :, 0]


def segments(count, first, second):
    """Connected components of the graph with edges first[k]-second[k]."""
    graph = coo_matrix((np.ones(len(first)), (first, second)), shape=(count, count))
    return connected_components(graph, directed=False)[1]


def oracle_recall(segment, classes, total_per_class):
    """Per-class share of all labelled points whose segment's true majority class is their own."""
    votes = np.zeros((segment.max() + 1, len(CLASSES)))
    np.add.at(votes, (segment, classes), 1)
    majority = votes.argmax(1)[segment]
    recall = [np.sum((classes == index) & (majority == index)) / total_per_class[index] for index in range(len(CLASSES))]
    return recall, majority


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--data', default=os.path.join(os.path.dirname(__file__), '../../../shared/data'))
    arguments = parser.parse_args()
    for frame in (52, 88):
        points, classes = labelled_frame(arguments.data, frame)
        total_per_class = np.maximum(np.bincount(classes, minlength=len(CLASSES)), 1)
        above = height_above_ground(points) > 0.1
        points, classes = points[above], classes[above]
        tree = cKDTree(points)
        shape, axis, normal = local_shape(points, tree)
        runs = []
        for radius in (0.2, 0.3, 0.5):
            pairs = tree.query_pairs(radius, output_type='ndarray')
            runs.append(('euclidean %.1f m' % radius, segments(len(points), pairs[:, 0], pairs[:, 1])))
        for radius, cosine in ((0.25, 0.9), (0.3, 0.8), (0.3, 0.95)):
            pairs = tree.query_pairs(radius, output_type='ndarray')
            first, second = pairs[:, 0], pairs[:, 1]
            directions_agree = np.where(shape[first] == 0, np.abs(np.sum(axis[first] * axis[second], 1)) > cosine,
                                        np.abs(np.sum(normal[first] * normal[second], 1)) > cosine)
            join = (shape[first] == shape[second]) & ((shape[first] == 2) | directions_agree)
            runs.append(('same shape %.2f m, cos %.2f' % (radius, cosine),
                         segments(len(points), first[join], second[join])))
        for name, segment in runs:
            recall, majority = oracle_recall(segment, classes, total_per_class)
            trunk_went = np.bincount(majority[classes == TRUNK], minlength=len(CLASSES)) / max(1, np.sum(classes == TRUNK))
            print('frame %d %-28s segments %5d  %s   trunk points in segments of: %s' % (
                frame, name, segment.max() + 1,
                '  '.join('%s %.2f' % (CLASSES[index], recall[index]) for index in range(1, len(CLASSES))),
                ' '.join('%s %.2f' % (CLASSES[index], trunk_went[index]) for index in range(len(CLASSES)))))


if __name__ == '__main__':
    main()
