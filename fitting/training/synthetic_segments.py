"""Training segments of the learned fitter and its input normalisation.

Two sources: segments cut from simulated scans by the C++ simulator (`quadrix fitter-segments`,
experiments/synthetic/scan_segments.h; read by load_scan_segments), and the clean analytic samples
below (make_segments). Used only by train_learned_fitter.py (training needs numpy; inference is C++/Eigen, see
fitting/learned_fitter.cpp, which implements the same normalisation and decoding).

An analytic segment of one primitive type (paper §"Quadric Fitting": QuadricsNet is trained on fragmented,
noisy point clouds with the parameters of the complete surface as ground truth):
  * random size in metres, random pose (uniform rotation, translation up to tens of metres);
  * a visible fraction f in [0.1, 1] of the surface (a cap of a sphere/ellipsoid, an angular
    sector of a cylinder/cone/pole, a sub-rectangle of a plane);
  * isotropic Gaussian noise with a standard deviation drawn in [0, 5 cm];
  * exactly `num_points` points (the network's fixed N).

Normalisation (the network's input frame, identical in C++ `normalise_segment`):
  centre c = mean of the points; sigma = RMS distance to c (unit RMS radius);
  E = covariance eigenvectors in descending eigenvalue order; the first two columns are signed so
  that the third moment sum((u . e)^3) is >= 0 and e3 = e1 x e2 (det +1);
  u = E^T (x - c) / sigma.
Ground truth is expressed in the same frame (lengths divided by sigma, directions rotated by E^T).
"""

import numpy as np

# Types with a network, in manifest order; names are quadric_type_name() of geometry/quadric.h.
TYPES = ["plane", "line", "sphere", "circular_cylinder", "circular_cone", "ellipsoid"]

# Number of raw network outputs per type (decoded by decode_* below and in learned_fitter.cpp).
OUTPUT_SIZES = {
    "plane": 4,              # normal (3, normalised), signed offset d: plane n . u = d
    "line": 6,               # direction (3, normalised), a point (3) projected to the foot from the origin
    "sphere": 4,             # centre (3), log radius
    "circular_cylinder": 7,  # axis (3), axis point (3) projected to the foot, log radius
    "circular_cone": 7,      # axis (3), apex (3), log tan(half-angle)
    "ellipsoid": 12,         # rotation 6-D (two columns, Gram-Schmidt), log semi-axes (3), centre (3)
}

NOISE_MAX = 0.05          # metres: noise standard deviation drawn in [0, NOISE_MAX]
VISIBLE_MIN = 0.1         # smallest visible fraction of the surface


def random_rotations(rng, count):
    """Uniform random rotations (count, 3, 3) from normalised Gaussian quaternions."""
    q = rng.normal(size=(count, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1),
    ], axis=1)


def log_uniform(rng, low, high, size):
    """Log-uniform samples in [low, high]."""
    return np.exp(rng.uniform(np.log(low), np.log(high), size=size))


def cap_directions(rng, count, num_points, visible, axis=None):
    """Unit directions uniform on a spherical cap of area fraction `visible` around +z (or `axis`)."""
    z_min = 1.0 - 2.0 * visible[:, None]
    z = rng.uniform(0.0, 1.0, size=(count, num_points)) * (1.0 - z_min) + z_min
    phi = rng.uniform(0.0, 2.0 * np.pi, size=(count, num_points))
    rho = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    directions = np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=-1)
    if axis is not None:
        directions = np.einsum("bij,bnj->bni", axis, directions)
    return directions


def sample_canonical(rng, type_name, count, num_points, visible):
    """Points (count, N, 3) in each segment's canonical frame and the canonical scales (count, 3).

    Canonical conventions of geometry/quadric.h: plane normal = axis a (x); line/cylinder/cone
    axis = axis c (z); cone scale = (tan a, tan b, 1) with the apex at the origin.
    """
    shape = (count, num_points)
    phi0 = rng.uniform(0.0, 2.0 * np.pi, size=(count, 1))
    sector = phi0 + rng.uniform(0.0, 1.0, size=shape) * 2.0 * np.pi * visible[:, None]
    scale = np.ones((count, 3))
    if type_name == "plane":
        width = rng.uniform(1.0, 10.0, size=(count, 2)) * np.sqrt(visible)[:, None]
        y = (rng.uniform(size=shape) - 0.5) * width[:, :1]
        z = (rng.uniform(size=shape) - 0.5) * width[:, 1:]
        points = np.stack([np.zeros(shape), y, z], axis=-1)
    elif type_name == "line":
        # Poles: a thin tube of radius 0-15 cm around the axis, an angular sector of it visible.
        length = rng.uniform(1.0, 10.0, size=(count, 1))
        radius = rng.uniform(0.0, 0.15, size=(count, 1))
        z = (rng.uniform(size=shape) - 0.5) * length
        points = np.stack([radius * np.cos(sector), radius * np.sin(sector), z], axis=-1)
    elif type_name == "sphere":
        radius = log_uniform(rng, 0.3, 3.0, (count, 1))
        points = cap_directions(rng, count, num_points, visible) * radius[:, :, None]
        scale = np.repeat(radius, 3, axis=1)
    elif type_name == "ellipsoid":
        scale = log_uniform(rng, 0.3, 3.0, (count, 3))
        points = cap_directions(rng, count, num_points, visible, random_rotations(rng, count)) * scale[:, None, :]
    elif type_name == "circular_cylinder":
        radius = log_uniform(rng, 0.1, 2.0, (count, 1))
        length = log_uniform(rng, 1.0, 10.0, (count, 1))
        z = (rng.uniform(size=shape) - 0.5) * length
        points = np.stack([radius * np.cos(sector), radius * np.sin(sector), z], axis=-1)
        scale = np.concatenate([radius, radius, np.ones((count, 1))], axis=1)
    elif type_name == "circular_cone":
        tangent = rng.uniform(np.tan(np.radians(10.0)), np.tan(np.radians(50.0)), size=(count, 1))
        h0 = rng.uniform(0.1, 1.5, size=(count, 1))
        h1 = h0 + rng.uniform(0.5, 4.0, size=(count, 1))
        # Area density of a cone grows linearly with the height: h = sqrt(U(h0^2, h1^2)).
        h = np.sqrt(rng.uniform(size=shape) * (h1 ** 2 - h0 ** 2) + h0 ** 2)
        points = np.stack([h * tangent * np.cos(sector), h * tangent * np.sin(sector), h], axis=-1)
        scale = np.concatenate([tangent, tangent, np.ones((count, 1))], axis=1)
    else:
        raise ValueError("unknown type " + type_name)
    return points, scale


def normalise(points):
    """Network input frame of segments (count, N, 3): returns (u, centre, sigma, E)."""
    centre = points.mean(axis=1, keepdims=True)
    centred = points - centre
    sigma = np.sqrt((centred ** 2).sum(axis=2).mean(axis=1))
    sigma = np.where(sigma > 0.0, sigma, 1.0)
    scaled = centred / sigma[:, None, None]
    covariance = np.einsum("bni,bnj->bij", scaled, scaled) / points.shape[1]
    _, vectors = np.linalg.eigh(covariance)
    vectors = vectors[:, :, ::-1].copy()  # descending variance
    for column in range(2):
        projection = np.einsum("bni,bi->bn", scaled, vectors[:, :, column])
        sign = np.where((projection ** 3).sum(axis=1) >= 0.0, 1.0, -1.0)
        vectors[:, :, column] *= sign[:, None]
    vectors[:, :, 2] = np.cross(vectors[:, :, 0], vectors[:, :, 1])
    u = np.einsum("bni,bij->bnj", scaled, vectors)
    return u, centre[:, 0, :], sigma, vectors


def normalised_truth(type_name, world, rotation, translation, scale, visible, noise):
    """Normalised inputs and ground truth of segments given in world (or sensor) coordinates.

    world (count, N, 3): the N sampled points; rotation (count, 3, 3), translation (count, 3):
    canonical frame -> world; scale (count, 3): canonical scales (radii in metres, cone tangents).
    Returns (inputs float32 (count, N, 3), truth dict of float64 arrays in the normalised frame).
    """
    u, centre, sigma, frame = normalise(world)
    # Canonical pose in the normalised frame: R_n = E^T R, t_n = E^T (t - c) / sigma.
    rotation_n = np.einsum("bji,bjk->bik", frame, rotation)
    centre_n = np.einsum("bji,bj->bi", frame, translation - centre) / sigma[:, None]
    lengths = scale / sigma[:, None]
    truth = {"rotation": rotation_n, "centre": centre_n, "visible": visible, "noise": noise}
    if type_name == "plane":
        normal = rotation_n[:, :, 0]
        truth["direction"] = normal
        truth["foot"] = (normal * centre_n).sum(axis=1, keepdims=True) * normal
    elif type_name in ("line", "circular_cylinder", "circular_cone"):
        axis = rotation_n[:, :, 2]
        truth["direction"] = axis
        truth["foot"] = centre_n - (axis * centre_n).sum(axis=1, keepdims=True) * axis
        if type_name == "circular_cylinder":
            truth["log_scale"] = np.log(lengths[:, :1])
        if type_name == "circular_cone":
            truth["log_scale"] = np.log(scale[:, :1])  # tan(half-angle) has no unit
    elif type_name == "sphere":
        truth["log_scale"] = np.log(lengths[:, :1])
    elif type_name == "ellipsoid":
        truth["log_scale"] = np.log(lengths)
        # Shape matrix A = R diag(s) R^T: invariant to the order and signs of the axes.
        truth["shape_matrix"] = np.einsum("bij,bj,bkj->bik", rotation_n, lengths, rotation_n)
    return u.astype(np.float32), truth


def make_segments(rng, type_name, count, num_points, visible=None, noise=None):
    """Normalised analytic segments of one type and their ground truth in the normalised frame.

    Returns (inputs float32 (count, N, 3), truth dict of float64 arrays). `visible` and `noise`
    default to the training ranges; pass arrays to fix them (e.g. clean full surfaces).
    """
    if visible is None:
        visible = rng.uniform(VISIBLE_MIN, 1.0, size=count)
    if noise is None:
        noise = rng.uniform(0.0, NOISE_MAX, size=count)
    canonical, scale = sample_canonical(rng, type_name, count, num_points, visible)
    rotation = random_rotations(rng, count)
    translation = rng.normal(size=(count, 3)) * 20.0
    world = np.einsum("bij,bnj->bni", rotation, canonical) + translation[:, None, :]
    world += rng.normal(size=world.shape) * noise[:, None, None]
    return normalised_truth(type_name, world, rotation, translation, scale, visible, noise)


def strided_sample(count, num_points):
    """Column indices of the deterministic input sample (C++ learned_fitter_sample): point i of N is
    column floor(i * M / N) when M >= N, else i mod M."""
    index = np.arange(num_points)
    return (index * count) // num_points if count >= num_points else index % count


def load_scan_segments(directory, type_name, num_points):
    """Segments of one type written by `quadrix fitter-segments` (experiments/synthetic/scan_segments.h),
    sampled and normalised as the C++ fitter does. Returns (inputs, truth, extra) where extra holds
    per-segment visible fraction, noise, range, leaked points and crop flags; None when there are none."""
    import json
    import os
    with open(os.path.join(directory, "segments.json")) as stream:
        description = json.load(stream)
    table = np.load(os.path.join(directory, "segments.npy"))
    points = np.load(os.path.join(directory, "points.npy")).astype(np.float64)
    column = {name: index for index, name in enumerate(description["columns"])}
    if type_name not in description["types"]:
        return None
    rows = table[table[:, column["type"]] == description["types"][type_name]]
    if len(rows) == 0:
        return None
    world = np.stack([points[int(row[column["offset"]]) + strided_sample(int(row[column["count"]]), num_points)]
                      for row in rows])
    rotation = rows[:, column["r00"]:column["r22"] + 1].reshape(-1, 3, 3)
    translation = rows[:, column["tx"]:column["tz"] + 1]
    scale = rows[:, column["scale_0"]:column["scale_2"] + 1]
    inputs, truth = normalised_truth(type_name, world, rotation, translation, scale,
                                     rows[:, column["visible_fraction"]], rows[:, column["noise"]])
    extra = {name: rows[:, column[name]] for name in ("visible_fraction", "noise", "range", "leaked_points", "crop")}
    return inputs, truth, extra
