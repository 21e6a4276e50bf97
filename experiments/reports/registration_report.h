// What `quadrix register --out DIR` writes: report.json (the contract: "transform", "status",
// "timings_ms" with "total" and one entry per stage, "counts", "candidates"), merged.ply (target
// grey, transformed source coloured) and bev.png (bird's-eye picture of the aligned clouds).
#pragma once

#include "estimation/overlap.h"
#include "estimation/registration.h"
#include "geometry/point_cloud.h"

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace quadrix {

/// Context of a run that the report records beside the RegistrationResult.
struct RegistrationReportContext {
  std::string source_path;                        ///< source cloud file
  std::string target_path;                        ///< target cloud file
  std::string source_preset;                      ///< preset used for the source (with "auto: ..." reasons in preset_notes)
  std::string target_preset;                      ///< preset used for the target
  std::string preset_notes;                       ///< how the presets were chosen (auto measurements), free text
  double load_ms = 0.0;                           ///< time to read both files, ms
  double total_ms = 0.0;                          ///< files loaded -> transform: reading + register_clouds, ms
  std::optional<Eigen::Isometry3d> ground_truth;  ///< T_gt mapping source into target, when known
  std::optional<OverlapMeasure> overlap;           ///< measure_overlap of the result, when measured
  Eigen::Vector3d source_sensor_origin = Eigen::Vector3d::Zero();  ///< where the source's sensor stood in its file's frame (the result is between sensor-centred clouds, centred_on_sensor)
  Eigen::Vector3d target_sensor_origin = Eigen::Vector3d::Zero();  ///< where the target's sensor stood in its file's frame
};

/// The report as a JSON document (pretty-printed). Keys: "transform" (4x4 row-major list of lists),
/// "status", "message", "timings_ms" ("total" = context.total_ms, "load", then every stage of the
/// result: modelling_source, modelling_target, correspondences, graphs, cliques, estimation,
/// selection, "registration" = register_clouds' own total), "counts", "candidates" (one object per
/// level: level, threshold_m, clique_size, refinement_status, valid, selected, score, pair_count,
/// filtered_count, term_count, factor_count, transform, note, clique: [[source record, target record], ...] of I*_k),
/// "best_to_second_ratio", "fitness", "inlier_rmse_m", "correspondence_count" (RegistrationResult's
/// fitness, inlier_rmse and correspondences.size(); the pairs themselves are left to the API),
/// "information" (6x6 row-major, rotation then translation, left perturbation in the target frame),
/// "from_initial_guess", "input"
/// (paths and presets), with sensor origins other than zero "sensor_origins" {source, target,
/// transform_between_files: the answer between the files' own frames (between_cloud_frames); every
/// other transform of the report is between the sensor-centred clouds}, with a ground truth
/// "ground_truth" {transform, rte_m, rre_deg, success} between the sensor-centred clouds, and
/// with a measured overlap "overlap" {distance_m, transformed, identity, sampled_points}; when the
/// dense search ran, "dense_search" {weakest_direction, weakest_share, best, rival, margin,
/// source_points, target_points, optima: [{start, overlap, median_residual_m, refined, transform}]}.
std::string registration_report_json(const RegistrationResult& result, const RegistrationReportContext& context);

/// Writes registration_report_json atomically to `path`.
void write_registration_report(const std::string& path, const RegistrationResult& result,
                               const RegistrationReportContext& context);

/// The merged cloud: target points grey (160,160,160), source points transformed by `transform`
/// and coloured orange (255,120,0); the `labels` field marks the side (0 target, 1 source).
PointCloud merge_aligned_clouds(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform);

/// Options of the bird's-eye picture.
struct BirdsEyeOptions {
  int image_size = 1024;        ///< width = height of the square image, pixels
  double half_extent = 0.0;     ///< half side of the pictured square around the target origin, m (0: framed on both clouds, see birds_eye_frame)
  double max_height = 0.0;      ///< points higher than this above the target origin are left out, m (0: keep all); roofs hide streets
  std::string status;           ///< the registration's status, shown in a banner coloured by it ("" : no banner)
  std::string title;            ///< short text after the status in the banner (e.g. the two file names)
};

/// Colours of the bird's-eye picture and its legend.
inline constexpr std::array<std::uint8_t, 3> kBirdsEyeTargetColor{150, 150, 150};        ///< target points
inline constexpr std::array<std::uint8_t, 3> kBirdsEyeSourceColor{235, 100, 0};          ///< moved source points
inline constexpr std::array<std::uint8_t, 3> kBirdsEyeTargetSensorColor{0, 0, 200};      ///< target sensor cross
inline constexpr std::array<std::uint8_t, 3> kBirdsEyeSourceSensorColor{130, 0, 130};    ///< source sensor cross (where the answer puts it)

/// Background of the bird's-eye status banner: ok green, ambiguous amber, degenerate and failed
/// red, anything else blue-grey (the page's status colours).
std::array<std::uint8_t, 3> status_picture_color(const std::string& status);

/// The square a bird's-eye picture shows: centre (x, y) and half side, m.
struct BirdsEyeFrame {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  ///< center of the pictured square, target frame, m
  double half_extent = 50.0;                         ///< half side of the pictured square, m
};

/// Frames the target and the transformed source together: the box between the 2nd and 98th
/// percentiles of their x and of their y (stray far points do not shrink the scene), squared,
/// with a 10% margin, half side clamped to 5..200 m. With options.half_extent > 0, that square
/// around the target origin instead.
BirdsEyeFrame birds_eye_frame(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                              const BirdsEyeOptions& options = {});

/// Writes a PNG seen from above (x right, y up): white background, target grey, transformed source
/// orange, both sensors as labelled crosses (target at its origin, source where the answer puts
/// it), a legend of these colours (top left), a banner with options.status coloured by it, and a
/// scale bar with its length in metres (bottom left). Atomic.
void write_birds_eye_png(const std::string& path, const PointCloud& source, const PointCloud& target,
                         const Eigen::Isometry3d& transform, const BirdsEyeOptions& options = {});

}  // namespace quadrix
