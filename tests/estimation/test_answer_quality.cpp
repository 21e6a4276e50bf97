// What a back end uses of an answer (estimation/answer_quality.h): fitness, inlier RMSE and the
// correspondence set against a brute-force evaluation, the information matrix against a numerical
// Hessian of the point-to-plane cost it stands for, its near-zero eigenvalue along a corridor, its
// growth with the inliers, and its move to another target origin. Scenes are sampled at random.
#include "estimation/answer_quality.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace quadrix {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

PointCloud cloud_of(const std::vector<Eigen::Vector3d>& points) {
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i].cast<float>();
  return cloud;
}

// A rectangle: corner + u * side_a + v * side_b, u and v uniform in [0, 1].
struct Rectangle {
  Eigen::Vector3d corner, side_a, side_b;
};

// `count` uniform samples over `rectangles` (chosen evenly), each moved by `pose`.
std::vector<Eigen::Vector3d> sample(const std::vector<Rectangle>& rectangles, std::size_t count, const Eigen::Isometry3d& pose,
                                    std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<std::size_t> pick(0, rectangles.size() - 1);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < count; ++i) {
    const Rectangle& r = rectangles[pick(rng)];
    points.push_back(pose * Eigen::Vector3d(r.corner + unit(rng) * r.side_a + unit(rng) * r.side_b));
  }
  return points;
}

// Plates of six orientations, far enough apart that every point's nearest target points lie on its
// own plate: each fitted normal is the plate's, and the residuals at the truth are float rounding.
std::vector<Rectangle> separated_plates() {
  return {{{-20, -20, 0}, {6, 0, 0}, {0, 6, 0}},       {{10, -15, 0}, {0, 0, 5}, {0, 6, 0}},
          {{-15, 10, 0}, {6, 0, 0}, {0, 0, 5}},       {{12, 12, 2}, {4, 4, 0}, {0, 0, 5}},
          {{-5, -5, 8}, {5, 0, 3}, {0, 5, 0}},        {{0, 20, -5}, {0, 5, 2}, {5, 0, 0}}};
}

Eigen::Isometry3d pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  transform.translation() = translation;
  return transform;
}

TEST(AnswerQuality, FitnessRmseAndCorrespondencesAreOpen3dsEvaluation) {
  std::mt19937 rng(71);
  const Eigen::Isometry3d truth = pose(0.4, {1, 2, 3}, {2.0, -1.0, 0.5});
  // The source covers more than the target: only part of it can be inlier.
  std::vector<Rectangle> plates = separated_plates();
  const std::vector<Eigen::Vector3d> target_points = sample({plates.begin(), plates.begin() + 4}, 1500, Eigen::Isometry3d::Identity(), rng);
  const std::vector<Eigen::Vector3d> source_points = sample(plates, 800, truth.inverse(), rng);
  const PointCloud source = cloud_of(source_points), target = cloud_of(target_points);
  AnswerQualityOptions options;
  options.correspondence_distance = 0.25;
  const AnswerQuality quality = measure_answer_quality(source, target, truth, options);
  // Brute force: every source point's nearest target point.
  std::size_t inliers = 0;
  double squared = 0.0;
  std::size_t k = 0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d moved = truth * source.point(i);
    std::size_t nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < target.size(); ++j) {
      const double d = (moved - target.point(j)).norm();
      if (d < best) best = d, nearest = j;
    }
    if (best > options.correspondence_distance) continue;
    ++inliers;
    squared += best * best;
    ASSERT_LT(k, quality.correspondences.size());
    EXPECT_EQ(quality.correspondences[k].first, i);
    EXPECT_EQ(quality.correspondences[k].second, nearest);
    ++k;
  }
  EXPECT_EQ(quality.correspondences.size(), inliers);
  EXPECT_EQ(quality.normals.size(), inliers);
  EXPECT_GT(inliers, 300u);
  EXPECT_LT(inliers, 700u);  // the plates the target lacks hold a third of the source
  EXPECT_NEAR(quality.fitness, static_cast<double>(inliers) / static_cast<double>(source.size()), 1e-12);
  EXPECT_NEAR(quality.inlier_rmse, std::sqrt(squared / static_cast<double>(inliers)), 1e-9);
}

TEST(AnswerQuality, InformationIsTheNumericalHessianOfThePointToPlaneCost) {
  std::mt19937 rng(72);
  for (int round = 0; round < 3; ++round) {
    std::uniform_real_distribution<double> shift(-5.0, 5.0);
    const Eigen::Isometry3d truth = pose(0.3 + 0.4 * round, {shift(rng), shift(rng), 3.0}, {shift(rng), shift(rng), shift(rng)});
    const PointCloud target = cloud_of(sample(separated_plates(), 6000, Eigen::Isometry3d::Identity(), rng));
    const PointCloud source = cloud_of(sample(separated_plates(), 3000, truth.inverse(), rng));
    const AnswerQuality quality = measure_answer_quality(source, target, truth);
    ASSERT_GT(quality.correspondences.size(), 2500u);
    for (const Eigen::Vector3d& normal : quality.normals) ASSERT_NEAR(normal.norm(), 1.0, 1e-9);
    // Central differences of E(δ) at 0, step h: E is quadratic up to the rotation's curvature
    // times residuals that are float rounding here, so the difference quotient is H.
    const double h = 1e-4;
    const auto cost = [&](const Vector6d& delta) {
      return point_to_plane_cost(source, target, truth, quality.correspondences, quality.normals, delta);
    };
    EXPECT_LT(cost(Vector6d::Zero()), 1e-8 * static_cast<double>(quality.correspondences.size()));
    Matrix6d numerical;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) {
        const Vector6d a = h * Vector6d::Unit(i), b = h * Vector6d::Unit(j);
        numerical(i, j) = (cost(a + b) - cost(a - b) - cost(-a + b) + cost(-a - b)) / (4.0 * h * h);
      }
    const double relative = (numerical - quality.information).norm() / quality.information.norm();
    EXPECT_LT(relative, 1e-3) << "information\n" << quality.information << "\nnumerical Hessian\n" << numerical;
    EXPECT_TRUE(quality.information.isApprox(quality.information.transpose(), 1e-12));
    const Eigen::SelfAdjointEigenSolver<Matrix6d> solver(quality.information);
    EXPECT_GT(solver.eigenvalues()(0), 0.0);
    // Six plate orientations fix every translation (rotations are weighed by squared lever arms,
    // so their eigenvalues are on another scale).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> translations(quality.information.bottomRightCorner<3, 3>());
    EXPECT_GT(translations.eigenvalues()(0), 0.05 * translations.eigenvalues()(2));
  }
}

TEST(AnswerQuality, InformationGrowsWithTheInliersAndIsPositiveSemiDefinite) {
  std::mt19937 rng(73);
  const Eigen::Isometry3d truth = pose(0.5, {0, 0, 1}, {3.0, 1.0, 0.0});
  const PointCloud target = cloud_of(sample(separated_plates(), 20000, Eigen::Isometry3d::Identity(), rng));
  const PointCloud sparse = cloud_of(sample(separated_plates(), 2000, truth.inverse(), rng));
  const PointCloud dense = cloud_of(sample(separated_plates(), 4000, truth.inverse(), rng));
  const AnswerQuality few = measure_answer_quality(sparse, target, truth);
  const AnswerQuality many = measure_answer_quality(dense, target, truth);
  const double inlier_ratio = static_cast<double>(many.correspondences.size()) / static_cast<double>(few.correspondences.size());
  EXPECT_NEAR(inlier_ratio, 2.0, 0.1);
  // The same scene sampled twice as densely: each entry is a sum over inliers, twice as many.
  EXPECT_NEAR(many.information.trace() / few.information.trace(), inlier_ratio, 0.1 * inlier_ratio);
  for (const AnswerQuality* quality : {&few, &many}) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> solver(quality->information);
    EXPECT_GE(solver.eigenvalues()(0), -1e-9 * solver.eigenvalues()(5));
  }
}

TEST(AnswerQuality, SampledInformationEstimatesTheFullSum) {
  // The information from evenly spaced inliers, weighed by inliers / sampled, estimates the sum over
  // every inlier: on three random scenes with 12,000 inliers and 1,000 samples, its entries stay
  // within 10% of the full sum's (Frobenius norm), and so does its smallest eigenvalue.
  std::mt19937 rng(74);
  for (int round = 0; round < 3; ++round) {
    const Eigen::Isometry3d truth = pose(0.2 + 0.5 * round, {0, 0, 1}, {1.0 * round, -2.0, 0.5});
    const PointCloud target = cloud_of(sample(separated_plates(), 30000, Eigen::Isometry3d::Identity(), rng));
    const PointCloud source = cloud_of(sample(separated_plates(), 12000, truth.inverse(), rng));
    AnswerQualityOptions every;
    every.information_samples = 0;
    AnswerQualityOptions sampled;
    sampled.information_samples = 1000;
    const AnswerQuality full = measure_answer_quality(source, target, truth, every);
    const AnswerQuality estimate = measure_answer_quality(source, target, truth, sampled);
    ASSERT_GT(full.correspondences.size(), 10000u);
    EXPECT_EQ(estimate.correspondences, full.correspondences);
    EXPECT_DOUBLE_EQ(full.information_weight, 1.0);
    EXPECT_GT(estimate.information_weight, 10.0);
    EXPECT_LT((estimate.information - full.information).norm(), 0.1 * full.information.norm());
    const Eigen::SelfAdjointEigenSolver<Matrix6d> full_solver(full.information), estimate_solver(estimate.information);
    EXPECT_NEAR(estimate_solver.eigenvalues()(0), full_solver.eigenvalues()(0), 0.1 * full_solver.eigenvalues()(0));
  }
}

TEST(AnswerQuality, ACorridorLeavesANearZeroEigenvalueAlongItself) {
  std::mt19937 rng(74);
  // A corridor along x: floor, ceiling and two walls, 100 m long, open at both ends.
  const std::vector<Rectangle> corridor = {{{-50, -2, 0}, {100, 0, 0}, {0, 4, 0}},
                                           {{-50, -2, 3}, {100, 0, 0}, {0, 4, 0}},
                                           {{-50, -2, 0}, {100, 0, 0}, {0, 0, 3}},
                                           {{-50, 2, 0}, {100, 0, 0}, {0, 0, 3}}};
  const Eigen::Isometry3d truth = pose(0.05, {0, 0, 1}, {0.5, 0.1, 0.0});
  const PointCloud target = cloud_of(sample(corridor, 40000, Eigen::Isometry3d::Identity(), rng));
  // The source sees the middle of the corridor only, so every source point has its target.
  std::vector<Eigen::Vector3d> seen;
  for (const Eigen::Vector3d& p : sample(corridor, 20000, Eigen::Isometry3d::Identity(), rng))
    if (std::abs(p.x()) < 30.0) seen.push_back(truth.inverse() * p);
  const PointCloud source = cloud_of(seen);
  const AnswerQuality quality = measure_answer_quality(source, target, truth);
  EXPECT_GT(quality.fitness, 0.95);
  const Matrix6d& information = quality.information;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> solver(information);
  const Vector6d eigenvalues = solver.eigenvalues();
  // Rotations are weighed by lever arms (metres squared), so the scale is the translations' own:
  // the least held of across (y) and up (z).
  const double held = std::min(information(4, 4), information(5, 5));
  // The weakest direction is the translation along the corridor (x), and it carries next to
  // nothing: only the normals fitted across the corridor's edges lean along it (measured: 0.8% of
  // the least-held other translation, against 100% for a direction the walls hold).
  EXPECT_LT(information(3, 3), 0.02 * held) << information;
  EXPECT_LT(eigenvalues(0), 0.02 * held) << eigenvalues.transpose();
  EXPECT_GT(std::abs(solver.eigenvectors()(3, 0)), 0.99) << solver.eigenvectors().col(0).transpose();
  // Every other direction is held: the next eigenvalue is far from zero.
  EXPECT_GT(eigenvalues(1), 1e-2 * held) << eigenvalues.transpose();
}

TEST(AnswerQuality, InformationAboutAShiftedTargetOriginMatchesMeasuringThere) {
  std::mt19937 rng(75);
  const Eigen::Isometry3d truth = pose(0.7, {1, -1, 2}, {1.0, 2.0, 0.3});
  const std::vector<Eigen::Vector3d> target_points = sample(separated_plates(), 5000, Eigen::Isometry3d::Identity(), rng);
  const PointCloud source = cloud_of(sample(separated_plates(), 2000, truth.inverse(), rng));
  // The target file's frame: the same points with the sensor at `origin` (centred_on_sensor subtracts it).
  const Eigen::Vector3d origin(40.0, -25.0, 3.0);
  std::vector<Eigen::Vector3d> shifted;
  for (const Eigen::Vector3d& p : target_points) shifted.push_back(p + origin);
  const AnswerQuality in_sensor_frame = measure_answer_quality(source, cloud_of(target_points), truth);
  const AnswerQuality in_file_frame =
      measure_answer_quality(source, cloud_of(shifted), Eigen::Translation3d(origin) * truth);
  ASSERT_EQ(in_sensor_frame.correspondences.size(), in_file_frame.correspondences.size());
  const Matrix6d moved = information_about_shifted_origin(in_sensor_frame.information, origin);
  // Float positions 40 m out round to a few micrometres: agreement to 1e-4 relative.
  EXPECT_LT((moved - in_file_frame.information).norm() / in_file_frame.information.norm(), 1e-4);
}

TEST(AnswerQuality, EmptyCloudsAndBadOptions) {
  const PointCloud empty;
  const PointCloud some = cloud_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const AnswerQuality none = measure_answer_quality(empty, some, Eigen::Isometry3d::Identity());
  EXPECT_EQ(none.fitness, 0.0);
  EXPECT_TRUE(none.correspondences.empty());
  EXPECT_TRUE(none.information.isZero());
  EXPECT_EQ(measure_answer_quality(some, empty, Eigen::Isometry3d::Identity()).fitness, 0.0);
  AnswerQualityOptions bad;
  bad.correspondence_distance = 0.0;
  EXPECT_THROW(measure_answer_quality(some, some, Eigen::Isometry3d::Identity(), bad), Error);
  bad = {};
  bad.normal_neighbours = 2;
  EXPECT_THROW(measure_answer_quality(some, some, Eigen::Isometry3d::Identity(), bad), Error);
}

}  // namespace
}  // namespace quadrix
