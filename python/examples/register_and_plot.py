#!/usr/bin/env python3
"""Registers a pair of clouds, prints the report and saves a top view of the aligned clouds.

Usage (from the repository root, after building):
    PYTHONPATH=build/python /usr/bin/python3 python/examples/register_and_plot.py SOURCE TARGET \
        [--preset auto] [--gt T.txt] [--out top_view.png]
Without SOURCE and TARGET it simulates the street pair of `make demo` (quadrix.synth).
The picture (matplotlib, Agg backend: no display needed) shows the target grey and the moved
source orange, seen from above, like `quadrix register --out`'s bev.png.
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the backend)
import numpy as np  # noqa: E402

import quadrix  # noqa: E402


def load_pair(arguments):
    """The source and target clouds and the ground truth (None when unknown)."""
    if arguments.source and arguments.target:
        truth = np.loadtxt(arguments.gt).reshape(4, 4) if arguments.gt else None
        return quadrix.read_cloud(arguments.source), quadrix.read_cloud(arguments.target), truth
    data = quadrix.synth("street", seed=3, sensor="hdl64", primitives=False)
    pair = data["pairs"][0]
    return data["clouds"][pair["source"]], data["clouds"][pair["target"]], pair["transform"]


def save_top_view(path, source, target, transform, title):
    """Writes a PNG of the target (grey) and the transformed source (orange) seen from above."""
    moved = source.points @ transform[:3, :3].T + transform[:3, 3]
    figure, axes = plt.subplots(figsize=(8, 8))
    axes.scatter(target.points[:, 0], target.points[:, 1], s=0.2, c="#a0a0a0", linewidths=0, label="target")
    axes.scatter(moved[:, 0], moved[:, 1], s=0.2, c="#ff7800", linewidths=0, label="source, registered")
    axes.set_aspect("equal")
    axes.set_xlabel("x (m)")
    axes.set_ylabel("y (m)")
    axes.set_title(title)
    axes.legend(loc="upper right", markerscale=20)
    figure.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(figure)


def main():
    """Parses the arguments, registers, prints the report and saves the picture."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", nargs="?", help="source cloud file")
    parser.add_argument("target", nargs="?", help="target cloud file")
    parser.add_argument("--preset", default="auto", help="sensor preset (see quadrix.presets())")
    parser.add_argument("--gt", help="ground-truth 4x4 mapping source into target (text file)")
    parser.add_argument("--out", default="top_view.png", help="PNG to write")
    arguments = parser.parse_args()

    source, target, truth = load_pair(arguments)
    result = quadrix.register(source, target, preset=arguments.preset, ground_truth=truth)
    report = dict(result.report)
    report.pop("candidates")  # one entry per clique level: long; see result.candidates
    print(json.dumps(report, indent=2))
    save_top_view(arguments.out, source, target, result.transform, f"{result.status}: {result.message}")
    print(f"wrote {arguments.out}")
    return 0 if result.ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
