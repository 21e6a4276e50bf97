#!/usr/bin/python3
"""Trains the learned quadric fitter (one small PointNet per primitive type, in the spirit of
QuadricsNet, paper §"Quadric Fitting") and exports it for the C++/Eigen inference of
fitting/learned_fitter.cpp.

Run through `make train-fitter`, which first writes segments cut from simulated scans with
`quadrix fitter-segments` (fixed seed) and passes them as --scan-segments; it installs Debian's
python3-torch/python3-numpy if missing. Training only: nothing here runs at build or test time.

Data per type: the scan segments of that type (at most --max-scan-segments, an even stride), plus
analytic partial, noisy segments (synthetic_segments.make_segments) up to --min-segments, at least
--analytic. A --validation share of that pool is held out; each epoch ends with the validation
loss, the rate halves after --lr-patience epochs without improvement, training stops after
--patience such epochs or --max-epochs, and the epoch with the best validation loss is exported.
Types are independent (own seed), trained in --jobs worker processes of --threads torch threads.

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
import multiprocessing
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


def concatenate(parts):
    """Concatenates (inputs, truth) pairs on the truth keys they all have."""
    keys = set.intersection(*(set(truth) for _, truth in parts))
    inputs = np.concatenate([inputs for inputs, _ in parts])
    truth = {key: np.concatenate([truth[key] for _, truth in parts]) for key in keys}
    return inputs, truth


def subset(inputs, truth, index):
    return inputs[index], {key: value[index] for key, value in truth.items()}


def mean_loss(type_name, model, inputs, truth, batch=1024):
    """Mean of the summed loss terms over a data set (evaluation mode, no gradients)."""
    model.eval()
    total = 0.0
    with torch.no_grad():
        for first in range(0, len(inputs), batch):
            part_inputs, part_truth = subset(inputs, truth, slice(first, first + batch))
            terms = loss_terms(type_name, decode(type_name, model(torch.from_numpy(part_inputs))), to_tensors(part_truth))
            total += float(sum(terms.values())) * len(part_inputs)
    model.train()
    return total / len(inputs)


def train_type(type_name, args, seed):
    """Trains one type's network with a validation split and early stopping; returns the model with
    the best validation loss, its training record and the golden inputs."""
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    generation_start = time.time()
    parts = []
    scan = synthetic.load_scan_segments(args.scan_segments, type_name, args.num_points) if args.scan_segments else None
    scan_count = 0 if scan is None else len(scan[0])
    if scan is not None:
        if scan_count > args.max_scan_segments:  # an even stride keeps every scene, sensor and range
            keep = np.arange(args.max_scan_segments) * scan_count // args.max_scan_segments
            scan = (scan[0][keep], {key: value[keep] for key, value in scan[1].items()}, scan[2])
            scan_count = len(keep)
        parts.append(scan[:2])
    analytic_count = max(args.analytic, args.min_segments - scan_count)
    parts.append(synthetic.make_segments(rng, type_name, analytic_count, args.num_points))
    inputs, truth = concatenate(parts)
    is_scan = np.concatenate([np.ones(scan_count, bool), np.zeros(analytic_count, bool)])
    order = rng.permutation(len(inputs))
    validation_count = int(round(args.validation * len(inputs)))
    validation_index, training_index = order[:validation_count], order[validation_count:]
    training_inputs, training_truth = subset(inputs, truth, training_index)
    validation_inputs, validation_truth = subset(inputs, truth, validation_index)
    validation_scan = is_scan[validation_index]
    held_inputs, held_truth = synthetic.make_segments(rng, type_name, args.held_out, args.num_points)
    clean_inputs, clean_truth = synthetic.make_segments(rng, type_name, args.held_out, args.num_points,
                                                        visible=np.ones(args.held_out), noise=np.zeros(args.held_out))
    generation_seconds = time.time() - generation_start

    model = PointNetRegressor(synthetic.OUTPUT_SIZES[type_name])
    optimiser = torch.optim.Adam(model.parameters(), lr=args.learning_rate)
    all_inputs = torch.from_numpy(training_inputs)
    all_truth = to_tensors(training_truth)
    count = len(training_inputs)
    start = time.time()
    cpu_start = time.process_time()
    training_curve, validation_curve = [], []
    best_loss, best_epoch, best_state = float("inf"), -1, None
    stale = 0
    for epoch in range(args.max_epochs):
        permutation = torch.randperm(count)
        total, batches = 0.0, 0
        for first in range(0, count - args.batch + 1, args.batch):
            index = permutation[first:first + args.batch]
            predicted = decode(type_name, model(all_inputs[index]))
            terms = loss_terms(type_name, predicted, {key: value[index] for key, value in all_truth.items()})
            loss = sum(terms.values())
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item()
            batches += 1
        training_curve.append(total / batches)
        validation_curve.append(mean_loss(type_name, model, validation_inputs, validation_truth))
        improved = validation_curve[-1] < best_loss * (1.0 - args.min_improvement)
        if improved:
            best_loss, best_epoch, stale = validation_curve[-1], epoch, 0
            best_state = {key: value.clone() for key, value in model.state_dict().items()}
        else:
            stale += 1
            if stale % args.lr_patience == 0:  # plateau: halve the rate
                for group in optimiser.param_groups:
                    group["lr"] *= 0.5
        print("  %s epoch %d: training %.4f validation %.4f (best %.4f at %d) lr %.2g %.0f s" % (
            type_name, epoch, training_curve[-1], validation_curve[-1], best_loss, best_epoch,
            optimiser.param_groups[0]["lr"], time.time() - start), flush=True)
        if stale >= args.patience:
            break
    model.load_state_dict(best_state)
    seconds = time.time() - start
    scan_validation = validation_scan & (truth_visible(validation_truth) <= 0.5)
    record = {
        "training_seconds": round(seconds, 1),
        "training_cpu_seconds": round(time.process_time() - cpu_start, 1),
        "generation_seconds": round(generation_seconds, 1),
        "seed": seed,
        "scan_segments": scan_count,
        "analytic_segments": analytic_count,
        "training_segments": int(count),
        "validation_segments": int(validation_count),
        "epochs_run": len(training_curve),
        "best_epoch": best_epoch + 1,
        "best_validation_loss": round(best_loss, 6),
        "training_loss": [round(value, 6) for value in training_curve],
        "validation_loss": [round(value, 6) for value in validation_curve],
        "validation_scan_partial": evaluate(type_name, model, *subset(validation_inputs, validation_truth, scan_validation))
        if scan_validation.any() else {},
        "held_out_partial_noisy": evaluate(type_name, model, held_inputs, held_truth),
        "held_out_clean_full": evaluate(type_name, model, clean_inputs, clean_truth),
    }
    return model, record, held_inputs[:args.golden]


def train_worker(job):
    """One type's training in a worker: returns (state dict, record, golden inputs)."""
    type_name, args = job
    torch.set_num_threads(args.threads)
    print("training %s" % type_name, flush=True)
    model, record, golden_inputs = train_type(type_name, args, args.seed + synthetic.TYPES.index(type_name))
    return model.state_dict(), record, golden_inputs


def truth_visible(truth):
    return np.asarray(truth["visible"], dtype=np.float64)


def write_loss_svg(path, records):
    """Training and validation loss per epoch, one panel per type (log scale), as a standalone SVG."""
    names = list(records)
    columns, width, height, margin = 3, 330, 230, 46
    rows = (len(names) + columns - 1) // columns
    parts = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" font-size="11">'
             % (columns * width, rows * height + 24),
             '<text x="8" y="16" font-size="13">Learned fitter: training (blue) and validation (orange) loss per epoch, '
             'log scale; the marker is the kept epoch</text>']
    for panel, name in enumerate(names):
        record = records[name]
        x0, y0 = (panel % columns) * width + margin, (panel // columns) * height + 24 + 20
        plot_w, plot_h = width - margin - 14, height - 20 - 36
        values = [v for v in record["training_loss"] + record["validation_loss"] if v > 0]
        low, high = np.log10(min(values)), np.log10(max(values))
        if high - low < 1e-6:
            high = low + 1.0
        epochs = max(len(record["training_loss"]), 2)

        def point(epoch, value):
            return (x0 + plot_w * epoch / (epochs - 1),
                    y0 + plot_h * (1.0 - (np.log10(max(value, 1e-12)) - low) / (high - low)))

        parts.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#999"/>' % (x0, y0, plot_w, plot_h))
        parts.append('<text x="%d" y="%d">%s (%d epochs, best %d)</text>' % (
            x0, y0 - 6, name, record["epochs_run"], record["best_epoch"]))
        parts.append('<text x="%d" y="%d" text-anchor="end">%.3g</text>' % (x0 - 3, y0 + 8, 10 ** high))
        parts.append('<text x="%d" y="%d" text-anchor="end">%.3g</text>' % (x0 - 3, y0 + plot_h, 10 ** low))
        parts.append('<text x="%d" y="%d" text-anchor="middle">epoch</text>' % (x0 + plot_w / 2, y0 + plot_h + 16))
        for key, colour in (("training_loss", "#1f77b4"), ("validation_loss", "#ff7f0e")):
            coordinates = " ".join("%.1f,%.1f" % point(epoch, value) for epoch, value in enumerate(record[key]))
            parts.append('<polyline fill="none" stroke="%s" stroke-width="1.5" points="%s"/>' % (colour, coordinates))
        best_x, best_y = point(record["best_epoch"] - 1, record["best_validation_loss"])
        parts.append('<circle cx="%.1f" cy="%.1f" r="3" fill="#ff7f0e"/>' % (best_x, best_y))
    parts.append("</svg>")
    with open(path, "w") as stream:
        stream.write("\n".join(parts) + "\n")


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
    parser.add_argument("--scan-segments", default="", help="folder written by `quadrix fitter-segments` (empty: none)")
    parser.add_argument("--max-scan-segments", type=int, default=6000, help="at most this many scan segments per type")
    parser.add_argument("--analytic", type=int, default=1500, help="analytic segments per type (at least)")
    parser.add_argument("--min-segments", type=int, default=6000,
                        help="analytic segments top the scan segments up to this many per type")
    parser.add_argument("--validation", type=float, default=0.1, help="share of the segments kept for validation")
    parser.add_argument("--max-epochs", type=int, default=100, help="most passes over the training segments")
    parser.add_argument("--patience", type=int, default=4, help="stop after this many epochs without a better validation loss")
    parser.add_argument("--lr-patience", type=int, default=2, help="halve the rate after this many epochs without one")
    parser.add_argument("--min-improvement", type=float, default=1e-3, help="relative decrease that counts as better")
    parser.add_argument("--loss-svg", default="", help="write the loss curves here (SVG; empty: not written)")
    parser.add_argument("--batch", type=int, default=64, help="segments per optimiser step")
    parser.add_argument("--learning-rate", type=float, default=2e-3, help="Adam's initial rate (halved on plateaus)")
    parser.add_argument("--held-out", type=int, default=1000, help="held-out segments per type (each set)")
    parser.add_argument("--golden", type=int, default=4, help="golden input segments per type")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads per type (the machine is shared)")
    parser.add_argument("--jobs", type=int, default=2, help="types trained at the same time (worker processes)")
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
    # Types are independent (own seed, one torch thread each), so running them in parallel worker
    # processes gives the same weights as running them one after the other.
    jobs = [(type_name, args) for type_name in args.types]
    if args.jobs > 1:
        with multiprocessing.get_context("fork").Pool(args.jobs) as pool:
            trained = pool.map(train_worker, jobs, chunksize=1)
    else:
        trained = [train_worker(job) for job in jobs]
    for type_name, (state, record, golden_inputs) in zip(args.types, trained):
        model = PointNetRegressor(synthetic.OUTPUT_SIZES[type_name])
        model.load_state_dict(state)
        networks[type_name] = export_type(output, type_name, model, golden_inputs)
        records[type_name] = record
        print("  %s: %s" % (type_name, json.dumps(record)), flush=True)
    total_seconds = time.time() - total_start
    scan_source = {}
    if args.scan_segments:
        with open(os.path.join(args.scan_segments, "segments.json")) as stream:
            description = json.load(stream)
        scan_source = {key: description[key] for key in ("seed", "scans", "object_scans", "crops", "segments")
                       if key in description}
        scan_source["command"] = ("quadrix fitter-segments --seed %s --scans %s --object-scans %s --crops %s" % (
            description.get("seed"), description.get("scans"), description.get("object_scans"), description.get("crops")))
    if args.loss_svg:
        write_loss_svg(args.loss_svg, records)
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
            "jobs": args.jobs,
            "scan_segments": scan_source,
            "scan_segments_per_type_at_most": args.max_scan_segments,
            "analytic_segments_per_type_at_least": args.analytic,
            "segments_per_type_at_least": args.min_segments,
            "validation_share": args.validation,
            "held_out_segments_per_type": args.held_out,
            "max_epochs": args.max_epochs,
            "patience": args.patience,
            "lr_patience": args.lr_patience,
            "min_improvement": args.min_improvement,
            "epochs_run": {name: record["epochs_run"] for name, record in records.items()},
            "best_validation_loss": {name: record["best_validation_loss"] for name, record in records.items()},
            "batch": args.batch,
            "learning_rate": args.learning_rate,
            "seed": args.seed,
            "analytic_noise_max_m": synthetic.NOISE_MAX,
            "analytic_visible_fraction": [synthetic.VISIBLE_MIN, 1.0],
            "total_seconds": round(total_seconds, 1),
            # The main process plus every type's training loop (the workers' own clocks).
            "total_cpu_seconds": round(time.process_time() - total_cpu_start +
                                       sum(record["training_cpu_seconds"] for record in records.values()), 1),
            "per_type": records,
        },
    }
    with open(os.path.join(output, "manifest.json"), "w") as stream:
        json.dump(manifest, stream, indent=1, sort_keys=False)
        stream.write("\n")
    print("exported %d networks to %s in %.0f s" % (len(networks), output, total_seconds))


if __name__ == "__main__":
    main()
