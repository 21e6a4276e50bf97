#!/usr/bin/env python3
"""Writes tests/fuzz/seeds/<harness>/: tiny valid and near-valid inputs of every format, made here
from scratch (no shared data), so libFuzzer starts from each format's structure.

Run it after changing a format; it rewrites the seed folders it owns and nothing else:
    python3 tests/fuzz/make_seeds.py
"""

import json
import math
import pathlib
import shutil
import struct
import sys

sys.dont_write_bytecode = True  # no __pycache__ beside the sources
import lzf  # noqa: E402

SEEDS = pathlib.Path(__file__).resolve().parent / "seeds"


def floats(*values, fmt="<f"):
    """Little-endian (or `fmt`) packed numbers."""
    return b"".join(struct.pack(fmt, value) for value in values)


# ----------------------------------------------------------------------------------------------
# KITTI .bin, nuScenes .pcd.bin and SemanticKITTI .label: raw little-endian records.

def binary_records():
    """Raw float32 records and uint32 labels."""
    nan = float("nan")
    return {
        "empty.bin": b"",
        "kitti_3_points.bin": floats(1.5, -2.0, 0.25, 0.3, 10.0, 20.0, -1.7, 0.9, nan, 1.0, 2.0, 0.0),
        "nuscenes_2_points.bin": floats(1.0, 2.0, 3.0, 0.5, 7.0, -4.0, 5.0, 6.0, 0.25, 12.0),
        "both_4_points.bin": floats(*[float(k) for k in range(20)]),
        "labels.bin": struct.pack("<4I", 0x00010028, 40, 0xFFFF0000, 9),
        "odd_size.bin": b"\x00\x00\x80\x3f\x00\x00\x00",
    }


# ----------------------------------------------------------------------------------------------
# PLY clouds and meshes.

def ply_header(encoding, elements):
    """A PLY header for `elements` = [(name, count, ["type name", ...])]."""
    lines = ["ply", f"format {encoding} 1.0", "comment quadrix fuzz seed"]
    for name, count, properties in elements:
        lines.append(f"element {name} {count}")
        lines.extend(f"property {p}" for p in properties)
    lines.append("end_header")
    return ("\n".join(lines) + "\n").encode()


def ply_clouds():
    """PLY point clouds: every encoding, every scalar type, elements before the vertices."""
    seeds = {}
    seeds["ascii_every_field.ply"] = ply_header("ascii", [
        ("camera", 1, ["float view_x", "list uchar int ids"]),
        ("vertex", 4, ["float x", "float y", "float z", "float intensity", "uint label", "uchar red",
                       "uchar green", "uchar blue", "double normal_x"]),
    ]).replace(b"end_header", b"obj_info made by make_seeds.py\nend_header") + (
        b"0.5 3 1 2 3\n"
        b"1 2 3 0.5 7 255 0 10 0.25\n"
        b"-1.5 0 2e3 1 0 0 128 255 -1\n"
        b"\n"
        b"nan 1 1 0 3 1 2 3 0\n"
        b"+4 5 6 0.125 4294967295 9 9 9 1e-300\n")
    le_types = ["char a", "uchar b", "short c", "ushort d", "int e", "uint f", "float x", "float y",
                "float z", "double scalar_intensity", "list uchar float extra"]
    record = struct.pack("<bBhHiIfffd", -3, 200, -300, 60000, -70000, 4000000000, 1.0, 2.0, 3.0, 0.5)
    seeds["binary_le_every_type.ply"] = ply_header("binary_little_endian", [("vertex", 2, le_types)]) + (
        record + b"\x02" + floats(0.5, 0.25) + record + b"\x00")
    seeds["binary_le_plain.ply"] = ply_header("binary_little_endian", [
        ("vertex", 3, ["float x", "float y", "float z"])]) + floats(1, 2, 3, 4, 5, 6, -7, 8e3, 9e-3)
    seeds["binary_be_double.ply"] = ply_header("binary_big_endian", [
        ("vertex", 2, ["float x", "float y", "float z", "float64 reflectance", "int8 ring"])]) + (
        struct.pack(">fffdb", 1, 2, 3, 0.75, 5) + struct.pack(">fffdb", -1, -2, -3, 0.5, 6))
    seeds["binary_le_face_first.ply"] = ply_header("binary_little_endian", [
        ("face", 1, ["list uchar int vertex_indices"]),
        ("vertex", 1, ["float x", "float y", "float z"])]) + b"\x03" + struct.pack("<3i", 0, 0, 0) + floats(1, 2, 3)
    seeds["binary_le_truncated.ply"] = ply_header("binary_little_endian", [
        ("vertex", 3, ["float x", "float y", "float z"])]) + floats(1, 2, 3, 4, 5)
    seeds["ascii_empty.ply"] = ply_header("ascii", [("vertex", 0, ["float x", "float y", "float z"])])
    return seeds


def ply_meshes():
    """PLY meshes: quads, triangles, unit-range colours, lists with uint lengths, an extra element."""
    seeds = {}
    corners = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    body = "".join(f"{x} {y} {z} {40 * i} {255 - 30 * i} 7\n" for i, (x, y, z) in enumerate(corners))
    body += "".join("4 " + " ".join(map(str, quad)) + "\n" for quad in quads)
    seeds["ascii_cube.ply"] = ply_header("ascii", [
        ("vertex", 8, ["float x", "float y", "float z", "uchar red", "uchar green", "uchar blue"]),
        ("face", 6, ["list uchar int vertex_indices"])]) + body.encode()
    seeds["binary_le_triangle.ply"] = ply_header("binary_little_endian", [
        ("vertex", 3, ["double x", "double y", "double z"]),
        ("face", 1, ["list uchar int vertex_indices"])]) + (
        struct.pack("<9d", 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\x03" + struct.pack("<3i", 0, 1, 2))
    seeds["binary_be_unit_colours.ply"] = ply_header("binary_big_endian", [
        ("vertex", 4, ["float x", "float y", "float z", "float red", "float green", "float blue"]),
        ("face", 2, ["uchar flags", "list uint int vertex_index"]),
        ("edge", 1, ["int vertex1", "int vertex2"])]) + (
        floats(0, 0, 0, 1, 0, 0, fmt=">f") + floats(1, 0, 0, 0, 1, 0, fmt=">f") +
        floats(1, 1, 0, 0, 0, 1, fmt=">f") + floats(0, 1, 0, 0.5, 0.5, 0.5, fmt=">f") +
        b"\x01" + struct.pack(">I3i", 3, 0, 1, 2) + b"\x00" + struct.pack(">I4i", 4, 0, 1, 2, 3) +
        struct.pack(">2i", 0, 1))
    seeds["ascii_bad_index.ply"] = ply_header("ascii", [
        ("vertex", 3, ["float x", "float y", "float z"]),
        ("face", 1, ["list ushort uint vertex_indices"])]) + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"
    return seeds


# ----------------------------------------------------------------------------------------------
# PCD: ascii, binary, binary_compressed.

def pcd_header(fields, sizes, types, counts, width, height=1, data="ascii", points=True, count_line=True):
    """A PCD v0.7 header; `points`/`count_line` False leave out POINTS/COUNT."""
    lines = ["# .PCD v0.7 - quadrix fuzz seed", "VERSION 0.7", "FIELDS " + " ".join(fields),
             "SIZE " + " ".join(map(str, sizes)), "TYPE " + " ".join(types)]
    if count_line:
        lines.append("COUNT " + " ".join(map(str, counts)))
    lines += [f"WIDTH {width}", f"HEIGHT {height}", "VIEWPOINT 0 0 0 1 0 0 0"]
    if points:
        lines.append(f"POINTS {width * height}")
    lines.append(f"DATA {data}")
    return ("\n".join(lines) + "\n").encode()


def packed_rgb_float(red, green, blue):
    """A 0x00RRGGBB colour stored in a float, as PCL writes rgb."""
    return struct.unpack("<f", struct.pack("<I", (red << 16) | (green << 8) | blue))[0]


def pcds():
    """PCD clouds: every DATA encoding, packed colours, padding and COUNT > 1 fields."""
    seeds = {}
    rgb = [packed_rgb_float(255, 0, 10), packed_rgb_float(1, 2, 3), packed_rgb_float(0, 128, 255)]
    seeds["ascii_rgb.pcd"] = pcd_header(["x", "y", "z", "intensity", "rgb"], [4] * 5, ["F"] * 5, [1] * 5, 3) + (
        f"1 2 3 0.5 {rgb[0]!r}\n-4 5.5 6e2 0.25 {rgb[1]!r}\n\nnan 0 0 1 {rgb[2]!r}\n".encode())
    fields = ["x", "y", "z", "label", "rgba", "_", "normal"]
    sizes = [4, 4, 4, 4, 4, 1, 4]
    types = ["F", "F", "F", "U", "U", "U", "F"]
    counts = [1, 1, 1, 1, 1, 2, 3]
    body = b""
    for k in range(2):
        body += floats(1.0 + k, 2.0, -3.0) + struct.pack("<II", 7 + k, 0xFF102030) + b"\x00\x00" + floats(0, 0, 1)
    seeds["binary_label_rgba_padding.pcd"] = pcd_header(fields, sizes, types, counts, 2, data="binary") + body
    typed = pcd_header(["x", "y", "z", "a", "b", "c", "d"], [8, 8, 8, 1, 2, 8, 8],
                       ["F", "F", "F", "I", "U", "I", "U"], [1] * 7, 2, data="binary")
    seeds["binary_every_type.pcd"] = typed + (
        struct.pack("<dddbHqQ", 1, 2, 3, -1, 65535, -2**40, 2**63) + struct.pack("<dddbHqQ", 4, 5, 6, 1, 0, 5, 6))
    xyzi = [floats(0.0, 1.0, 2.0, 3.0), floats(1.0, 1.0, 1.0, 1.0), floats(-5.0, -5.0, -5.0, -5.0),
            floats(0.5, 0.5, 0.25, 0.5)]
    field_major = b"".join(xyzi)
    compressed = lzf.compress(field_major)
    assert lzf.decompress(compressed, len(field_major)) == field_major
    seeds["binary_compressed.pcd"] = pcd_header(["x", "y", "z", "intensity"], [4] * 4, ["F"] * 4, [1] * 4, 4,
                                                data="binary_compressed") + (
        struct.pack("<II", len(compressed), len(field_major)) + compressed)
    long_field_major = floats(*([1.5] * 40 + [2.5] * 40 + [float(k) for k in range(40)]))
    long_compressed = lzf.compress(long_field_major)
    seeds["binary_compressed_long_runs.pcd"] = pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 20, 2,
                                                          data="binary_compressed") + (
        struct.pack("<II", len(long_compressed), len(long_field_major)) + long_compressed)
    seeds["ascii_organized_no_points.pcd"] = pcd_header(
        ["x", "y", "z"], [4, 4, 4], ["F", "F", "F"], [], 2, 2, points=False, count_line=False) + (
        b"1 2 3\n4 5 6\n7 8 9\n1e39 0 0\n")
    seeds["ascii_columns_count.pcd"] = (
        b"COLUMNS x y z histogram\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 3\nWIDTH 1\nPOINTS 1\nDATA ascii\n"
        b"1 2 3 0.1 0.2 0.7\n")
    seeds["binary_truncated.pcd"] = pcd_header(["x", "y", "z"], [4, 4, 4], ["F"] * 3, [1] * 3, 2,
                                               data="binary") + floats(1, 2, 3, 4)
    return seeds


# ----------------------------------------------------------------------------------------------
# XYZ and CSV text (both readers get every seed).

def text_clouds():
    """XYZ and CSV texts: comments, CRLF, headers, quotes, non-finite numbers."""
    return {
        "xyz_comments.xyz": b"# x y z\n1 2 3\n4.5 -6 7e2 # trailing comment\n\n",
        "xyz_intensity_crlf.xyz": b"1 2 3 0.5\r\n4\t5\t6\t0.25\r\n",
        "xyz_colours.xyz": b"1 2 3 255 0 10\n-1 -2 -3 0 128 255\n",
        "xyz_seven_columns.xyz": b"1 2 3 4 5 6 7\n",
        "xyz_non_finite.xyz": b"1 2 3\nnan 1 1\n1 inf 2\n1e400 0 0\n+1 -0 1e-400\n",
        "csv_header.csv": b"x,y,z,intensity,label\n1,2,3,0.5,7\n4,5,6,0.25,8\n",
        "csv_quoted_header.csv": b"\"X\",\"Y\",\"Z\",'red','green','blue'\n1,2,3,0.1,0.2,0.3\n",
        "csv_headerless.csv": b"1,2,3\n4,5,6\n\n7,8,9\n",
        "csv_spaces_comment.csv": b"# exported\n x , y , z \n 1 , 2 , 3 \n",
        "empty.txt": b"",
    }


# ----------------------------------------------------------------------------------------------
# NumPy .npy (clouds and poses).

def npy(descr, shape, payload, fortran=False, version=1, shape_text=None):
    """A .npy file of format `version` with the given dtype, shape and payload."""
    shape_text = shape_text or ("(" + ", ".join(map(str, shape)) + ("," if len(shape) == 1 else "") + ")")
    header = f"{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape_text}, }}"
    prefix = 10 if version == 1 else 12
    padding = (-(prefix + len(header) + 1)) % 64
    header = (header + " " * padding + "\n").encode()
    size = struct.pack("<H", len(header)) if version == 1 else struct.pack("<I", len(header))
    return b"\x93NUMPY" + bytes([version, 0]) + size + header + payload


def rotation_z(angle):
    """A 3x4 row-major pose rotating `angle` radians about z."""
    c, s = math.cos(angle), math.sin(angle)
    return [c, -s, 0.0, 0.5, s, c, 0.0, -1.25, 0.0, 0.0, 1.0, 2.0]


def npys():
    """.npy arrays: every dtype and byte order, Fortran order, versions 1-3, poses, empty and 1-D."""
    pose = rotation_z(0.3)
    return {
        "f4_c_3x3.npy": npy("<f4", (3, 3), floats(*range(9))),
        "f8_fortran_2x4.npy": npy("<f8", (2, 4), floats(1, 5, 2, 6, 3, 7, 4, 8, fmt="<d"), fortran=True),
        "f4_big_endian_2x3.npy": npy(">f4", (2, 3), floats(1, 2, 3, 4, 5, 6, fmt=">f")),
        "f8_v2_1x3.npy": npy("<f8", (1, 3), floats(1, 2, 3, fmt="<d"), version=2),
        "f4_v3_2x6.npy": npy("<f4", (2, 6), floats(*range(12)), version=3),
        "pose_f8_4x4.npy": npy("<f8", (4, 4), floats(*pose, 0, 0, 0, 1, fmt="<d")),
        "pose_f4_3x4.npy": npy("<f4", (3, 4), floats(*pose)),
        "one_dimensional.npy": npy("<f8", (3,), floats(1, 2, 3, fmt="<d")),
        "empty_0x3.npy": npy("<f4", (0, 3), b""),
        "python2_long_shape.npy": npy("<f4", None, floats(*range(6)), shape_text="(2L, 3L)"),
    }


# ----------------------------------------------------------------------------------------------
# Poses and calibration.

def numbers(values):
    """Numbers as space-separated text."""
    return " ".join(repr(round(v, 9)) for v in values)


def pose_matrices():
    """4x4 and 3x4 pose texts: comments, commas, signs and exponents."""
    pose = rotation_z(0.5235987755982988)
    return {
        "identity_4x4.txt": b"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",
        "rotation_3x4_comments.txt": ("# T_target_source\n" + "\n".join(
            numbers(pose[4 * r:4 * r + 4]) + f"  # row {r}" for r in range(3)) + "\n").encode(),
        "commas_one_line.txt": (",".join(repr(v) for v in pose + [0.0, 0.0, 0.0, 1.0]) + "\n").encode(),
        "signs_exponents.txt": b"+1.0e0 -0.0 0 1e-3\n0 1 0 -2E+1\n0 0 1.0 0\r\n0 0 0 1",
    }


def kitti_poses():
    """KITTI pose lists."""
    lines = ["# frame poses"] + [numbers(rotation_z(0.01 * k)[:3] + [float(k)] + rotation_z(0.01 * k)[4:])
                                 for k in range(3)]
    return {
        "three_poses.txt": ("\n".join(lines[:2]) + "\n\n" + "\n".join(lines[2:]) + "\n").encode(),
        "identity.txt": b"1 0 0 0 0 1 0 0 0 0 1 0\n",
        "empty.txt": b"",
    }


def kitti_calibrations():
    """KITTI calibration files: Tr:, Tr_velo_to_cam: and per-sequence lines."""
    tr = [0.0, -1.0, 0.0, -0.01, 0.0, 0.0, -1.0, -0.05, 1.0, 0.0, 0.0, -0.27]
    projection = [718.856, 0.0, 607.1928, 0.0, 0.0, 718.856, 185.2157, 0.0, 0.0, 0.0, 1.0, 0.0]
    calib = "".join(f"P{k}: {numbers(projection)}\n" for k in range(4)) + f"Tr: {numbers(tr)}\n"
    return {
        "calib.txt": calib.encode(),
        "tr_velo_to_cam.txt": f"calib_time: 09-Jan-2012\nTr_velo_to_cam: {numbers(tr)}\n".encode(),
        "per_sequence.txt": (f"# velodyne to camera\nseq00-02 {numbers(tr)}\nseq03 {numbers(tr)}\n"
                             f"seq04-12 {numbers(tr)}\n").encode(),
    }


# ----------------------------------------------------------------------------------------------
# Registration configuration (YAML).

def registration_configs():
    """YAML configurations: every section, flow style, anchors, empty, an unknown key."""
    return {
        "every_section.yaml": (
            b"sensor: vlp16\n"
            b"extraction:\n  minimum_range: 1.5\n  up: [0, 0, 1]\n  static_scan: false\n"
            b"  planes:\n    voxel_size: 1.5\n    minimum_plane_points: 30\n"
            b"  trunks:\n    enabled: false\n  clusters:\n    radius: 0.5\n"
            b"modelling:\n  fitter: taubin\n  quadrics_per_class: 40\n"
            b"matching:\n  thresholds: [0.2, 0.4, 0.6]\n  top_k_similar: 3\n  match_augmented_points: true\n"
            b"estimation:\n  refiner: nlopt\n  max_iterations: 50\n  function_tolerance: 1.0e-8\n"
            b"selection:\n  dcs_phi: 1.0\n"
            b"ambiguity:\n  score_ratio: 0.9\n"
            b"dense_search:\n  enabled: true\n  voxel_size: 0.2\n  source_samples: 2000\n"),
        "flow_style.yaml": b"{sensor: mid360, matching: {thresholds: [0.5]}, extraction: {up: [0, 1, 1]}}\n",
        "anchor_alias.yaml": b"extraction:\n  planes: &planes\n    voxel_size: 2.0\n# comment\n",
        "empty.yaml": b"",
        "unknown_key.yaml": b"extraction:\n  planes:\n    voxle_size: 1\n",
    }


# ----------------------------------------------------------------------------------------------
# Scene models: the JSON of scene_model_to_json and the binary format (kSceneModelBinaryVersion).

def fnv1a(data):
    """FNV-1a of `data`, the checksum of the binary model format."""
    value = 2166136261
    for byte in data:
        value = ((value ^ byte) * 16777619) & 0xFFFFFFFF
    return value


def sample_model():
    """A three-record model (ground plane, line, one augmented point) with a descriptor and timings."""
    plane = [1.0] + [0.0] * 9 + [0.0] + [1.0, 0.0, 0.0] + [1.0, 0.0, 0.0, 0.0] + [0.0, 0.0, -1.7]
    plane[1] = 1.0  # q.A
    line = [3.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0,
            math.cos(0.2), 0.0, 0.0, math.sin(0.2), 5.0, 2.0, 0.0]
    point = [4.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0,
             1.0, 0.0, 0.0, 0.0, -3.0, 4.0, 0.5]
    return {
        "records": [(plane, "plane", 2, 1200), (line, "line", 1, 85), (point, "point", 0, 12)],
        "augmented_begin": 2,
        "descriptors": [[float(k % 5) for k in range(33)]],
        "ground": (True, [0.0, 0.0, 1.0], 1.7),
        "source_points": 4000,
        "timings": {"extraction": 12.5, "fitting": 3.25},
    }


def model_json(model):
    """`model` as scene_model_to_json writes it (plus an extra stats member)."""
    quadrics = []
    for index, (record, type_name, _, points) in enumerate(model["records"]):
        quadrics.append({"index": index, "label": int(record[0]), "type": type_name, "points": points,
                         "augmented": index >= model["augmented_begin"], "q": record[1:11],
                         "scale": record[11:14], "rotation": record[14:18], "center": record[18:21],
                         "record": record})
    found, normal, offset = model["ground"]
    document = {
        "format": "quadrix-scene-model", "version": 1, "quadrics": quadrics,
        "ground": {"found": found, "normal": normal, "offset": offset},
        "augmented_begin": model["augmented_begin"], "augmented_descriptors": model["descriptors"],
        "stats": {"source_points": model["source_points"], "records": len(quadrics),
                  "augmented_points": len(quadrics) - model["augmented_begin"],
                  "counts_by_class": {}, "counts_by_type": {}, "timings_ms": model["timings"],
                  "binary_bytes": 0, "note": "extra \u00e9 \\u00e9 \"quoted\""},
    }
    return json.dumps(document, indent=2).encode()


def model_binary(model):
    """`model` in the binary format, checksum included."""
    found, normal, offset = model["ground"]
    out = b"QDXSCENE" + struct.pack("<IQQQB", 1, len(model["records"]), model["augmented_begin"],
                                    model["source_points"], 1 if found else 0)
    out += floats(*normal, offset, fmt="<d")
    for record, _, type_code, points in model["records"]:
        out += floats(*record, fmt="<d") + struct.pack("<BI", type_code, points)
    out += struct.pack("<Q", len(model["descriptors"]))
    for descriptor in model["descriptors"]:
        out += floats(*descriptor)
    out += struct.pack("<I", len(model["timings"]))
    for name, value in sorted(model["timings"].items()):
        out += struct.pack("<I", len(name)) + name.encode() + struct.pack("<d", value)
    return out + struct.pack("<I", fnv1a(out))


def empty_model():
    """A model without records."""
    return {"records": [], "augmented_begin": 0, "descriptors": [], "ground": (False, [0.0, 0.0, 1.0], 0.0),
            "source_points": 0, "timings": {}}


def scene_model_jsons():
    """Model JSON documents."""
    return {
        "three_records.json": model_json(sample_model()),
        "empty_model.json": model_json(empty_model()),
        "nested.json": b'{"format": "quadrix-scene-model", "version": 1, "quadrics": [[[{"a": null}]]], "x": [true, false]}',
    }


def scene_model_binaries():
    """Binary models, one with a wrong checksum."""
    good = model_binary(sample_model())
    return {
        "three_records.qsm": good,
        "empty_model.qsm": model_binary(empty_model()),
        "bad_checksum.qsm": good[:-1] + bytes([good[-1] ^ 0xFF]),
    }


# ----------------------------------------------------------------------------------------------
# LAS 1.0-1.4: public header, variable-length records, point records of formats 0-10.

LAS_BASE_SIZES = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]
LAS_RGB_OFFSETS = [0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30]


def las_file(minor, point_format, points, extra_bytes=0, vlr=b"", scale=(0.01, 0.01, 0.01), offset=(0.0, 0.0, 0.0),
             projection=()):
    """A LAS file of integer points [(X, Y, Z, intensity, class)] with a correct header; `vlr` is the
    payload of one WKT record, `projection` further LASF_Projection records [(record id, payload)]."""
    header_size = 227 if minor <= 2 else 235 if minor == 3 else 375
    record = LAS_BASE_SIZES[point_format] + extra_bytes
    records = ([(2112, vlr)] if vlr else []) + list(projection)
    vlrs = b"".join(struct.pack("<H16sHH32s", 0, b"LASF_Projection", record_id, len(payload), b"fuzz seed") + payload
                    for record_id, payload in records)
    offset_to_points = header_size + len(vlrs)
    coordinates = [[p[axis] * scale[axis] + offset[axis] for p in points] for axis in range(3)]
    low = [min(c) if c else 0.0 for c in coordinates]
    high = [max(c) if c else 0.0 for c in coordinates]
    legacy = len(points) if point_format < 6 or minor < 4 else 0
    header = bytearray(header_size)
    header[0:4] = b"LASF"
    header[24] = 1
    header[25] = minor
    header[26:38] = b"quadrix fuzz"
    struct.pack_into("<HIIBHI", header, 94, header_size, offset_to_points, len(records), point_format, record, legacy)
    struct.pack_into("<3d", header, 131, *scale)
    struct.pack_into("<3d", header, 155, *offset)
    struct.pack_into("<6d", header, 179, high[0], low[0], high[1], low[1], high[2], low[2])
    if minor >= 4:
        struct.pack_into("<Q", header, 247, len(points))
    body = bytearray()
    for X, Y, Z, intensity, cls in points:
        data = bytearray(record)
        struct.pack_into("<iiiH", data, 0, X, Y, Z, intensity)
        if point_format < 6:
            data[14] = 0x09  # return 1 of 1
            data[15] = cls & 31
        else:
            data[14] = 0x11
            data[16] = cls
        if LAS_RGB_OFFSETS[point_format]:
            struct.pack_into("<3H", data, LAS_RGB_OFFSETS[point_format], 65535, 32768, 256)
        body += data
    return bytes(header) + vlrs + bytes(body)


def las_files():
    """Every point format, versions 1.2-1.4, extra bytes, a VLR, and damaged headers."""
    points = [(100, -200, 300, 7, 2), (-5000, 12000, 0, 65535, 1), (0, 0, -70, 0, 6)]
    seeds = {}
    for point_format in range(11):
        minor = 4 if point_format >= 6 else 2 + point_format % 2
        seeds[f"format_{point_format}_1_{minor}.las"] = las_file(minor, point_format, points,
                                                                  extra_bytes=point_format % 3,
                                                                  vlr=b"\x01\x02" if point_format % 2 else b"")
    utm = las_file(4, 6, points, scale=(0.001, 0.001, 0.001), offset=(500000.0, 5400000.0, 100.0))
    seeds["utm_1_4.las"] = utm
    # Coordinate units: GeoTIFF keys (projected, international foot, vertical metre, a user-defined
    # unit size among the double parameters) and a compound WKT with a projected and a vertical unit.
    keys = struct.pack("<24H", 1, 1, 0, 5, 1024, 0, 1, 1, 3076, 0, 1, 9002, 3077, 34736, 1, 0, 4099, 0, 1, 9001,
                       2052, 0, 1, 9003)
    seeds["geokeys_feet_1_2.las"] = las_file(2, 1, points, projection=[(34735, keys), (34736, struct.pack("<2d", 0.3048, 1.0))])
    wkt = (b'COMPD_CS["c",PROJCS["p",GEOGCS["g",UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],'
           b'UNIT["metre",1]],VERT_CS["v",VERT_DATUM["d",2005],UNIT["US survey foot",0.304800609601219]]]\x00')
    seeds["wkt_compound_1_4.las"] = las_file(4, 6, points, vlr=wkt)
    seeds["empty_1_3.las"] = las_file(3, 1, [])
    seeds["truncated_points.las"] = las_file(2, 1, points)[:-9]
    lying = bytearray(las_file(4, 7, points))
    struct.pack_into("<Q", lying, 247, 4)
    seeds["count_lies.las"] = bytes(lying)
    laz = bytearray(las_file(2, 3, points))
    laz[104] = 0x83
    seeds["laz_bits.las"] = bytes(laz)
    return seeds


HARNESSES = {
    "binary_records": binary_records,
    "ply_cloud": ply_clouds,
    "ply_mesh": ply_meshes,
    "pcd": pcds,
    "text_cloud": text_clouds,
    "npy": npys,
    "las": las_files,
    "pose_matrix": pose_matrices,
    "kitti_poses": kitti_poses,
    "kitti_calibration": kitti_calibrations,
    "registration_config": registration_configs,
    "scene_model_json": scene_model_jsons,
    "scene_model_binary": scene_model_binaries,
}


def main():
    """Rewrites every seeds/<harness>/ folder."""
    for harness, make in HARNESSES.items():
        folder = SEEDS / harness
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        for name, content in make().items():
            (folder / name).write_bytes(content)
        print(f"{folder}: {len(list(folder.iterdir()))} seeds")


if __name__ == "__main__":
    main()
