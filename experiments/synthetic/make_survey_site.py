#!/usr/bin/env python3
"""A survey-scale synthetic site: a campus of copies of the simulated monument on one plaza, each
scanned by its own seven TLS stations, merged into one binary PLY, with its exact primitive list.

The monument (`quadrix synth monument --sensor tls --out DIR`) stands on a 160 x 140 m plaza
(x in [-90, 70], y in [-70, 70]); copies are placed 160 m apart in x and 140 m apart in y, so their
plazas form one ground plane. Each copy holds 33 cylinders, 24 planes besides the ground, 3
spheres and 1 cone (scene.json of the synth folder); the site holds copies times that plus one
ground plane. Each copy is scanned from its own stations only (a neighbour's stations would see it
too on a real site: the point count grows with the copies and the shadows stay the monument's).

    quadrix synth monument --sensor tls --out /tmp/monument
    /usr/bin/python3 experiments/synthetic/make_survey_site.py /tmp/monument \\
        --copies 4x2 --out /tmp/site_8.ply

Writes the PLY (float32 x, y, z, in the site's frame) and SITE.truth.json beside it.
"""
import argparse
import json
import pathlib
import sys

import numpy as np

PLAZA_X, PLAZA_Y = 160.0, 140.0
PER_COPY = {"circular_cylinder": 33, "plane": 24, "sphere": 3, "circular_cone": 1}


PLY_TYPES = {"float": "<f4", "double": "<f8", "uint": "<u4", "int": "<i4", "uchar": "u1", "ushort": "<u2", "short": "<i2"}


def read_ply_positions(path):
    """x, y, z of a binary little-endian PLY whose vertex element holds scalar properties only (as
    `quadrix synth` writes them)."""
    with open(path, "rb") as stream:
        header, count, fields = [], 0, []
        while True:
            line = stream.readline().decode("ascii", "replace").strip()
            header.append(line)
            if line.startswith("element vertex"):
                count = int(line.split()[2])
            elif line.startswith("property"):
                kind, name = line.split()[1:3]
                if kind not in PLY_TYPES:
                    sys.exit(f"make_survey_site: {path}: property {name} of type {kind} is not a scalar this reader knows")
                fields.append((name, PLY_TYPES[kind]))
            elif line == "end_header" or not line and len(header) > 100:
                break
        if "format binary_little_endian 1.0" not in header:
            sys.exit(f"make_survey_site: {path}: expected a binary little-endian PLY")
        vertices = np.fromfile(stream, dtype=np.dtype(fields), count=count)
    if vertices.shape[0] != count:
        sys.exit(f"make_survey_site: {path}: {vertices.shape[0]} of {count} vertices present (truncated)")
    return np.column_stack([vertices["x"], vertices["y"], vertices["z"]]).astype(np.float64)


def station_points(folder):
    """Every station of a `quadrix synth ... --sensor tls` folder moved into the world frame (float64)."""
    scans = sorted(folder.glob("scan_*.ply"))
    if not scans:
        sys.exit(f"make_survey_site: no scan_*.ply in {folder} (run `quadrix synth monument --sensor tls --out {folder}`)")
    clouds = []
    for scan in scans:
        pose_file = folder / scan.name.replace("scan_", "pose_").replace(".ply", ".txt")
        pose = np.loadtxt(pose_file).reshape(4, 4)
        points = read_ply_positions(scan)
        clouds.append(points @ pose[:3, :3].T + pose[:3, 3])
    return np.concatenate(clouds)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("monument", type=pathlib.Path, help="folder written by quadrix synth monument --sensor tls")
    parser.add_argument("--copies", default="2x2", help="copies in x and y, e.g. 4x2")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="site PLY to write")
    args = parser.parse_args()
    try:
        nx, ny = (int(v) for v in args.copies.lower().split("x"))
    except ValueError:
        sys.exit(f"make_survey_site: --copies expects NxM, got {args.copies!r}")
    if nx < 1 or ny < 1:
        sys.exit("make_survey_site: --copies needs at least one copy each way")
    monument = station_points(args.monument).astype(np.float64)
    count = nx * ny * monument.shape[0]
    temporary = args.out.with_name(args.out.name + ".part")
    with open(temporary, "wb") as out:
        out.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {count}\n"
                  "property float x\nproperty float y\nproperty float z\nend_header\n".encode())
        for i in range(nx):
            for j in range(ny):
                (monument + np.array([i * PLAZA_X, j * PLAZA_Y, 0.0])).astype("<f4").tofile(out)
    temporary.replace(args.out)
    copies = nx * ny
    truth = {name: copies * value for name, value in PER_COPY.items()}
    truth["plane"] += 1  # the shared plaza
    site = {"copies": [nx, ny], "points": count, "stations": copies * len(list(args.monument.glob("scan_*.ply"))),
            "extent_m": [nx * PLAZA_X, ny * PLAZA_Y], "truth": truth}
    args.out.with_suffix(".truth.json").write_text(json.dumps(site, indent=1) + "\n")
    print(json.dumps(site))


if __name__ == "__main__":
    main()
