// The refiner study (`quadrix compare-refiners`): every registered refinement backend x
// algorithm x robust loss minimises the same objective (paper Eq. (quadrics distance), Algorithm 1
// LMOptimizer; estimation/refiner.h) from perturbed starts, on
//   - the synthetic monument and street (experiments/synthetic/synthetic_scene.h): ground-truth quadric
//     records moved by a known pose, with optional noise on the target attributes (centres, axes,
//     scales) and a share of wrong correspondences;
//   - the real KITTI loop-closure pairs of ../shared/data/pairs.tsv: both clouds modelled as
//     `quadrix register` does, the correspondences that are inliers under the ground truth and those
//     of the maximum clique the pipeline selects.
// It reports final RTE/RRE, convergence, iterations, evaluations and time, and writes a CSV with one
// row per refinement, a Markdown summary and an SVG plot. Fixed seeds make every run identical
// (times aside).
#pragma once

#include "estimation/quadric_distance.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace quadrix {

/// One refiner set-up compared by the study.
struct RefinerConfiguration {
  std::string backend;                ///< refiner registry name ("ceres", "nlopt", ...)
  std::string algorithm;              ///< RefinerOptions::algorithm ("" = the backend's default)
  RobustLoss loss = RobustLoss::None; ///< robust kernel
};

/// The algorithms the study runs for a backend: ceres {levenberg_marquardt, dogleg}, nlopt {lbfgs,
/// slsqp, bobyqa}; any other registered backend runs its default algorithm ("").
std::vector<std::string> refiner_study_algorithms(const std::string& backend);

/// Every backend x algorithm x loss (backends empty = every registered refiner); throws
/// quadrix::Error for an unknown backend name.
std::vector<RefinerConfiguration> refiner_study_configurations(const std::vector<std::string>& backends,
                                                              const std::vector<RobustLoss>& losses);

/// "backend/algorithm" (or just the backend when the algorithm is the default).
std::string refiner_configuration_name(const RefinerConfiguration& configuration);

/// Noise added to each target record of a synthetic problem (paper Struct. 1 attributes).
struct AttributeNoise {
  double centre = 0.0;       ///< std dev per axis of the element's displacement (centre), metres
  double axis_degrees = 0.0; ///< std dev per axis of the element's rotation about its centre (principal axes), degrees
  double scale = 0.0;        ///< relative std dev of the full scales s_f (and of the quadric's canonical scales)
};

/// Options of the study; the defaults are the committed report's configuration.
struct RefinerStudyOptions {
  std::vector<std::string> scenes = {"monument", "street"};     ///< synthetic scenes (experiments/synthetic/synthetic_scene.h names)
  std::vector<std::string> backends;                            ///< registry names; empty = every registered refiner
  std::vector<RobustLoss> losses = {RobustLoss::None, RobustLoss::Huber, RobustLoss::Cauchy, RobustLoss::Dcs};  ///< kernels
  std::vector<double> outlier_fractions = {0.0, 0.1, 0.25, 0.5};  ///< share of wrong synthetic correspondences
  std::vector<AttributeNoise> noise_levels = {{0.0, 0.0, 0.0}, {0.02, 0.5, 0.05}};  ///< synthetic target attribute noise levels
  int trials = 10;                          ///< perturbed starts per synthetic cell and per real correspondence set
  double minimum_translation = 0.5;         ///< start perturbation: translation drawn uniformly in [min, max], metres
  double maximum_translation = 5.0;         ///< upper end of that translation range, metres
  double minimum_rotation_degrees = 2.0;    ///< start perturbation: rotation angle drawn uniformly in [min, max], degrees
  double maximum_rotation_degrees = 20.0;   ///< upper end of that rotation range, degrees
  double loss_scale = 0.5;                  ///< a of Huber/Cauchy, Phi of DCS, units of ||e|| (metres / unit-vector length)
  double converged_translation = 0.01;      ///< converged: final pose within this of the criterion pose, metres
  double converged_rotation_degrees = 0.05; ///< and within this angle, degrees
  std::size_t max_synthetic_elements = 120; ///< a synthetic problem uses at most this many primitives (a random subset per trial)
  bool augment_non_central = true;          ///< Augment() of Algorithm 1 on linear / planar centres (as the pipeline)
  std::uint64_t seed = 20241122;            ///< base seed; every problem and start derives from it
  bool real_data = true;                    ///< also run the real KITTI loop-closure pairs when the data exists
  std::string data_root = "../shared/data"; ///< folder holding pairs.tsv
  std::string real_preset = "vlp64";        ///< registration preset used to model the KITTI clouds (HDL-64E)
  std::size_t max_real_pairs = 0;           ///< at most this many loop-closure pairs (0 = all)
  int threads = 1;                          ///< worker threads (1 keeps refinement times free of contention between workers)
};

/// One refinement of the study.
struct RefinerStudyRow {
  std::string source;                ///< synthetic scene name or real pair id
  std::string correspondence_set;    ///< "synthetic", "gt_inliers" (real, inliers under the ground truth) or "clique" (real, the pipeline's clique)
  std::string backend;               ///< registry name
  std::string algorithm;             ///< algorithm run
  std::string loss;                  ///< robust_loss_name
  double noise = 0.0;                ///< synthetic centre noise sigma, metres (its level's axis/scale noise go with it)
  double outlier_fraction = 0.0;     ///< wrong correspondences asked for (synthetic)
  int trial = 0;                     ///< start index
  double start_translation = 0.0;    ///< ||t_start - t_gt||, metres
  double start_rotation_degrees = 0.0;  ///< angle of R_start^T R_gt, degrees
  std::size_t correspondences = 0;   ///< record correspondences given to the factor builder
  std::size_t wrong_correspondences = 0;  ///< of which wrong (synthetic: by construction; real: farther than 0.5 m under the ground truth)
  std::size_t factors = 0;           ///< factors of the problem (with augmentation and ground)
  std::string status;                ///< refinement_status_name
  double rte = 0.0;                  ///< ||t - t_gt||, metres
  double rre_degrees = 0.0;          ///< rotation error against the ground truth, degrees
  std::string criterion;             ///< "truth" (noise-free synthetic without wrong correspondences) or "reference"
  double reference_rte = 0.0;        ///< RTE of the reference refinement (same configuration started at the ground truth), metres
  double reference_rre_degrees = 0.0;///< its RRE, degrees
  double gap_translation = 0.0;      ///< final pose vs the criterion pose (truth or reference), metres
  double gap_rotation_degrees = 0.0; ///< same, degrees
  bool converged = false;            ///< gap_translation < converged_translation and gap_rotation < converged_rotation
  int iterations = 0;                ///< RefinementResult::iterations
  int evaluations = 0;               ///< RefinementResult::evaluations
  double initial_cost = 0.0;         ///< F at the start
  double final_cost = 0.0;           ///< F at the end
  double time_ms = 0.0;              ///< RefinementResult::seconds in milliseconds (wall clock)
  double cpu_ms = 0.0;               ///< CPU time of the refining thread, milliseconds (robust to a loaded machine)
};

/// All refinements of a study.
struct RefinerStudyResult {
  std::vector<RefinerStudyRow> rows;                      ///< one per refinement, in a fixed order
  std::vector<RefinerConfiguration> configurations;       ///< what was compared
  std::vector<std::string> notes;                         ///< how each real pair was prepared, or why it was skipped
  double seconds = 0.0;                                   ///< wall time of the study
};

/// Progress callback: refinements done, refinements in total.
using RefinerStudyProgress = std::function<void(std::size_t done, std::size_t total)>;

/// Runs the study; throws quadrix::Error for an unknown scene or backend, or values out of range.
RefinerStudyResult run_refiner_study(const RefinerStudyOptions& options, const RefinerStudyProgress& progress = {});

/// Writes one CSV row per refinement (header first), atomically.
void write_refiner_study_csv(const std::string& path, const RefinerStudyResult& result);
/// Writes the Markdown report (definitions, convergence per configuration and outlier level, cost,
/// real pairs, the command that produced it), atomically.
void write_refiner_study_markdown(const std::string& path, const RefinerStudyResult& result,
                                  const RefinerStudyOptions& options, const std::string& command_line);
/// Writes an SVG: convergence against the wrong-correspondence share per loss, and median time, atomically.
void write_refiner_study_svg(const std::string& path, const RefinerStudyResult& result);

}  // namespace quadrix
