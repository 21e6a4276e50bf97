// The fitter study: the synthetic generator honours type, visibility, noise and outliers; a small
// study measures what it should (exact fits have zero errors, runs are reproducible); the writers
// produce complete CSV / Markdown / SVG files; the real segments are plausible when the data exists.
#include "experiments/studies/fitter_study.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "test_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace quadrix {
namespace {


std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(SyntheticSegment, NoiseFreeInliersLieOnTheTrueSurface) {
  for (const QuadricType type : synthetic_segment_types()) {
    SyntheticSegmentSpec spec;
    spec.type = type;
    spec.points = 300;
    spec.seed = 11;
    const SyntheticSegment segment = make_synthetic_segment(spec);
    ASSERT_EQ(segment.points.cols(), 300);
    EXPECT_EQ(segment.outlier_count, 0);
    const QuadricDecomposition truth = Quadric::from_canonical(type, segment.scale, segment.pose).decompose();
    for (Eigen::Index i = 0; i < segment.points.cols(); ++i)
      ASSERT_LT(orthogonal_distance(truth, segment.points.col(i)), 1e-9 * (1.0 + segment.pose.translation().norm()))
          << quadric_type_name(type) << " point " << i;
    for (Eigen::Index i = 0; i < segment.full_surface.cols(); ++i)
      ASSERT_LT(orthogonal_distance(truth, segment.full_surface.col(i)), 1e-9 * (1.0 + segment.pose.translation().norm()));
  }
}

TEST(SyntheticSegment, VisibleSectorNoiseAndOutliersAreAsRequested) {
  SyntheticSegmentSpec spec;
  spec.type = QuadricType::CircularCylinder;
  spec.visible_fraction = 0.25;
  spec.points = 2000;
  spec.seed = 3;
  const SyntheticSegment clean = make_synthetic_segment(spec);
  // Angles in the canonical frame stay inside [0, 2 pi * 0.25].
  for (Eigen::Index i = 0; i < clean.points.cols(); ++i) {
    const Eigen::Vector3d local = clean.pose.inverse() * Eigen::Vector3d(clean.points.col(i));
    double angle = std::atan2(local.y(), local.x());
    if (angle < 0) angle += 2.0 * kPi;
    ASSERT_LE(angle, 0.5 * kPi + 1e-9);
  }
  spec.noise = 0.02;
  spec.outlier_fraction = 0.1;
  const SyntheticSegment noisy = make_synthetic_segment(spec);
  EXPECT_EQ(noisy.outlier_count, 200);
  // Same surface and samples (common random numbers): the noise is the difference.
  EXPECT_TRUE(noisy.pose.matrix().isApprox(clean.pose.matrix()));
  const Eigen::Matrix3Xd difference = noisy.points.rightCols(1800) - clean.points.rightCols(1800);
  const double sigma = std::sqrt(difference.squaredNorm() / (3.0 * 1800.0));
  EXPECT_NEAR(sigma, 0.02, 0.002);
  EXPECT_THROW(make_synthetic_segment(SyntheticSegmentSpec{QuadricType::Sphere, 0.0, 0.0, 0.0, 10, 1}), Error);
  EXPECT_THROW(make_synthetic_segment(SyntheticSegmentSpec{QuadricType::Sphere, -1.0, 1.0, 0.0, 10, 1}), Error);
  EXPECT_THROW(make_synthetic_segment(SyntheticSegmentSpec{QuadricType::HyperbolicParaboloid, 0.0, 1.0, 0.0, 10, 1}), Error);
}

FitterStudyOptions small_study() {
  FitterStudyOptions options;
  options.types = {QuadricType::Sphere, QuadricType::CircularCylinder};
  options.noise_levels = {0.0, 0.02};
  options.visible_fractions = {1.0};
  options.outlier_fractions = {0.0};
  options.fitters = {"statistical", "taubin", "constrained"};
  options.trials = 2;
  options.points_per_segment = 300;
  options.real_data = false;
  options.scan_segments = false;
  options.threads = 2;
  return options;
}

TEST(FitterStudy, MeasuresExactFitsAsExactAndIsReproducible) {
  const FitterStudyOptions options = small_study();
  const FitterStudyResult first = run_fitter_study(options);
  // 2 types x 2 noise x 2 trials segments, 3 fitters, hint + auto.
  ASSERT_EQ(first.rows.size(), 2u * 2u * 2u * 3u * 2u);
  int exact_rows = 0;
  for (const auto& row : first.rows) {
    if (row.fitter == "constrained" && row.mode == "hint" && row.noise == 0.0) {
      ++exact_rows;
      EXPECT_TRUE(row.type_correct);
      EXPECT_LT(row.scale_error, 1e-6);
      EXPECT_LT(row.centre_error, 1e-6);
      EXPECT_LT(row.surface_rms, 1e-6);
    }
    if (row.fitter == "statistical" && row.mode == "auto") {
      EXPECT_EQ(row.fitted_type, QuadricType::Ellipsoid);
    }
    if (row.fitter == "statistical" && row.mode == "hint" && row.true_type == QuadricType::Sphere) {
      EXPECT_GT(row.surface_rms, 1e-3);  // k_s * sigma is not the radius of a full sphere
    }
  }
  EXPECT_EQ(exact_rows, 4);
  const FitterStudyResult second = run_fitter_study(options);
  ASSERT_EQ(second.rows.size(), first.rows.size());
  for (std::size_t i = 0; i < first.rows.size(); ++i) {
    EXPECT_EQ(first.rows[i].fitter, second.rows[i].fitter);
    EXPECT_EQ(first.rows[i].status, second.rows[i].status);
    if (std::isfinite(first.rows[i].surface_rms)) {
      EXPECT_DOUBLE_EQ(first.rows[i].surface_rms, second.rows[i].surface_rms);
    }
  }
}

TEST(FitterStudy, FitsHeldApartScanSegmentsAndReportsThem) {
  FitterStudyOptions options = small_study();
  options.fitters = {"statistical", "taubin"};
  options.automatic_type = false;
  options.scan_segments = true;
  options.scan_scene_scans = 1;
  options.scan_object_scans = 5;
  options.scan_segments_per_type = 3;
  const FitterStudyResult result = run_fitter_study(options);
  std::size_t scan_rows = 0;
  std::vector<double> plane_axis_errors;
  for (const auto& row : result.rows) {
    if (row.source != "scan") continue;
    ++scan_rows;
    EXPECT_EQ(row.mode, "hint");
    EXPECT_GT(row.visible_fraction, 0.0);
    EXPECT_LE(row.visible_fraction, 1.0);
    if (row.fitter == "statistical" && row.true_type == QuadricType::Plane) plane_axis_errors.push_back(row.axis_error_deg);
  }
  EXPECT_GT(scan_rows, 0u);
  // A patch of a plane: its least-variance direction is close to the true normal.
  ASSERT_FALSE(plane_axis_errors.empty());
  std::sort(plane_axis_errors.begin(), plane_axis_errors.end());
  EXPECT_LT(plane_axis_errors[plane_axis_errors.size() / 2], 10.0);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "quadrix_test_fitter_study_scans";
  std::filesystem::create_directories(folder);
  write_fitter_study_markdown((folder / "fitters.md").string(), result, options, "quadrix compare-fitters --test");
  const std::string markdown = read_text(folder / "fitters.md");
  EXPECT_THAT(markdown, ::testing::HasSubstr("## Held-apart scan segments"));
  EXPECT_THAT(markdown, ::testing::HasSubstr("### Where each fitter wins (scan segments)"));
}

TEST(FitterStudy, RejectsBadOptions) {
  FitterStudyOptions options = small_study();
  options.fitters = {"no_such_fitter"};
  EXPECT_THROW(run_fitter_study(options), Error);
  options = small_study();
  options.visible_fractions = {1.5};
  EXPECT_THROW(run_fitter_study(options), Error);
  options = small_study();
  options.types = {QuadricType::HyperboloidOneSheet};
  EXPECT_THROW(run_fitter_study(options), Error);
}

TEST(FitterStudy, WritesCsvMarkdownAndSvg) {
  FitterStudyOptions options = small_study();
  options.trials = 1;
  const FitterStudyResult result = run_fitter_study(options);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "quadrix_test_fitter_study";
  std::filesystem::create_directories(folder);
  write_fitter_study_csv((folder / "fitters.csv").string(), result);
  write_fitter_study_markdown((folder / "fitters.md").string(), result, options, "quadrix compare-fitters --test");
  write_fitter_study_svg((folder / "fitters.svg").string(), result);
  const std::string csv = read_text(folder / "fitters.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(result.rows.size()) + 1);
  EXPECT_THAT(csv, ::testing::StartsWith("source,fitter,mode,true_type"));
  const std::string markdown = read_text(folder / "fitters.md");
  EXPECT_THAT(markdown, ::testing::HasSubstr("quadrix compare-fitters --test"));
  EXPECT_THAT(markdown, ::testing::HasSubstr("| constrained | sphere | 100% |"));
  EXPECT_THAT(markdown, ::testing::HasSubstr("## Type accuracy without a hint"));
  const std::string svg = read_text(folder / "fitters.svg");
  EXPECT_THAT(svg, ::testing::StartsWith("<svg"));
  EXPECT_THAT(svg, ::testing::HasSubstr("</svg>"));
  EXPECT_THAT(svg, ::testing::HasSubstr("<polyline"));
  // The plot check: four panels (three factors and the time per fit) and a legend entry per fitter.
  std::size_t panels = 0;
  for (std::size_t at = svg.find("font-weight=\"bold\""); at != std::string::npos; at = svg.find("font-weight=\"bold\"", at + 1))
    ++panels;
  EXPECT_EQ(panels, 4u);
  // Well-formed markup: every '<' opens a tag (titles must not carry a raw "<=").
  for (std::size_t at = svg.find('<'); at != std::string::npos; at = svg.find('<', at + 1))
    EXPECT_TRUE(std::isalpha(static_cast<unsigned char>(svg[at + 1])) || svg[at + 1] == '/')
        << "raw '<' in the SVG at " << svg.substr(at, 30);
  for (const auto& fitter : result.fitters) EXPECT_THAT(svg, ::testing::HasSubstr(">" + fitter + "</text>"));
  std::filesystem::remove_all(folder);
}

TEST(FitterStudy, RealSegmentsArePlausible) {
  QUADRIX_REQUIRE_SHARED_DATA("single_scans/table_scene_mug_stereo_textured.pcd");
  QUADRIX_REQUIRE_SHARED_DATA("single_scans/lamppost.pcd");
  std::vector<std::string> notes;
  const auto segments = real_fitter_segments(::quadrix::testing::shared_data_root().string(), 5000, notes);
  ASSERT_EQ(segments.size(), 4u);
  EXPECT_TRUE(notes.empty());
  for (const auto& segment : segments) {
    EXPECT_GT(segment.points.cols(), 500) << segment.name;
    EXPECT_LE(segment.points.cols(), 5000) << segment.name;
    EXPECT_FALSE(segment.how.empty());
  }
  const auto fitter = make_quadric_fitter("constrained");
  // The mug: a cylinder of a few centimetres radius; the lamppost's pole: under 15 cm.
  const QuadricFit mug = fitter->fit(segments[1].points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  ASSERT_EQ(mug.status, FitStatus::Ok) << mug.message;
  EXPECT_GT(mug.shape.scale(0), 0.02);
  EXPECT_LT(mug.shape.scale(0), 0.08);
  const QuadricFit pole = fitter->fit(segments[2].points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  ASSERT_EQ(pole.status, FitStatus::Ok) << pole.message;
  EXPECT_GT(pole.shape.scale(0), 0.02);
  EXPECT_LT(pole.shape.scale(0), 0.15);
  EXPECT_GT(std::abs(pole.shape.rotation.col(2).z()), std::cos(10.0 * kPi / 180.0));  // a near-vertical pole
  // The table plane: the RANSAC threshold was 1 cm, so the plane's residual is below it.
  const QuadricFit table = fitter->fit(segments[0].points, Eigen::Matrix3Xd(), QuadricType::Plane);
  ASSERT_EQ(table.status, FitStatus::Ok);
  EXPECT_LT(table.residual_rms, 0.01);
}

/// The KITTI segments come from the project's own extraction: large facades that a plane fits to
/// centimetres, and poles/trunks whose cylinder is near-vertical with a radius under half a metre.
TEST(FitterStudy, KittiSegmentsFromTheExtraction) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  std::vector<std::string> notes;
  const auto segments = kitti_fitter_segments(::quadrix::testing::shared_data_root().string(), 5000, 2, 2, notes);
  ASSERT_EQ(segments.size(), 6u) << (notes.empty() ? "" : notes.front());
  const auto fitter = make_quadric_fitter("constrained");
  for (const auto& segment : segments) {
    EXPECT_GE(segment.points.cols(), 15) << segment.name;
    EXPECT_LE(segment.points.cols(), 5000) << segment.name;
    const QuadricFit fit = fitter->fit(segment.points, Eigen::Matrix3Xd(), segment.type);
    if (segment.type == QuadricType::Plane) {
      ASSERT_EQ(fit.status, FitStatus::Ok) << segment.name << ": " << fit.message;
      EXPECT_GT(segment.points.cols(), 200) << segment.name;
      EXPECT_LT(fit.residual_rms, 0.1) << segment.name;
      EXPECT_LT(std::abs(fit.shape.rotation.col(0).z()), std::sin(20.0 * kPi / 180.0)) << segment.name << ": a facade is upright";
    } else if (segment.type == QuadricType::Line) {
      ASSERT_EQ(fit.status, FitStatus::Ok) << segment.name << ": " << fit.message;
      EXPECT_GT(std::abs(fit.shape.rotation.col(2).z()), std::cos(30.0 * kPi / 180.0)) << segment.name << ": poles stand";
    } else if (fit.status == FitStatus::Ok) {  // sparse rings may leave a pole's cylinder undetermined: a status
      EXPECT_LT(fit.shape.scale(0), 0.5) << segment.name << ": " << segment.points.cols() << " points, residual "
                                         << fit.residual_rms << " m, statistical scales " << fit.statistics.scale.transpose();
    }
  }
}

}  // namespace
}  // namespace quadrix
