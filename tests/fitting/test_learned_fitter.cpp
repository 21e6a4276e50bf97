// The learned fitter (ONNX-free, Eigen inference) and the auto policy (paper §"Quadric Fitting").
// Golden test against PyTorch, accuracy on clean full synthetic surfaces against the bounds measured
// on held-out data at training time, weight-file errors, the sampling/normalisation rules, and the
// learned-first / statistical-fallback policy with delta_p. Fixed seeds throughout.
#include "fitting/learned_fitter.h"
#include "fitting/neural_network.h"
#include "fitting/quadric_fitter.h"
#include "fitting/statistical_fitter.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "test_geometry.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace quadrix {
namespace {

using testing::random_pose;
using testing::TranslationDraw;

namespace fs = std::filesystem;
using ::testing::HasSubstr;

double log_uniform(std::mt19937_64& random, double low, double high) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  return std::exp(std::log(low) + unit(random) * (std::log(high) - std::log(low)));
}

/// A clean, fully visible synthetic segment: points, true canonical scale and pose. Sizes follow the
/// training ranges of fitting/training/synthetic_segments.py; sampled independently of it.
struct Segment {
  Eigen::Matrix3Xd points;
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

Segment clean_full_segment(QuadricType type, int count, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Segment segment;
  segment.pose = random_pose(random, 20.0, TranslationDraw::Gaussian);
  segment.points.resize(3, count);
  double width = 0, height = 0, radius = 0, length = 0, tangent = 0, h0 = 0, h1 = 0;
  switch (type) {
    case QuadricType::Plane: width = 1.0 + 9.0 * unit(random); height = 1.0 + 9.0 * unit(random); break;
    case QuadricType::Line: length = 1.0 + 9.0 * unit(random); radius = 0.15 * unit(random); break;
    case QuadricType::Sphere: radius = log_uniform(random, 0.3, 3.0); segment.scale.setConstant(radius); break;
    case QuadricType::Ellipsoid:
      for (int k = 0; k < 3; ++k) segment.scale(k) = log_uniform(random, 0.3, 3.0);
      break;
    case QuadricType::CircularCylinder:
      radius = log_uniform(random, 0.1, 2.0);
      length = log_uniform(random, 1.0, 10.0);
      segment.scale << radius, radius, 1.0;
      break;
    case QuadricType::CircularCone:
      tangent = std::tan((10.0 + 40.0 * unit(random)) * kPi / 180.0);
      h0 = 0.1 + 1.4 * unit(random);
      h1 = h0 + 0.5 + 3.5 * unit(random);
      segment.scale << tangent, tangent, 1.0;
      break;
    default: break;
  }
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * kPi * unit(random);
    Eigen::Vector3d local;
    switch (type) {
      case QuadricType::Plane: local << 0.0, (unit(random) - 0.5) * width, (unit(random) - 0.5) * height; break;
      case QuadricType::Line:
        local << radius * std::cos(angle), radius * std::sin(angle), (unit(random) - 0.5) * length;
        break;
      case QuadricType::Sphere:
      case QuadricType::Ellipsoid: {
        Eigen::Vector3d direction(normal(random), normal(random), normal(random));
        local = direction.normalized().cwiseProduct(segment.scale);
        break;
      }
      case QuadricType::CircularCylinder:
        local << radius * std::cos(angle), radius * std::sin(angle), (unit(random) - 0.5) * length;
        break;
      case QuadricType::CircularCone: {
        const double h = std::sqrt(h0 * h0 + unit(random) * (h1 * h1 - h0 * h0));
        local << h * tangent * std::cos(angle), h * tangent * std::sin(angle), h;
        break;
      }
      default: local.setZero();
    }
    segment.points.col(i) = segment.pose * local;
  }
  return segment;
}

/// Errors of one fit in the units the training script reports (synthetic_segments / accuracy()):
/// axis angle in degrees, relative scale error, and centre / foot error in units of the segment's
/// RMS radius.
struct FitErrors {
  double axis_deg = 0.0;
  double scale_rel = 0.0;
  double centre = 0.0;
};

FitErrors fit_errors(QuadricType type, const Segment& truth, const QuadricDecomposition& shape) {
  const Eigen::Vector3d centroid = truth.points.rowwise().mean();
  const double rms_radius = std::sqrt((truth.points.colwise() - centroid).colwise().squaredNorm().mean());
  FitErrors errors;
  const auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / kPi;
  };
  const auto line_foot = [&](const Eigen::Vector3d& point, const Eigen::Vector3d& axis) -> Eigen::Vector3d {
    const Eigen::Vector3d offset = centroid - point;
    return point + offset.dot(axis) * axis;
  };
  switch (type) {
    case QuadricType::Plane: {
      const Eigen::Vector3d normal = shape.rotation.col(0);
      const Eigen::Vector3d true_normal = truth.pose.linear().col(0);
      errors.axis_deg = angle(normal, true_normal);
      const Eigen::Vector3d foot = centroid - (centroid - shape.center).dot(normal) * normal;
      const Eigen::Vector3d true_foot = centroid - (centroid - truth.pose.translation()).dot(true_normal) * true_normal;
      errors.centre = (foot - true_foot).norm() / rms_radius;
      break;
    }
    case QuadricType::Line:
    case QuadricType::CircularCylinder: {
      errors.axis_deg = angle(shape.rotation.col(2), truth.pose.linear().col(2));
      errors.centre = (line_foot(shape.center, shape.rotation.col(2)) -
                       line_foot(truth.pose.translation(), truth.pose.linear().col(2)))
                          .norm() /
                      rms_radius;
      if (type == QuadricType::CircularCylinder) errors.scale_rel = std::abs(shape.scale(0) / truth.scale(0) - 1.0);
      break;
    }
    case QuadricType::CircularCone:
      errors.axis_deg = angle(shape.rotation.col(2), truth.pose.linear().col(2));
      errors.centre = (shape.center - truth.pose.translation()).norm() / rms_radius;
      errors.scale_rel = std::abs(shape.scale(0) / truth.scale(0) - 1.0);
      break;
    case QuadricType::Sphere:
      errors.centre = (shape.center - truth.pose.translation()).norm() / rms_radius;
      errors.scale_rel = std::abs(shape.scale(0) / truth.scale(0) - 1.0);
      break;
    case QuadricType::Ellipsoid: {
      errors.centre = (shape.center - truth.pose.translation()).norm() / rms_radius;
      Eigen::Vector3d found = shape.scale;
      Eigen::Vector3d expected = truth.scale;
      std::sort(found.data(), found.data() + 3);
      std::sort(expected.data(), expected.data() + 3);
      errors.scale_rel = (found.cwiseQuotient(expected).array() - 1.0).abs().maxCoeff();
      break;
    }
    default: break;
  }
  return errors;
}

std::vector<QuadricType> trained_types() {
  return {QuadricType::Plane,           QuadricType::Line,         QuadricType::Sphere,
          QuadricType::CircularCylinder, QuadricType::CircularCone, QuadricType::Ellipsoid};
}

// ---------------------------------------------------------------------------------------------
// Golden test: Eigen inference == PyTorch within 1e-4 on the fixed inputs shipped with the weights.

TEST(LearnedFitterModel, GoldenInferenceMatchesPyTorch) {
  const LearnedFitterModel model = load_learned_fitter_model(default_learned_fitter_directory());
  ASSERT_EQ(model.networks.size(), trained_types().size());
  for (const QuadricType type : trained_types()) {
    const LearnedTypeNetwork* network = model.find(type);
    ASSERT_NE(network, nullptr) << quadric_type_name(type);
    const NpyArray inputs = read_npy_float32(network->golden_inputs_path);
    const NpyArray outputs = read_npy_float32(network->golden_outputs_path);
    ASSERT_EQ(inputs.shape.size(), 3u);
    ASSERT_EQ(inputs.shape[1], model.num_points);
    ASSERT_EQ(inputs.shape[2], 3);
    ASSERT_EQ(outputs.shape.size(), 2u);
    ASSERT_EQ(outputs.shape[0], inputs.shape[0]);
    ASSERT_EQ(outputs.shape[1], network->network.output_size());
    ASSERT_GE(inputs.shape[0], 1);
    for (std::int64_t k = 0; k < inputs.shape[0]; ++k) {
      // Each golden segment is N x 3 row-major: its transpose is the 3 x N column layout.
      const Eigen::Matrix3Xf points = Eigen::Map<const Eigen::Matrix3Xf>(
          inputs.values.data() + k * model.num_points * 3, 3, model.num_points);
      const Eigen::VectorXf expected =
          Eigen::Map<const Eigen::VectorXf>(outputs.values.data() + k * outputs.shape[1], outputs.shape[1]);
      const Eigen::VectorXf found = network->network.forward(points);
      ASSERT_EQ(found.size(), expected.size());
      for (Eigen::Index j = 0; j < found.size(); ++j)
        EXPECT_NEAR(found(j), expected(j), 1e-4) << quadric_type_name(type) << " segment " << k << " output " << j;
    }
  }
}

TEST(LearnedFitterModel, OutputIsPermutationInvariantAndWeightsAreSmall) {
  const LearnedFitterModel model = load_learned_fitter_model(default_learned_fitter_directory());
  std::mt19937_64 random(41);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Eigen::Matrix3Xf points(3, model.num_points);
  for (Eigen::Index i = 0; i < points.size(); ++i) points.data()[i] = normal(random);
  std::size_t parameters = 0;
  for (const LearnedTypeNetwork& network : model.networks) {
    const Eigen::VectorXf forward = network.network.forward(points);
    const Eigen::VectorXf backward = network.network.forward(points.rowwise().reverse());
    EXPECT_LT((forward - backward).cwiseAbs().maxCoeff(), 1e-5) << quadric_type_name(network.type);
    parameters += network.network.parameter_count();
  }
  EXPECT_LT(parameters * sizeof(float), 20u * 1024u * 1024u);  // committed weights stay under 20 MB
}

// ---------------------------------------------------------------------------------------------
// Accuracy on clean full synthetic segments against the bounds measured on 1000 held-out clean
// full segments per type at training time (manifest.json "held_out_clean_full", p90 rounded up).

struct AccuracyBound {
  QuadricType type;
  double axis_deg;   ///< p90 axis / normal error, degrees (0: not applicable)
  double scale_rel;  ///< p90 relative radius / tan / max semi-axis error (0: not applicable)
  double centre;     ///< p90 centre, apex or foot error in units of the segment's RMS radius
};

class LearnedFitterAccuracy : public ::testing::TestWithParam<AccuracyBound> {};

TEST_P(LearnedFitterAccuracy, CleanFullSegmentsWithinHeldOutBounds) {
  const AccuracyBound bound = GetParam();
  const auto fitter = make_learned_fitter();
  std::mt19937_64 random(500 + static_cast<int>(bound.type));
  const int rounds = 40;
  int axis_within = 0, scale_within = 0, centre_within = 0;
  std::vector<double> axis, scale, centre;
  for (int round = 0; round < rounds; ++round) {
    const Segment segment = clean_full_segment(bound.type, 2000, random);
    const QuadricFit fit = fitter->fit(segment.points, Eigen::Matrix3Xd(), bound.type);
    ASSERT_EQ(fit.status, FitStatus::Ok) << fit.message;
    ASSERT_EQ(fit.type, bound.type);
    ASSERT_EQ(fit.shape.type, bound.type);
    EXPECT_TRUE(std::isfinite(fit.algebraic_distance));
    const FitErrors errors = fit_errors(bound.type, segment, fit.shape);
    axis.push_back(errors.axis_deg);
    scale.push_back(errors.scale_rel);
    centre.push_back(errors.centre);
    axis_within += errors.axis_deg <= bound.axis_deg + 1e-12 ? 1 : 0;
    scale_within += errors.scale_rel <= bound.scale_rel + 1e-12 ? 1 : 0;
    centre_within += errors.centre <= bound.centre ? 1 : 0;
  }
  const auto median = [](std::vector<double> values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  // Per measure: the median sits below the held-out p90, and at least 3 of 4 segments are within it
  // (9 of 10 expected when C++ inference reproduces the training-time evaluation).
  const std::string summary = quadric_type_name(bound.type) + ": median axis " + std::to_string(median(axis)) +
                              " deg, scale " + std::to_string(median(scale)) + ", centre " + std::to_string(median(centre));
  EXPECT_LE(median(axis), bound.axis_deg + 1e-12) << summary;
  EXPECT_LE(median(scale), bound.scale_rel + 1e-12) << summary;
  EXPECT_LE(median(centre), bound.centre) << summary;
  EXPECT_GE(axis_within, rounds * 3 / 4) << summary;
  EXPECT_GE(scale_within, rounds * 3 / 4) << summary;
  EXPECT_GE(centre_within, rounds * 3 / 4) << summary;
  std::printf("%s; within p90: axis %d, scale %d, centre %d of %d\n", summary.c_str(), axis_within, scale_within,
              centre_within, rounds);
}

INSTANTIATE_TEST_SUITE_P(
    TrainedTypes, LearnedFitterAccuracy,
    // Held-out clean full p90 of the committed weights (1000 segments per type), rounded up.
    ::testing::Values(AccuracyBound{QuadricType::Plane, 0.86, 0.0, 0.0017},
                      AccuracyBound{QuadricType::Line, 0.75, 0.0, 0.022},
                      AccuracyBound{QuadricType::Sphere, 0.0, 0.0024, 0.023},
                      AccuracyBound{QuadricType::CircularCylinder, 13.9, 0.091, 0.114},
                      AccuracyBound{QuadricType::CircularCone, 11.1, 0.198, 1.07},
                      AccuracyBound{QuadricType::Ellipsoid, 0.0, 1.1, 0.066}),
    [](const auto& info) { return quadric_type_name(info.param.type); });

// ---------------------------------------------------------------------------------------------
// Sampling, normalisation and decoding rules.

TEST(LearnedFitterSample, StridesThroughLargeSegmentsAndRepeatsSmallOnes) {
  Eigen::Matrix3Xd points(3, 10);
  for (int i = 0; i < 10; ++i) points.col(i) = Eigen::Vector3d::Constant(i);
  const Eigen::Matrix3Xd strided = learned_fitter_sample(points, 4);  // floor(i * 10 / 4) = 0, 2, 5, 7
  EXPECT_EQ(strided(0, 0), 0.0);
  EXPECT_EQ(strided(0, 1), 2.0);
  EXPECT_EQ(strided(0, 2), 5.0);
  EXPECT_EQ(strided(0, 3), 7.0);
  const Eigen::Matrix3Xd repeated = learned_fitter_sample(points.leftCols(3), 7);  // i mod 3
  for (int i = 0; i < 7; ++i) EXPECT_EQ(repeated(0, i), static_cast<double>(i % 3));
  EXPECT_THROW(learned_fitter_sample(Eigen::Matrix3Xd(3, 0), 4), Error);
}

TEST(LearnedFitterNormalisation, UnitRmsRadiusPrincipalAxesAndPositiveSkew) {
  std::mt19937_64 random(42);
  const Segment segment = clean_full_segment(QuadricType::CircularCone, 500, random);
  const SegmentNormalisation frame = normalise_segment(segment.points);
  EXPECT_NEAR((frame.center - segment.points.rowwise().mean()).norm(), 0.0, 1e-9);
  EXPECT_NEAR((frame.rotation.transpose() * frame.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(frame.rotation.determinant(), 1.0, 1e-12);
  const Eigen::Matrix3Xd u = frame.rotation.transpose() * (segment.points.colwise() - frame.center) / frame.scale;
  EXPECT_NEAR(u.colwise().squaredNorm().mean(), 1.0, 1e-9);
  const Eigen::Vector3d variance = u.array().square().rowwise().mean();
  EXPECT_GE(variance(0), variance(1));
  EXPECT_GE(variance(1), variance(2));
  EXPECT_GE(u.row(0).array().cube().sum(), 0.0);
  EXPECT_GE(u.row(1).array().cube().sum(), 0.0);
}

TEST(LearnedFitterDecode, UndoesTheNormalisation) {
  SegmentNormalisation frame;
  frame.center = Eigen::Vector3d(1.0, -2.0, 3.0);
  frame.scale = 3.0;
  frame.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 2.0).normalized()).toRotationMatrix();
  Eigen::VectorXf sphere(4);
  sphere << 0.1f, 0.0f, -0.2f, static_cast<float>(std::log(2.0));
  const LearnedPrimitive decoded = decode_learned_outputs(QuadricType::Sphere, sphere, frame, 10.0);
  EXPECT_NEAR(decoded.scale(0), 6.0, 1e-5);
  const Eigen::Vector3d expected_center = frame.center + 3.0 * frame.rotation * Eigen::Vector3d(0.1, 0.0, -0.2);
  EXPECT_NEAR((decoded.pose.translation() - expected_center).norm(), 0.0, 1e-6);

  Eigen::VectorXf cylinder(7);  // axis along normalised x, point (0.5, 1, 0) -> foot (0, 1, 0), radius e^0 * 3
  cylinder << 2.0f, 0.0f, 0.0f, 0.5f, 1.0f, 0.0f, 0.0f;
  const LearnedPrimitive tube = decode_learned_outputs(QuadricType::CircularCylinder, cylinder, frame, 10.0);
  EXPECT_NEAR(std::abs(tube.pose.linear().col(2).dot(frame.rotation.col(0))), 1.0, 1e-12);
  EXPECT_NEAR(tube.pose.linear().determinant(), 1.0, 1e-12);
  EXPECT_NEAR((tube.pose.translation() - (frame.center + 3.0 * frame.rotation.col(1))).norm(), 0.0, 1e-6);
  EXPECT_NEAR(tube.scale(0), 3.0, 1e-6);
  EXPECT_NEAR(tube.scale(1), 3.0, 1e-6);

  Eigen::VectorXf plane(4);  // normal along normalised z, offset 0.5 -> plane through c + 1.5 e3
  plane << 0.0f, 0.0f, -4.0f, -0.5f;
  const LearnedPrimitive flat = decode_learned_outputs(QuadricType::Plane, plane, frame, 10.0);
  EXPECT_NEAR(std::abs(flat.pose.linear().col(0).dot(frame.rotation.col(2))), 1.0, 1e-12);
  EXPECT_NEAR((flat.pose.translation() - (frame.center + 1.5 * frame.rotation.col(2))).norm(), 0.0, 1e-6);

  Eigen::VectorXf zero_axis = Eigen::VectorXf::Zero(7);
  EXPECT_EQ(decode_learned_outputs(QuadricType::CircularCone, zero_axis, frame, 10.0).type, QuadricType::Invalid);
  EXPECT_THROW(decode_learned_outputs(QuadricType::Sphere, cylinder, frame, 10.0), Error);
  EXPECT_THROW(decode_learned_outputs(QuadricType::EllipticCone, cylinder, frame, 10.0), Error);
}

// ---------------------------------------------------------------------------------------------
// Statuses of the fitter.

TEST(LearnedFitter, StatusesForUnsupportedTypesTooFewAndCoincidentPoints) {
  const auto fitter = make_learned_fitter();
  EXPECT_EQ(fitter->name(), "learned");
  std::mt19937_64 random(43);
  const Segment segment = clean_full_segment(QuadricType::CircularCylinder, 300, random);
  const QuadricFit unsupported = fitter->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::EllipticCylinder);
  EXPECT_EQ(unsupported.status, FitStatus::Failed);
  EXPECT_THAT(unsupported.message, HasSubstr("no network for type elliptic_cylinder"));
  EXPECT_THAT(unsupported.message, HasSubstr("circular_cylinder"));
  EXPECT_EQ(fitter->fit(segment.points.leftCols(5), Eigen::Matrix3Xd(), QuadricType::Ellipsoid).status,
            FitStatus::TooFewPoints);
  const Eigen::Matrix3Xd same = Eigen::Vector3d(1.0, 2.0, 3.0).replicate(1, 50);
  const QuadricFit coincident = fitter->fit(same, Eigen::Matrix3Xd(), QuadricType::Sphere);
  EXPECT_EQ(coincident.status, FitStatus::Degenerate);
  // Without a hint the learned fitter fits an ellipsoid (geometry-only clusters, as the paper does).
  const QuadricFit automatic = fitter->fit(segment.points, Eigen::Matrix3Xd(), std::nullopt);
  EXPECT_EQ(automatic.status, FitStatus::Ok);
  EXPECT_EQ(automatic.type, QuadricType::Ellipsoid);
  // A segment fed with fewer points than N (repeated cyclically) still fits.
  const QuadricFit few = fitter->fit(segment.points.leftCols(40), Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(few.status, FitStatus::Ok);
}

// ---------------------------------------------------------------------------------------------
// Weight folder resolution and bad weight files.

class LearnedFitterFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    source_ = default_learned_fitter_directory();
    copy_ = fs::path(::testing::TempDir()) / ("quadrix_learned_" + std::string(::testing::UnitTest::GetInstance()
                                                                                   ->current_test_info()
                                                                                   ->name()));
    fs::remove_all(copy_);
    fs::create_directories(copy_);
    for (const auto& entry : fs::directory_iterator(source_)) fs::copy_file(entry.path(), copy_ / entry.path().filename());
  }
  void TearDown() override { fs::remove_all(copy_); }

  std::string manifest_text() const {
    std::ifstream stream(copy_ / "manifest.json");
    return std::string((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  }
  void write(const std::string& name, const std::string& bytes) const {
    std::ofstream stream(copy_ / name, std::ios::binary | std::ios::trunc);
    stream << bytes;
  }
  std::string load_error() const {
    try {
      load_learned_fitter_model(copy_.string());
    } catch (const Error& error) {
      return error.what();
    }
    return "no error";
  }

  std::string source_;
  fs::path copy_;
};

TEST_F(LearnedFitterFiles, CopiedFolderLoadsThroughOptionsAndEnvironment) {
  LearnedFitterOptions options;
  options.model_directory = copy_.string();
  EXPECT_EQ(make_learned_fitter(options)->name(), "learned");
  // The environment variable overrides the compiled-in default; options override both.
  ASSERT_EQ(setenv(kLearnedFitterDirectoryVariable, "/nonexistent/quadrix_weights", 1), 0);
  EXPECT_EQ(default_learned_fitter_directory(), "/nonexistent/quadrix_weights");
  try {
    make_learned_fitter();
    ADD_FAILURE() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("/nonexistent/quadrix_weights/manifest.json"));
  }
  EXPECT_NO_THROW(make_learned_fitter(options));
  ASSERT_EQ(unsetenv(kLearnedFitterDirectoryVariable), 0);
  EXPECT_EQ(default_learned_fitter_directory(), source_);
}

TEST_F(LearnedFitterFiles, MissingWeightFileIsNamed) {
  fs::remove(copy_ / "sphere_head_1_weight.npy");
  EXPECT_THAT(load_error(), HasSubstr("sphere_head_1_weight.npy: cannot open"));
}

TEST_F(LearnedFitterFiles, CorruptWeightFileIsNamed) {
  write("plane_shared_0_weight.npy", "this is not numpy");
  EXPECT_THAT(load_error(), HasSubstr("plane_shared_0_weight.npy: not a .npy file"));
}

TEST_F(LearnedFitterFiles, TruncatedWeightFileIsNamed) {
  std::ifstream stream(copy_ / "ellipsoid_head_0_weight.npy", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  stream.close();
  write("ellipsoid_head_0_weight.npy", bytes.substr(0, bytes.size() - 100));
  const std::string error = load_error();
  EXPECT_THAT(error, HasSubstr("ellipsoid_head_0_weight.npy"));
  EXPECT_THAT(error, HasSubstr("truncated or corrupt"));
}

TEST_F(LearnedFitterFiles, WrongDtypeIsNamed) {
  // A valid .npy header declaring float64 data.
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }";
  header.resize(117, ' ');
  header += '\n';
  std::string bytes = std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size()) + '\0' + header;
  bytes += std::string(16, '\0');
  write("line_head_2_bias.npy", bytes);
  EXPECT_THAT(load_error(), HasSubstr("line_head_2_bias.npy: dtype '<f8' is not little-endian float32"));
}

TEST_F(LearnedFitterFiles, ShapeDisagreeingWithManifestIsNamed) {
  // Swap two tensors of different shapes: the loader compares each file with the manifest.
  fs::copy_file(copy_ / "circular_cone_shared_1_weight.npy", copy_ / "circular_cone_shared_2_weight.npy",
                fs::copy_options::overwrite_existing);
  const std::string error = load_error();
  EXPECT_THAT(error, HasSubstr("circular_cone_shared_2_weight.npy: shape"));
  EXPECT_THAT(error, HasSubstr("differs from"));
}

TEST_F(LearnedFitterFiles, BrokenManifestIsNamed) {
  write("manifest.json", manifest_text().substr(0, 200));
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: invalid JSON"));
  write("manifest.json", "{\"format\": \"quadrix-learned-fitter\", \"version\": 1, \"num_points\": 128}");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: missing field 'log_clamp'"));
}

// ---------------------------------------------------------------------------------------------
// The auto policy: learned first for learned_types, statistical when f_p2s > delta_p (paper
// §"Quadric Fitting"); other types go straight to the statistical fit.

TEST(AutoFitter, UsesTheLearnedFitWhenItsAlgebraicDistanceIsSmall) {
  AutoFitterOptions options;
  options.learned_types = trained_types();
  const auto automatic = make_auto_fitter(options);
  const auto learned = make_quadric_fitter("learned");
  EXPECT_EQ(automatic->name(), "auto");
  std::mt19937_64 random(44);
  for (const QuadricType type : trained_types()) {
    const Segment segment = clean_full_segment(type, 1000, random);
    const QuadricFit expected = learned->fit(segment.points, Eigen::Matrix3Xd(), type);
    const QuadricFit fit = automatic->fit(segment.points, Eigen::Matrix3Xd(), type);
    ASSERT_EQ(expected.status, FitStatus::Ok);
    ASSERT_LE(expected.algebraic_distance, 0.5) << quadric_type_name(type);
    EXPECT_EQ(fit.status, FitStatus::Ok);
    EXPECT_THAT(fit.message, HasSubstr("auto: learned fit used"));
    EXPECT_EQ(fit.quadric.matrix(), expected.quadric.matrix());
  }
}

TEST(AutoFitter, FallsBackToStatisticalAboveDeltaP) {
  std::mt19937_64 random(45);
  const Segment segment = clean_full_segment(QuadricType::Sphere, 1000, random);
  const QuadricFit statistical = make_statistical_fitter()->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::Sphere);
  AutoFitterOptions options;
  options.learned_types = trained_types();
  options.delta_p = -1.0;  // every learned f_p2s (>= 0) exceeds it
  const QuadricFit fit = make_auto_fitter(options)->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::Sphere);
  EXPECT_EQ(fit.status, FitStatus::Ok);
  EXPECT_THAT(fit.message, HasSubstr("auto: statistical fit used (learned f_p2s = "));
  EXPECT_THAT(fit.message, HasSubstr("> delta_p = -1"));
  EXPECT_EQ(fit.quadric.matrix(), statistical.quadric.matrix());

  // Out of distribution for the paper's default delta_p: a plane network asked to fit a sphere.
  const QuadricFit wrong = make_learned_fitter()->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::Plane);
  AutoFitterOptions paper;
  paper.learned_types = trained_types();
  const QuadricFit policy = make_auto_fitter(paper)->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::Plane);
  if (wrong.algebraic_distance > 0.5)
    EXPECT_THAT(policy.message, HasSubstr("auto: statistical fit used"));
  else
    EXPECT_THAT(policy.message, HasSubstr("auto: learned fit used"));
}

TEST(AutoFitter, FallsBackToStatisticalForTypesWithoutANetwork) {
  std::mt19937_64 random(46);
  const Segment segment = clean_full_segment(QuadricType::CircularCylinder, 500, random);
  AutoFitterOptions options;
  options.learned_types = {QuadricType::EllipticCylinder};  // tried first, but no network was trained for it
  const QuadricFit fit = make_auto_fitter(options)->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::EllipticCylinder);
  EXPECT_EQ(fit.status, FitStatus::Ok);
  EXPECT_EQ(fit.type, QuadricType::EllipticCylinder);
  EXPECT_THAT(fit.message, HasSubstr("auto: statistical fit used (learned fit failed: "));
  EXPECT_THAT(fit.message, HasSubstr("no network for type elliptic_cylinder"));
}

TEST(AutoFitter, GoesStraightToStatisticalForTypesNotInLearnedTypes) {
  std::mt19937_64 random(47);
  const Segment segment = clean_full_segment(QuadricType::CircularCylinder, 500, random);
  const QuadricFit statistical =
      make_statistical_fitter()->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  AutoFitterOptions options;
  options.learned_types = {QuadricType::Sphere};
  const QuadricFit fit = make_auto_fitter(options)->fit(segment.points, Eigen::Matrix3Xd(), QuadricType::CircularCylinder);
  EXPECT_EQ(fit.status, FitStatus::Ok);
  EXPECT_THAT(fit.message, HasSubstr("auto: statistical fit used (the learned fitter is not tried for circular_cylinder"));
  EXPECT_EQ(fit.quadric.matrix(), statistical.quadric.matrix());
}

}  // namespace
}  // namespace quadrix
