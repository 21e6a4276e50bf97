// report.json, merged.ply and bev.png of a registration (see registration_report.h).
#include "experiments/reports/registration_report.h"

#include "experiments/reports/model_picture.h"
#include "experiments/reports/picture_text.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <ostream>
#include <vector>

namespace quadrix {
namespace {

nlohmann::json matrix_json(const Eigen::Isometry3d& transform) {
  nlohmann::json rows = nlohmann::json::array();
  const Eigen::Matrix4d matrix = transform.matrix();
  for (int r = 0; r < 4; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 4; ++c) row.push_back(matrix(r, c));
    rows.push_back(row);
  }
  return rows;
}

// JSON has no infinity: unscored candidates get null.
nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

// 3x5 pixel glyphs of the digits and 'm' for the scale-bar label (rows top to bottom, 3 bits each).
const std::array<std::array<std::uint8_t, 5>, 11> kGlyphs = {{
    {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}, {0, 0, 7, 7, 5},
}};

struct Canvas {
  int size = 0;
  std::vector<std::uint8_t> pixels;  // RGB
  void set(int x, int y, std::array<std::uint8_t, 3> color) {
    if (x < 0 || y < 0 || x >= size || y >= size) return;
    std::uint8_t* pixel = &pixels[3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x))];
    pixel[0] = color[0];
    pixel[1] = color[1];
    pixel[2] = color[2];
  }
  void fill(int x0, int y0, int x1, int y1, std::array<std::uint8_t, 3> color) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) set(x, y, color);
  }
  // Draws `text` (digits and 'm') with glyph pixels of `scale` image pixels; returns the end x.
  int text(int x, int y, const std::string& text, int scale, std::array<std::uint8_t, 3> color) {
    for (const char c : text) {
      const int glyph = c == 'm' ? 10 : (c >= '0' && c <= '9' ? c - '0' : -1);
      if (glyph >= 0)
        for (int row = 0; row < 5; ++row)
          for (int column = 0; column < 3; ++column)
            if (kGlyphs[static_cast<std::size_t>(glyph)][static_cast<std::size_t>(row)] & (4 >> column))
              fill(x + column * scale, y + row * scale, x + (column + 1) * scale - 1, y + (row + 1) * scale - 1, color);
      x += 4 * scale;
    }
    return x;
  }
};

}  // namespace

std::string registration_report_json(const RegistrationResult& result, const RegistrationReportContext& context) {
  nlohmann::json report;
  report["transform"] = matrix_json(result.transform);
  report["status"] = registration_status_name(result.status);
  report["message"] = result.message;
  // What a back end uses: Open3D's evaluation and small_gicp's information (rotation then
  // translation, left perturbation in the target frame; RegistrationResult::information).
  nlohmann::json information = nlohmann::json::array();
  for (int r = 0; r < 6; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 6; ++c) row.push_back(result.information(r, c));
    information.push_back(row);
  }
  report["fitness"] = result.fitness;
  report["inlier_rmse_m"] = result.inlier_rmse;
  report["correspondence_count"] = result.correspondences.size();
  report["information"] = information;
  report["from_initial_guess"] = result.from_initial_guess;
  nlohmann::json timings;
  timings["total"] = context.total_ms;
  timings["load"] = context.load_ms;
  for (const auto& [stage, ms] : result.timings_ms) timings[stage == "total" ? "registration" : stage] = ms;
  report["timings_ms"] = timings;
  const RegistrationCounts& c = result.counts;
  report["counts"] = {{"source_points", c.source_points},
                      {"target_points", c.target_points},
                      {"source_elements", c.source_elements},
                      {"target_elements", c.target_elements},
                      {"source_quadrics", c.source_quadrics},
                      {"target_quadrics", c.target_quadrics},
                      {"source_augmented_points", c.source_augmented_points},
                      {"target_augmented_points", c.target_augmented_points},
                      {"correspondences", c.correspondences},
                      {"quadric_correspondences", c.quadric_correspondences},
                      {"augmented_correspondences", c.augmented_correspondences},
                      {"clique_sizes", c.clique_sizes},
                      {"source_isolated_points", c.source_isolated_points},
                      {"target_isolated_points", c.target_isolated_points}};
  nlohmann::json candidates = nlohmann::json::array();
  for (std::size_t i = 0; i < result.candidates.size(); ++i) {
    const RegistrationCandidate& candidate = result.candidates[i];
    // I*_k as [source record, target record] pairs: what the interactive page draws as lines.
    nlohmann::json clique = nlohmann::json::array();
    for (const RecordCorrespondence& pair : candidate.clique) clique.push_back({pair.source_index, pair.target_index});
    const bool selected = (result.status == RegistrationStatus::Ok || result.status == RegistrationStatus::Ambiguous) &&
                          i == result.best_candidate;
    candidates.push_back({{"level", candidate.level},
                          {"threshold_m", candidate.threshold},
                          {"clique_size", candidate.clique_size},
                          {"refinement_status", candidate.refinement_status},
                          {"valid", candidate.valid},
                          {"selected", selected},
                          {"score", number_or_null(candidate.score.score)},
                          {"pair_count", candidate.score.pair_count},
                          {"filtered_count", candidate.score.filtered_count},
                          {"term_count", candidate.score.term_count},
                          {"factor_count", candidate.factor_count},
                          {"refinement_filtered_count", candidate.filtered_count},
                          {"refinement_cost", number_or_null(candidate.refinement_cost)},
                          {"transform", matrix_json(candidate.transform)},
                          {"note", candidate.note},
                          {"clique", clique}});
  }
  report["candidates"] = candidates;
  report["best_to_second_ratio"] = number_or_null(result.best_to_second_ratio);
  report["input"] = {{"source", context.source_path},
                     {"target", context.target_path},
                     {"source_preset", context.source_preset},
                     {"target_preset", context.target_preset},
                     {"preset_notes", context.preset_notes}};
  if (!context.source_sensor_origin.isZero(0.0) || !context.target_sensor_origin.isZero(0.0)) {
    const Eigen::Vector3d& source = context.source_sensor_origin;
    const Eigen::Vector3d& target = context.target_sensor_origin;
    report["sensor_origins"] = {
        {"source", {source.x(), source.y(), source.z()}},
        {"target", {target.x(), target.y(), target.z()}},
        {"transform_between_files", matrix_json(between_cloud_frames(result.transform, source, target))}};
  }
  if (context.overlap)
    report["overlap"] = {{"distance_m", context.overlap->distance},
                         {"transformed", context.overlap->transformed},
                         {"identity", context.overlap->identity},
                         {"sampled_points", context.overlap->sampled}};
  if (result.dense_search) {
    const DenseSearchResult& search = *result.dense_search;
    nlohmann::json optima = nlohmann::json::array();
    for (const DenseOptimum& optimum : search.optima)
      optima.push_back({{"start", optimum.start},
                        {"overlap", optimum.overlap},
                        {"median_residual_m", optimum.median_residual},
                        {"refined", optimum.refined},
                        {"transform", matrix_json(optimum.transform)}});
    report["dense_search"] = {{"weakest_direction", {search.weakest_direction.x(), search.weakest_direction.y(), search.weakest_direction.z()}},
                              {"weakest_share", search.weakest_share},
                              {"best", search.best},
                              {"rival", search.rival ? nlohmann::json(*search.rival) : nlohmann::json(nullptr)},
                              {"margin", search.margin},
                              {"demoted", result.findings.dense_search_unclear},
                              {"unrefined_contenders", search.unrefined_contenders},
                              {"best_in_searched_region", search.best_in_searched_region},
                              {"source_points", search.source_points},
                              {"target_points", search.target_points},
                              {"optima", optima}};
  }
  if (!result.ground_correlation.empty()) {
    nlohmann::json poses = nlohmann::json::array();
    for (const GroundPose& pose : result.ground_correlation)
      poses.push_back({{"share", pose.share}, {"yaw_deg", pose.yaw_degrees}, {"transform", matrix_json(pose.transform)}});
    report["ground_correlation"] = poses;
  }
  if (result.half_turn) {
    const HalfTurnCheck& check = *result.half_turn;
    report["half_turn"] = {{"pivot", {check.pivot.x(), check.pivot.y(), check.pivot.z()}},
                           {"answer_overlap", check.answer_overlap},
                           {"rival_overlap", check.has_rival ? nlohmann::json(check.rival_overlap) : nlohmann::json(nullptr)},
                           {"rival", check.has_rival ? matrix_json(check.rival) : nlohmann::json(nullptr)},
                           {"demoted", result.findings.half_turn_rival || result.findings.half_turn_unclear}};
  }
  if (result.free_space) {
    const FreeSpaceMeasure& measure = *result.free_space;
    report["free_space"] = {{"source_in_target_free_space", measure.source_in_target_free_space},
                            {"target_in_source_free_space", measure.target_in_source_free_space},
                            {"source_tested", measure.source_tested},
                            {"target_tested", measure.target_tested},
                            {"sum", measure.sum()},
                            {"demoted", result.findings.in_free_space || result.findings.free_space_unjudged}};
  }
  if (context.ground_truth) {
    report["ground_truth"] = {{"transform", matrix_json(*context.ground_truth)},
                              {"rte_m", translation_error(result.transform, *context.ground_truth)},
                              {"rre_deg", rotation_error_degrees(result.transform, *context.ground_truth)},
                              {"success", registration_succeeded(result.transform, *context.ground_truth)}};
  }
  return report.dump(2) + "\n";
}

void write_registration_report(const std::string& path, const RegistrationResult& result,
                               const RegistrationReportContext& context) {
  const std::string text = registration_report_json(result, context);
  write_file_atomically(path, [&text](std::ostream& out) { out << text; });
}

PointCloud merge_aligned_clouds(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform) {
  PointCloud merged;
  const Eigen::Index target_count = static_cast<Eigen::Index>(target.size());
  const Eigen::Index source_count = static_cast<Eigen::Index>(source.size());
  merged.positions.resize(3, target_count + source_count);
  merged.positions.leftCols(target_count) = target.positions;
  merged.positions.rightCols(source_count) = (transform * source.positions.cast<double>()).cast<float>();
  merged.colors.assign(target.size(), {160, 160, 160});
  merged.colors.resize(target.size() + source.size(), {255, 120, 0});
  merged.labels.assign(target.size(), 0);
  merged.labels.resize(target.size() + source.size(), 1);
  return merged;
}

BirdsEyeFrame birds_eye_frame(const PointCloud& source, const PointCloud& target, const Eigen::Isometry3d& transform,
                              const BirdsEyeOptions& options) {
  BirdsEyeFrame frame;
  if (options.half_extent > 0.0) {
    frame.half_extent = options.half_extent;
    return frame;
  }
  // At most ~100k points of each cloud decide the frame (percentiles are stable well before that).
  std::vector<double> xs, ys;
  const auto collect = [&](const PointCloud& cloud, const Eigen::Isometry3d& pose) {
    const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 100000);
    for (std::size_t i = 0; i < cloud.size(); i += stride) {
      const Eigen::Vector3d p = pose * cloud.point(i);
      if (!p.allFinite()) continue;
      xs.push_back(p.x());
      ys.push_back(p.y());
    }
  };
  collect(target, Eigen::Isometry3d::Identity());
  collect(source, transform);
  if (xs.empty()) return frame;
  const auto percentile = [](std::vector<double>& values, double fraction) {
    const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(fraction * static_cast<double>(values.size())));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
  };
  const Eigen::Vector2d low(percentile(xs, 0.02), percentile(ys, 0.02));
  const Eigen::Vector2d high(percentile(xs, 0.98), percentile(ys, 0.98));
  frame.center = 0.5 * (low + high);
  frame.half_extent = std::clamp(0.55 * (high - low).maxCoeff(), 5.0, 200.0);  // scale bar >= 2 m: whole metres
  return frame;
}

PictureColor status_picture_color(const std::string& status) {
  if (status == "ok") return {205, 236, 205};
  if (status == "ambiguous") return {246, 227, 168};
  if (status == "degenerate" || status == "failed") return {243, 192, 192};
  return {221, 228, 238};
}

void write_birds_eye_png(const std::string& path, const PointCloud& source, const PointCloud& target,
                         const Eigen::Isometry3d& transform, const BirdsEyeOptions& options) {
  if (options.image_size < 64 || options.image_size > 16384)
    throw Error("write_birds_eye_png: image_size must be within 64..16384 pixels, got " + std::to_string(options.image_size));
  const BirdsEyeFrame frame = birds_eye_frame(source, target, transform, options);
  const double half_extent = frame.half_extent;
  Canvas canvas;
  canvas.size = options.image_size;
  canvas.pixels.assign(3 * static_cast<std::size_t>(canvas.size) * static_cast<std::size_t>(canvas.size), 255);
  const double pixels_per_metre = canvas.size / (2.0 * half_extent);
  const auto pixel_x = [&](double x) { return static_cast<int>(std::floor((x - frame.center.x() + half_extent) * pixels_per_metre)); };
  const auto pixel_y = [&](double y) { return static_cast<int>(std::floor((half_extent - y + frame.center.y()) * pixels_per_metre)); };
  const auto plot = [&](const Eigen::Vector3d& p, PictureColor color) {
    if (options.max_height > 0.0 && p.z() > options.max_height) return;
    canvas.set(pixel_x(p.x()), pixel_y(p.y()), color);
  };
  for (std::size_t i = 0; i < target.size(); ++i) plot(target.point(i), kBirdsEyeTargetColor);
  for (std::size_t i = 0; i < source.size(); ++i) plot(transform * source.point(i), kBirdsEyeSourceColor);
  // Scale bar: the largest of 1/2/5 x 10^k metres not longer than a fifth of the image.
  const double longest = 0.2 * 2.0 * half_extent;
  double bar = std::pow(10.0, std::floor(std::log10(longest)));
  for (const double factor : {5.0, 2.0})
    if (bar * factor <= longest) {
      bar *= factor;
      break;
    }
  const int bar_pixels = static_cast<int>(std::lround(bar * pixels_per_metre));
  const int margin = canvas.size / 32;
  const int thickness = std::max(3, canvas.size / 256);
  const int base = canvas.size - margin;
  canvas.fill(margin, base - thickness, margin + bar_pixels, base, {0, 0, 0});
  canvas.fill(margin, base - 4 * thickness, margin + thickness - 1, base, {0, 0, 0});
  canvas.fill(margin + bar_pixels - thickness + 1, base - 4 * thickness, margin + bar_pixels, base, {0, 0, 0});
  const std::string bar_label = std::to_string(static_cast<long long>(std::lround(bar))) + " m";
  RgbImage image{canvas.size, canvas.size, std::move(canvas.pixels)};
  const double text_height = std::max(11.0, canvas.size / 64.0);
  if (picture_font_available()) {
    draw_picture_text(image, margin, base - 4 * thickness - static_cast<int>(1.3 * text_height), bar_label, text_height, {0, 0, 0});
  } else {
    canvas.pixels = std::move(image.pixels);  // no font: the scale bar's digits from the built-in glyphs
    canvas.text(margin, base - 4 * thickness - 7 * std::max(2, canvas.size / 256), bar_label, std::max(2, canvas.size / 256), {0, 0, 0});
    image.pixels = std::move(canvas.pixels);
  }
  // The sensors (clouds are sensor-centred: the target's at its origin, the source's where the
  // answer puts it), each a labelled cross.
  const int arm = std::max(6, canvas.size / 110);
  const int width = std::max(3, canvas.size / 340);
  const Eigen::Vector3d source_sensor = transform.translation();
  draw_picture_cross(image, pixel_x(0.0), pixel_y(0.0), arm, width, kBirdsEyeTargetSensorColor);
  draw_picture_cross(image, pixel_x(source_sensor.x()), pixel_y(source_sensor.y()), arm, width, kBirdsEyeSourceSensorColor);
  draw_picture_text(image, pixel_x(0.0) + arm + 3, pixel_y(0.0) + 2, "target sensor", 0.85 * text_height, kBirdsEyeTargetSensorColor);
  draw_picture_text(image, pixel_x(source_sensor.x()) + arm + 3, pixel_y(source_sensor.y()) - static_cast<int>(text_height),
                    "source sensor", 0.85 * text_height, kBirdsEyeSourceSensorColor);
  // The status along the top (its colour as on the page: an ambiguous answer never looks like an
  // ok one), then the legend below it.
  int legend_top = margin;
  if (!options.status.empty()) {
    std::string banner = "status: " + options.status;
    if (options.status == "ambiguous") banner += " (not trusted: another placement fits about as well)";
    else if (options.status != "ok") banner += " (no trusted answer)";
    if (!options.title.empty()) banner += "   " + options.title;
    legend_top = draw_picture_banner(image, banner, status_picture_color(options.status), 1.15 * text_height).y1 + margin / 2;
  }
  draw_picture_legend(image, margin, legend_top, "",
                      {{kBirdsEyeTargetColor, "target"},
                       {kBirdsEyeSourceColor, "source, moved by the answer"},
                       {kBirdsEyeTargetSensorColor, "target sensor", true},
                       {kBirdsEyeSourceSensorColor, "source sensor (answer)", true}},
                      text_height);
  write_rgb_png(path, image);
}

}  // namespace quadrix
