// The paper's statistics-based fit (§"Quadric Fitting", steps 1-3):
//   1. centralisation  e_c = e - t_s;
//   2. eigen-decomposition of the covariance, sigma_s = sqrt(diag(Lambda_s)) in descending order;
//   3. s_s = k_s sigma_s, C_e = S^-T I_C S^-1, P_s = [R_s t_s; 0 1], Q = P_s^-T C_e P_s^-1.
// The paper leaves implicit which principal direction plays which canonical axis; we follow the
// canonical convention of geometry/quadric.h: a plane's normal (axis a) is the least-variance
// direction, a line/cylinder/cone axis (axis c) is the largest-variance direction.
#include "fitting/statistical_fitter.h"

#include <algorithm>
#include <chrono>

namespace quadrix {
namespace {

class StatisticalFitter final : public QuadricFitter {
 public:
  explicit StatisticalFitter(const StatisticalFitterOptions& options) : options_(options) {}

  std::string name() const override { return "statistical"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& /*normals*/, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    QuadricFit result;
    const QuadricType type = hint.value_or(options_.automatic_type);
    result.type = type;
    const auto finish = [&](QuadricFit& fit) -> QuadricFit& {
      fit.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return fit;
    };
    if (static_cast<std::size_t>(points.cols()) < minimum_points_for_type(type)) {
      result.status = FitStatus::TooFewPoints;
      result.message = "a " + quadric_type_name(type) + " needs at least " +
                       std::to_string(minimum_points_for_type(type)) + " points, got " + std::to_string(points.cols());
      return finish(result);
    }
    // Steps 1-2: t_s, R_s (descending variance, det +1) and s_s = k_s sigma_s.
    const StatisticalPose statistics = point_statistics(points, options_.scale_factor);
    result.statistics = statistics;
    const double largest_scale = statistics.scale.maxCoeff();
    if (!(largest_scale > 0.0)) {
      if (type != QuadricType::Point) {
        result.status = FitStatus::Degenerate;
        result.message = "all points coincide; only a point can be fitted";
        return finish(result);
      }
    }
    const Eigen::Vector3d scale =
        statistics.scale.cwiseMax(std::max(largest_scale * options_.minimum_relative_scale, 1e-12));
    if ((type == QuadricType::Plane || type == QuadricType::CircularCylinder || type == QuadricType::EllipticCylinder ||
         type == QuadricType::CircularCone || type == QuadricType::EllipticCone) &&
        statistics.scale(1) <= largest_scale * options_.minimum_relative_scale) {
      result.status = FitStatus::Degenerate;
      result.message = "the points are collinear; a " + quadric_type_name(type) + " is not determined";
      return finish(result);
    }

    // Step 3: map principal directions e1 (largest variance), e2, e3 onto canonical axes a, b, c.
    const Eigen::Matrix3d& directions = statistics.rotation;
    Eigen::Matrix3d axes = directions;
    Eigen::Vector3d canonical_scale = scale;
    switch (type) {
      case QuadricType::Plane:  // normal a = e3; cyclic permutation keeps det +1
        axes << directions.col(2), directions.col(0), directions.col(1);
        canonical_scale << scale(2), scale(0), scale(1);
        break;
      case QuadricType::Line:
      case QuadricType::CircularCylinder:
      case QuadricType::EllipticCylinder:
      case QuadricType::CircularCone:
      case QuadricType::EllipticCone:  // axis c = e1
        axes << directions.col(1), directions.col(2), directions.col(0);
        canonical_scale << scale(1), scale(2), scale(0);
        break;
      default:
        break;
    }
    // Symmetric types share one scale across their symmetric axes (the mean of the statistical ones).
    if (type == QuadricType::Sphere) canonical_scale.setConstant(canonical_scale.mean());
    if (type == QuadricType::CircularCylinder || type == QuadricType::CircularCone)
      canonical_scale.head<2>().setConstant(canonical_scale.head<2>().mean());
    // A cone's canonical form is x^2/a^2 + y^2/b^2 - z^2 = 0 with a, b the tangents of the half-angles:
    // the statistical cone takes the opening that passes through the k_s-sigma extents.
    if (type == QuadricType::CircularCone || type == QuadricType::EllipticCone) {
      canonical_scale.head<2>() /= canonical_scale(2);
      canonical_scale(2) = 1.0;
    }
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = axes;
    pose.translation() = statistics.center;
    result.quadric = Quadric::from_canonical(type, canonical_scale, pose);
    result.status = FitStatus::Ok;
    evaluate_fit(points, result, {}, options_.evaluation);
    return finish(result);
  }

 private:
  StatisticalFitterOptions options_;
};

}  // namespace

std::unique_ptr<QuadricFitter> make_statistical_fitter(const StatisticalFitterOptions& options) {
  return std::make_unique<StatisticalFitter>(options);
}

}  // namespace quadrix
