#!/usr/bin/python3
"""Trains the learned quadric fitter (one small PointNet per primitive type, in the spirit of
QuadricsNet, paper §"Quadric Fitting") on synthetic segments and exports it for the C++/Eigen
inference of fitting/learned_fitter.cpp.

Run through `make train-fitter` (which installs Debian's python3-torch/python3-numpy if missing).
Training only: nothing here runs at build or test time.

Network (per type): shared per-point MLP 3 -> 32 -> 64 -> 128 (ReLU), max-pool over the N points,
head 128 -> 128 -> 64 -> outputs (ReLU, last layer linear). No batch-norm, so nothing to fold.
Outputs are decoded in the normalised frame (synthetic_segments.OUTPUT_SIZES) and combined into
Q = P^-T C P^-1 (paper Eq. (Q=PCP)) in C++ after undoing the normalisation.

Losses on the geometry, invariant to the sign of axes and to the order of ellipsoid axes:
  axis/normal   1 - (u . u_gt)^2
  foot / centre smooth-L1 of the point (line/plane/cylinder: foot of the perpendicular from the
                segment centroid, sphere/ellipsoid: centre, cone: apex), normalised units
  scale         |log s - log s_gt| (radius, tan of the cone half-angle)
  ellipsoid     smooth-L1 of A = R diag(s) R^T against the true shape matrix, plus the centre.

Export (fitting/models/learned_fitter/): one .npy per tensor (float32, little endian, C order,
weights (out, in), biases (out,)), manifest.json (layers, shapes, activations, normalisation, N,
types, training record, held-out accuracy), and golden inputs/outputs for the C++ golden test.
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import synthetic_segments as synthetic  # noqa: E402

SHARED_WIDTHS = (32, 64, 128)
HEAD_WIDTHS = (128, 64)
LOG_CLAMP = 10.0  # decoded log-scales are clamped to [-LOG_CLAMP, LOG_CLAMP] (same in C++)


class PointNetRegressor(torch.nn.Module):
    """Shared per-point MLP, max-pool, MLP head (PointNet without transform nets)."""

    def __init__(self, output_size):
        super().__init__()
        widths = (3,) + SHARED_WIDTHS
        self.shared = torch.nn.ModuleList(torch.nn.Linear(a, b) for a, b in zip(widths[:-1], widths[1:]))
        widths = (SHARED_WIDTHS[-1],) + HEAD_WIDTHS + (output_size,)
        self.head = torch.nn.ModuleList(torch.nn.Linear(a, b) for a, b in zip(widths[:-1], widths[1:]))

    def forward(self, points):
        hidden = points
        for layer in self.shared:
            hidden = torch.relu(layer(hidden))
        hidden = hidden.max(dim=1).values
        for index, layer in enumerate(self.head):
            hidden = layer(hidden)
            if index + 1 < len(self.head):
                hidden = torch.relu(hidden)
        return hidden


def normalised(vectors):
    return vectors / vectors.norm(dim=-1, keepdim=True).clamp_min(1e-12)


def foot_point(point, direction):
    """Foot of the perpendicular from the origin on the line through `point` along `direction`."""
    return point - (point * direction).sum(-1, keepdim=True) * direction


def rotation_from_6d(six):
    """Gram-Schmidt of two predicted columns (Zhou et al. 2019); columns a, b, c = a x b."""
    a = normalised(six[:, 0:3])
    b = normalised(six[:, 3:6] - (a * six[:, 3:6]).sum(-1, keepdim=True) * a)
    return torch.stack([a, b, torch.cross(a, b, dim=-1)], dim=-1)


def decode(type_name, raw):
    """Decoded parameters (normalised frame) of raw outputs; mirrors decode_* in learned_fitter.cpp."""
    out = {}
    if type_name == "plane":
        out["direction"] = normalised(raw[:, 0:3])
        out["foot"] = raw[:, 3:4] * out["direction"]
    elif type_name in ("line", "circular_cylinder", "circular_cone"):
        out["direction"] = normalised(raw[:, 0:3])
        if type_name == "circular_cone":
            out["centre"] = raw[:, 3:6]
        else:
            out["foot"] = foot_point(raw[:, 3:6], out["direction"])
        if type_name != "line":
            out["log_scale"] = raw[:, 6:7].clamp(-LOG_CLAMP, LOG_CLAMP)
    elif type_name == "sphere":
        out["centre"] = raw[:, 0:3]
        out["log_scale"] = raw[:, 3:4].clamp(-LOG_CLAMP, LOG_CLAMP)
    elif type_name == "ellipsoid":
        rotation = rotation_from_6d(raw[:, 0:6])
        out["rotation"] = rotation
        out["log_scale"] = raw[:, 6:9].clamp(-LOG_CLAMP, LOG_CLAMP)
        out["centre"] = raw[:, 9:12]
        lengths = out["log_scale"].exp()
        out["shape_matrix"] = torch.einsum("bij,bj,bkj->bik", rotation, lengths, rotation)
    return out


def loss_terms(type_name, predicted, truth):
    """Per-term mean losses (dict) of decoded predictions against truth tensors."""
    smooth = torch.nn.functional.smooth_l1_loss
    terms = {}
    if "direction" in predicted:
        terms["axis"] = 2.0 * (1.0 - (predicted["direction"] * truth["direction"]).sum(-1) ** 2).mean()
    if "foot" in predicted:
        terms["foot"] = smooth(predicted["foot"], truth["foot"], beta=0.05)
    if type_name in ("sphere", "ellipsoid", "circular_cone"):
        terms["centre"] = smooth(predicted["centre"], truth["centre"], beta=0.05)
    if type_name == "ellipsoid":
        terms["shape"] = smooth(predicted["shape_matrix"], truth["shape_matrix"], beta=0.05)
    elif "log_scale" in predicted:
        terms["scale"] = (predicted["log_scale"] - truth["log_scale"]).abs().mean()
    return terms


def to_tensors(truth):
    return {key: torch.from_numpy(np.ascontiguousarray(value)).float() for key, value in truth.items()}


def accuracy(type_name, predicted, truth):
    """Held-out errors per segment (numpy): axis error in degrees, relative scale error, and
    centre/foot error in units of the segment's RMS radius (the normalised frame's unit)."""
    errors = {}
    if "direction" in predicted:
        cosine = np.abs((predicted["direction"] * truth["direction"]).sum(-1)).clip(0.0, 1.0)
        errors["axis_deg"] = np.degrees(np.arccos(cosine))
    if "foot" in predicted:
        errors["foot"] = np.linalg.norm(predicted["foot"] - truth["foot"], axis=-1)
    if "centre" in predicted:
        errors["centre"] = np.linalg.norm(predicted["centre"] - truth["centre"], axis=-1)
    if type_name == "ellipsoid":
        difference = np.linalg.norm(predicted["shape_matrix"] - truth["shape_matrix"], axis=(1, 2))
        errors["shape_rel"] = difference / np.linalg.norm(truth["shape_matrix"], axis=(1, 2))
        sorted_predicted = np.sort(np.exp(predicted["log_scale"]), axis=1)
        sorted_truth = np.sort(np.exp(truth["log_scale"]), axis=1)
        errors["scale_rel_max"] = np.abs(sorted_predicted / sorted_truth - 1.0).max(axis=1)
    elif "log_scale" in predicted:
        errors["scale_rel"] = np.abs(np.exp(predicted["log_scale"][:, 0] - truth["log_scale"][:, 0]) - 1.0)
    return {name: {"median": float(np.median(value)), "p90": float(np.percentile(value, 90)),
                   "mean": float(np.mean(value))} for name, value in errors.items()}


def evaluate(type_name, model, inputs, truth):
    model.eval()
    with torch.no_grad():
        raw = model(torch.from_numpy(inputs))
        predicted = {key: value.numpy().astype(np.float64) for key, value in decode(type_name, raw).items()}
    model.train()
    return accuracy(type_name, predicted, truth)


def train_type(type_name, args, seed):
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    generation_start = time.time()
    inputs, truth = synthetic.make_segments(rng, type_name, args.segments, args.num_points)
    held_inputs, held_truth = synthetic.make_segments(rng, type_name, args.held_out, args.num_points)
    clean_inputs, clean_truth = synthetic.make_segments(rng, type_name, args.held_out, args.num_points,
                                                        visible=np.ones(args.held_out), noise=np.zeros(args.held_out))
    generation_seconds = time.time() - generation_start
    model = PointNetRegressor(synthetic.OUTPUT_SIZES[type_name])
    optimiser = torch.optim.Adam(model.parameters(), lr=args.learning_rate)
    steps = args.epochs * (args.segments // args.batch)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, T_max=steps, eta_min=args.learning_rate * 0.01)
    all_inputs = torch.from_numpy(inputs)
    all_truth = to_tensors(truth)
    start = time.time()
    cpu_start = time.process_time()
    step = 0
    for epoch in range(args.epochs):
        order = torch.randperm(args.segments)
        for first in range(0, args.segments - args.batch + 1, args.batch):
            index = order[first:first + args.batch]
            predicted = decode(type_name, model(all_inputs[index]))
            terms = loss_terms(type_name, predicted, {key: value[index] for key, value in all_truth.items()})
            loss = sum(terms.values())
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            schedule.step()
            step += 1
            if step % 100 == 0:
                print("  %s epoch %d step %d/%d loss %.4f (%s)" % (
                    type_name, epoch, step, steps, loss.item(),
                    ", ".join("%s %.4f" % (k, v.item()) for k, v in terms.items())), flush=True)
    seconds = time.time() - start
    record = {
        "training_seconds": round(seconds, 1),
        "training_cpu_seconds": round(time.process_time() - cpu_start, 1),
        "generation_seconds": round(generation_seconds, 1),
        "seed": seed,
        "held_out_partial_noisy": evaluate(type_name, model, held_inputs, held_truth),
        "held_out_clean_full": evaluate(type_name, model, clean_inputs, clean_truth),
    }
    return model, record, held_inputs[:args.golden]


def save_npy(directory, name, array):
    array = np.ascontiguousarray(array, dtype="<f4")
    np.save(os.path.join(directory, name), array, allow_pickle=False)
    return name


def export_type(directory, type_name, model, golden_inputs):
    """Writes one .npy per tensor and the golden files; returns the manifest entry."""
    def layers(modules, prefix, last_linear):
        entries = []
        for index, layer in enumerate(modules):
            weight = layer.weight.detach().numpy()
            bias = layer.bias.detach().numpy()
            stem = "%s_%s_%d" % (type_name, prefix, index)
            entries.append({
                "weight": save_npy(directory, stem + "_weight.npy", weight),
                "bias": save_npy(directory, stem + "_bias.npy", bias),
                "weight_shape": list(weight.shape),
                "bias_shape": list(bias.shape),
                "activation": "identity" if (last_linear and index + 1 == len(modules)) else "relu",
            })
        return entries

    model.eval()
    with torch.no_grad():
        golden_outputs = model(torch.from_numpy(golden_inputs)).numpy()
    return {
        "output_size": synthetic.OUTPUT_SIZES[type_name],
        "shared_mlp": layers(model.shared, "shared", False),
        "pooling": "max",
        "head": layers(model.head, "head", True),
        "golden_inputs": save_npy(directory, "golden_%s_inputs.npy" % type_name, golden_inputs),
        "golden_outputs": save_npy(directory, "golden_%s_outputs.npy" % type_name, golden_outputs),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                         "..", "models", "learned_fitter"),
                        help="export folder (default fitting/models/learned_fitter)")
    parser.add_argument("--types", nargs="+", default=synthetic.TYPES, help="types to train")
    parser.add_argument("--num-points", type=int, default=128, help="N, points per segment")
    parser.add_argument("--segments", type=int, default=9600, help="training segments per type")
    parser.add_argument("--epochs", type=int, default=2, help="passes over the training segments")
    parser.add_argument("--batch", type=int, default=64, help="segments per optimiser step")
    parser.add_argument("--learning-rate", type=float, default=2e-3, help="Adam's initial rate (cosine decay)")
    parser.add_argument("--held-out", type=int, default=1000, help="held-out segments per type (each set)")
    parser.add_argument("--golden", type=int, default=4, help="golden input segments per type")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads (the machine is shared)")
    parser.add_argument("--seed", type=int, default=20240611, help="base seed; type k uses seed + k")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    output = os.path.abspath(args.output)
    os.makedirs(output, exist_ok=True)
    for stale in os.listdir(output):
        if stale.endswith(".npy") or stale == "manifest.json":
            os.remove(os.path.join(output, stale))
    total_start = time.time()
    total_cpu_start = time.process_time()
    networks = {}
    records = {}
    for offset, type_name in enumerate(args.types):
        print("training %s" % type_name, flush=True)
        model, record, golden_inputs = train_type(type_name, args, args.seed + synthetic.TYPES.index(type_name))
        networks[type_name] = export_type(output, type_name, model, golden_inputs)
        records[type_name] = record
        print("  %s: %s" % (type_name, json.dumps(record)), flush=True)
    total_seconds = time.time() - total_start
    manifest = {
        "format": "quadrix-learned-fitter",
        "version": 1,
        "num_points": args.num_points,
        "input": {
            "sampling": "strided: point i of N is input column floor(i * M / N) when M >= N, else i mod M",
            "centre": "mean of the N sampled points",
            "scale": "RMS distance of the N sampled points to the centre (unit RMS radius)",
            "rotation": "covariance eigenvectors, descending variance; first two signed so that the sum of "
                        "cubed projections is >= 0; third = first x second",
            "layout": "per segment N x 3 float32 (x, y, z) in the normalised frame",
        },
        "outputs": synthetic.OUTPUT_SIZES,
        "log_clamp": LOG_CLAMP,
        "types": list(networks.keys()),
        "networks": networks,
        "training": {
            "script": "fitting/training/train_learned_fitter.py",
            "command": "make train-fitter",
            "torch_version": torch.__version__,
            "threads": args.threads,
            "segments_per_type": args.segments,
            "held_out_segments_per_type": args.held_out,
            "epochs": args.epochs,
            "batch": args.batch,
            "learning_rate": args.learning_rate,
            "seed": args.seed,
            "data_size_bytes_per_type": args.segments * args.num_points * 3 * 4,
            "noise_max_m": synthetic.NOISE_MAX,
            "visible_fraction": [synthetic.VISIBLE_MIN, 1.0],
            "total_seconds": round(total_seconds, 1),
            "total_cpu_seconds": round(time.process_time() - total_cpu_start, 1),
            "per_type": records,
        },
    }
    with open(os.path.join(output, "manifest.json"), "w") as stream:
        json.dump(manifest, stream, indent=1, sort_keys=False)
        stream.write("\n")
    print("exported %d networks to %s in %.0f s" % (len(networks), output, total_seconds))


if __name__ == "__main__":
    main()
