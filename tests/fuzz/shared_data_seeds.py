#!/usr/bin/env python3
"""Cuts small seeds out of the real files in ../shared/data, at fuzz time and into the build folder
(the data's licences keep it out of the repository): the first points of a KITTI, nuScenes, PLY,
PCD (ascii, binary, binary_compressed) and .npy cloud with their counts rewritten, the first labels
of a SemanticKITTI file, the first lines of text clouds and pose lists, and the pose and
calibration files as they are.

    python3 tests/fuzz/shared_data_seeds.py DATA_DIR OUT_DIR

writes OUT_DIR/<harness>/<file>; a file missing from DATA_DIR is skipped with a note.
"""

import pathlib
import re
import struct
import sys

sys.dont_write_bytecode = True  # no __pycache__ beside the sources
import lzf  # noqa: E402

POINTS = 200       # records kept from binary clouds and label files
TEXT_POINTS = 20   # records kept from PLY/PCD clouds and text files


def head_lines(data, count):
    """The first `count` lines of `data`."""
    return b"".join(data.splitlines(keepends=True)[:count])


def cut_raw_records(data, record_size):
    """The first POINTS fixed-size records of `data`."""
    return data[:POINTS * record_size]


PLY_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
             "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}


def cut_ply(data):
    """Header with `element vertex` set to TEXT_POINTS, then that many records (vertex-only files)."""
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("latin-1")
    body = data[end:]
    if "\nelement " in header.split("element vertex", 1)[1]:
        raise ValueError("elements besides 'vertex'")
    stride = sum(PLY_SIZES[m] for m in re.findall(r"^property (\w+) \w+$", header, re.M))
    header = re.sub(r"element vertex \d+", f"element vertex {TEXT_POINTS}", header)
    if "format ascii" in header:
        return header.encode("latin-1") + head_lines(body, TEXT_POINTS)
    return header.encode("latin-1") + body[:TEXT_POINTS * stride]


def pcd_header_fields(header):
    """A PCD header's lines as {key: [values]}."""
    values = {}
    for line in header.splitlines():
        parts = line.split()
        if parts and not parts[0].startswith("#"):
            values[parts[0]] = parts[1:]
    return values


def cut_pcd(data):
    """Header with WIDTH/HEIGHT/POINTS set to TEXT_POINTS x 1, then that many points in its encoding
    (binary_compressed: decompressed, cut per field and compressed again)."""
    start = data.index(b"\nDATA ") + 1
    end = data.index(b"\n", start) + 1
    header = data[:end].decode("latin-1")
    body = data[end:]
    fields = pcd_header_fields(header)
    sizes = [int(size) for size in fields["SIZE"]]
    counts = [int(count) for count in fields.get("COUNT", ["1"] * len(sizes))]
    points = int(fields["POINTS"][0]) if "POINTS" in fields else int(fields["WIDTH"][0]) * int(fields["HEIGHT"][0])
    keep = min(points, TEXT_POINTS)
    header = re.sub(r"^WIDTH \d+$", f"WIDTH {keep}", header, flags=re.M)
    header = re.sub(r"^HEIGHT \d+$", "HEIGHT 1", header, flags=re.M)
    header = re.sub(r"^POINTS \d+$", f"POINTS {keep}", header, flags=re.M)
    encoding = fields["DATA"][0]
    if encoding == "ascii":
        return header.encode("latin-1") + head_lines(body, keep)
    stride = sum(size * count for size, count in zip(sizes, counts))
    if encoding == "binary":
        return header.encode("latin-1") + body[:keep * stride]
    compressed_size, uncompressed_size = struct.unpack("<II", body[:8])
    field_major = lzf.decompress(body[8:8 + compressed_size], uncompressed_size)
    # Points from the middle: the first rows of an organised (camera) cloud are often all NaN.
    first = (points - keep) // 2
    kept, offset = b"", 0
    for size, count in zip(sizes, counts):
        width = size * count
        kept += field_major[offset + first * width:offset + (first + keep) * width]
        offset += points * width
    compressed = lzf.compress(kept)
    return header.encode("latin-1") + struct.pack("<II", len(compressed), len(kept)) + compressed


def cut_npy(data):
    """Header with the first dimension set to POINTS (C order), then those rows."""
    header_length = struct.unpack("<H", data[8:10])[0]
    header = data[10:10 + header_length].decode("latin-1")
    match = re.search(r"'shape': \((\d+), (\d+)\)", header)
    rows, columns = int(match.group(1)), int(match.group(2))
    item = int(re.search(r"'descr': '.f(\d)'", header).group(1))
    keep = min(rows, POINTS)
    new_header = header.replace(match.group(0), f"'shape': ({keep}, {columns})")
    new_header = new_header.rstrip("\n").ljust(len(header) - 1) + "\n"
    body = data[10 + header_length:]
    return data[:8] + struct.pack("<H", len(new_header)) + new_header.encode("latin-1") + body[:keep * columns * item]


def csv_from_xyz(data):
    """The first TEXT_POINTS lines of an XYZ file as CSV with an x,y,z header row."""
    lines = [line.split() for line in data.splitlines()[:TEXT_POINTS]]
    return b"x,y,z\n" + b"".join(b",".join(parts) + b"\n" for parts in lines if parts)


# harness -> [(output name, input relative to the data folder, cut)]
CUTS = {
    "binary_records": [
        ("kitti_000000_200.bin", "kitti00/velodyne/000000.bin", lambda d: cut_raw_records(d, 16)),
        ("nuscenes_200.bin",
         "single_scans/nuscenes_n008-2018-08-01-15-16-36-0400__LIDAR_TOP__1533151603597909.pcd.bin",
         lambda d: cut_raw_records(d, 20)),
        ("semantic_kitti_000052_200.label", "kitti00/labels/000052.label", lambda d: cut_raw_records(d, 4)),
    ],
    "ply_cloud": [
        ("hdl32_source_20.ply", "hdl32_pair/source.ply", cut_ply),
        ("kitti_004438_20.ply", "kitti00/velodyne/004438.ply", cut_ply),
        ("vlp16_source_20.ply", "quadricsreg_demo/vlp16_source.ply", cut_ply),
    ],
    "ply_mesh": [
        ("hdl32_source_20.ply", "hdl32_pair/source.ply", cut_ply),
        ("avia_source_20.ply", "quadricsreg_demo/avia_source.ply", cut_ply),
    ],
    "pcd": [
        ("lamppost_ascii_20.pcd", "single_scans/lamppost.pcd", cut_pcd),
        ("avia_binary_20.pcd", "quadricsreg_demo/cross_avia_vlp_source_1.pcd", cut_pcd),
        ("table_mug_binary_compressed_20.pcd", "single_scans/table_scene_mug_stereo_textured.pcd", cut_pcd),
    ],
    "text_cloud": [
        ("scan000_20.xyz", "3dtk/scan000_RH_m.xyz", lambda d: head_lines(d, TEXT_POINTS)),
        ("scan001_20.csv", "3dtk/scan001_RH_m.xyz", csv_from_xyz),
    ],
    "npy": [
        ("3dmatch_src_200.npy", "3dmatch_demo/src.npy", cut_npy),
        ("3dmatch_gt.npy", "3dmatch_demo/gt.npy", lambda d: d),
    ],
    "pose_matrix": [
        ("kitti_T_000001_from_000000.txt", "kitti00/gt/T_000001_from_000000.txt", lambda d: d),
        ("hdl32_T_target_source.txt", "hdl32_pair/T_target_source.txt", lambda d: d),
        ("3dtk_T_scan000_from_scan001.txt", "3dtk/T_scan000_from_scan001_RH_m.txt", lambda d: d),
        ("3dmatch_gt_ref_from_src.txt", "3dmatch_demo/gt_ref_from_src.txt", lambda d: d),
    ],
    "kitti_poses": [
        ("kitti_poses_00_20.txt", "kitti_poses/00.txt", lambda d: head_lines(d, TEXT_POINTS)),
    ],
    "kitti_calibration": [
        ("calib_Tr_velo_to_cam.txt", "kitti_poses/calib_Tr_velo_to_cam.txt", lambda d: d),
    ],
}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    data_dir, out_dir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    written = 0
    for harness, cuts in CUTS.items():
        folder = out_dir / harness
        folder.mkdir(parents=True, exist_ok=True)
        for name, relative, cut in cuts:
            source = data_dir / relative
            if not source.is_file():
                print(f"shared_data_seeds: {source} absent, skipped")
                continue
            try:
                (folder / name).write_bytes(cut(source.read_bytes()))
                written += 1
            except (ValueError, KeyError, AttributeError) as error:
                print(f"shared_data_seeds: cannot cut {source}: {error}")
    print(f"shared_data_seeds: {written} cut-outs of {data_dir} in {out_dir}")


if __name__ == "__main__":
    main()
