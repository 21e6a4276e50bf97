// The learned quadric fitter (paper §"Quadric Fitting": QuadricsNet learns the canonical C and the
// pose P separately and combines them into Q = P^-T C P^-1, Eq. (Q=PCP)) and the paper's `auto`
// policy (learned first; the statistical fit when f_p2s of the learned one exceeds delta_p), here
// applied only to the types where the learned fit measured better (docs/learned_fitter.md).
//
// One small PointNet per type (plane, line, sphere, circular cylinder, circular cone, ellipsoid),
// trained by fitting/training/train_learned_fitter.py (`make train-fitter`) on segments cut from
// simulated scans plus analytic partial, noisy segments, exported as .npy tensors + manifest.json,
// and evaluated here with Eigen only.
#pragma once

#include "fitting/neural_network.h"
#include "fitting/quadric_fitter.h"
#include "fitting/statistical_fitter.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace quadrix {

/// Environment variable that overrides the compiled-in weight folder.
inline constexpr const char* kLearnedFitterDirectoryVariable = "QUADRIX_LEARNED_FITTER_DIR";

/// The weight folder used when options name none: $QUADRIX_LEARNED_FITTER_DIR if set and non-empty,
/// else the compiled-in <source>/fitting/models/learned_fitter.
std::string default_learned_fitter_directory();

/// One type's network and its golden files, as listed in manifest.json.
struct LearnedTypeNetwork {
  QuadricType type = QuadricType::Invalid;  ///< primitive type the network fits
  PointNetRegressor network;                ///< shared MLP + max-pool + head
  std::string golden_inputs_path;           ///< .npy (K, N, 3): fixed normalised inputs
  std::string golden_outputs_path;          ///< .npy (K, outputs): PyTorch's raw outputs for them
};

/// Every network of a weight folder.
struct LearnedFitterModel {
  std::string directory;                    ///< folder the model was read from
  int num_points = 0;                       ///< N, points per segment the networks were trained on
  double log_clamp = 10.0;                  ///< decoded log-scales are clamped to [-log_clamp, log_clamp]
  std::vector<LearnedTypeNetwork> networks; ///< one per trained type

  /// The network for `type`, or nullptr when none was trained for it.
  const LearnedTypeNetwork* find(QuadricType type) const;
};

/// Reads <directory>/manifest.json and every .npy it names, checking each tensor's shape against the
/// manifest and the layer chaining; throws quadrix::Error naming the file and what was wrong.
LearnedFitterModel load_learned_fitter_model(const std::string& directory);

/// The network's input frame of a segment: u = rotation^T (x - center) / scale.
struct SegmentNormalisation {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();          ///< c, mean of the sampled points
  double scale = 1.0;                                        ///< sigma, RMS distance to c (unit RMS radius)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();    ///< E, principal axes (descending, skew-signed, det +1)
};

/// The deterministic input sample: point i of `count` is column floor(i * M / count) when M >= count
/// (an even stride through the input order), else column i mod M (cyclic repetition; max-pooling
/// ignores repeats). Requires M >= 1.
Eigen::Matrix3Xd learned_fitter_sample(const Eigen::Matrix3Xd& points, int count);

/// Normalisation of the sampled points exactly as the training script does it (see
/// fitting/training/synthetic_segments.py `normalise`); scale 1 when all points coincide.
SegmentNormalisation normalise_segment(const Eigen::Matrix3Xd& sampled);

/// Canonical scale and pose of a learned fit, in metres and world coordinates.
struct LearnedPrimitive {
  QuadricType type = QuadricType::Invalid;         ///< the network's type
  Eigen::Vector3d scale = Eigen::Vector3d::Ones(); ///< from_canonical scales (cone: tan, tan, 1)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< P_q, canonical frame -> world
};

/// Decodes raw network outputs (normalised frame) into world scale and pose, undoing `frame`.
/// Throws quadrix::Error when `raw` does not have the type's output size.
LearnedPrimitive decode_learned_outputs(QuadricType type, const Eigen::VectorXf& raw, const SegmentNormalisation& frame,
                                        double log_clamp);

/// Options of the learned fitter.
struct LearnedFitterOptions {
  std::string model_directory;                          ///< weight folder; empty: default_learned_fitter_directory()
  QuadricType automatic_type = QuadricType::Ellipsoid;  ///< type without a hint (paper: geometry-only clusters -> ellipsoid)
  FitEvaluationOptions evaluation;                      ///< how the residual statistics are computed (default: every point)
};

/// The learned fitter. Loads every network at construction (throws quadrix::Error for a missing or
/// corrupt weight folder). Normals are not used. A type without a network gives status Failed with
/// a message listing the trained types.
std::unique_ptr<QuadricFitter> make_learned_fitter(const LearnedFitterOptions& options = {});

/// Types whose learned fit `auto` tries first by default: those where the learned fitter beat the
/// statistical one on held-apart scan segments (papers/studies/fitters.md, docs/modelling.md).
std::vector<QuadricType> default_auto_learned_types();

/// Options of the auto fitter (paper §"Quadric Fitting": learned first, statistical fallback).
struct AutoFitterOptions {
  double delta_p = 0.5;                    ///< delta_p: learned fit rejected when its f_p2s exceeds this (paper)
  std::vector<QuadricType> learned_types = default_auto_learned_types();  ///< types tried with the learned fitter first; others go straight to the statistical fit
  LearnedFitterOptions learned;            ///< options of the learned fitter tried first
  StatisticalFitterOptions statistical;    ///< options of the statistical fallback
};

/// The paper's policy, restricted to the types where it pays: for a type in learned_types, the
/// learned fit unless it failed or f_p2s (unit_space_algebraic_distance) exceeds delta_p, else the
/// statistical fit; other types get the statistical fit. QuadricFit::message names the fitter used
/// and why.
std::unique_ptr<QuadricFitter> make_auto_fitter(const AutoFitterOptions& options = {});

}  // namespace quadrix
