// Pose graph in Ceres: translation (R^3) and quaternion (ceres::EigenQuaternionManifold, Ceres 2.1)
// blocks per pose, an autodiff relative-pose cost per edge weighted by the square root of its
// information, and the robust kernels of quadric_distance.h as ceres::LossFunctions.
#include "estimation/pose_graph.h"

#include "estimation/quadric_distance.h"
#include "geometry/error.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>

namespace quadrix {
namespace {

/// e = [2 vec(q_est q_z^-1); p_est - p_z] with T_est = T_to^-1 T_from, the quaternion product taken
/// in the hemisphere of w >= 0 so that a full turn is no error.
template <typename T>
Eigen::Matrix<T, 6, 1> relative_error(const Eigen::Matrix<T, 3, 1>& p_from, const Eigen::Quaternion<T>& q_from,
                                      const Eigen::Matrix<T, 3, 1>& p_to, const Eigen::Quaternion<T>& q_to,
                                      const Eigen::Vector3d& p_z, const Eigen::Quaterniond& q_z) {
  const Eigen::Quaternion<T> q_to_inverse = q_to.conjugate();
  const Eigen::Quaternion<T> q_estimate = q_to_inverse * q_from;
  const Eigen::Matrix<T, 3, 1> p_estimate = q_to_inverse * (p_from - p_to);
  Eigen::Quaternion<T> delta = q_estimate * q_z.conjugate().template cast<T>();
  if (delta.w() < T(0)) delta.coeffs() = -delta.coeffs();
  Eigen::Matrix<T, 6, 1> error;
  error.template head<3>() = T(2) * delta.vec();
  error.template tail<3>() = p_estimate - p_z.template cast<T>();
  return error;
}

/// The weighted residual S e of one edge, S^T S = Ω.
struct RelativePoseCost {
  Eigen::Vector3d p_z;
  Eigen::Quaterniond q_z;
  Eigen::Matrix<double, 6, 6> root_information;

  template <typename T>
  bool operator()(const T* p_from, const T* q_from, const T* p_to, const T* q_to, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> pa(p_from), pb(p_to);
    const Eigen::Map<const Eigen::Quaternion<T>> qa(q_from), qb(q_to);
    const Eigen::Matrix<T, 6, 1> error = relative_error<T>(pa, Eigen::Quaternion<T>(qa), pb, Eigen::Quaternion<T>(qb), p_z, q_z);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> weighted(residual);
    weighted = root_information.template cast<T>() * error;
    return true;
  }
};

/// A robust kernel of quadric_distance.h (evaluate_robust_loss, shared with the refiners) as a Ceres
/// loss on s = χ²: DCS (Agarwal et al. 2013) or Huber.
class KernelLoss final : public ceres::LossFunction {
 public:
  KernelLoss(RobustLoss kernel, double scale) : kernel_(kernel), scale_(scale) {}
  void Evaluate(double s, double rho[3]) const override {
    const LossValue value = evaluate_robust_loss(kernel_, scale_, s);
    rho[0] = value.rho;
    rho[1] = value.derivative;
    rho[2] = value.second;
  }

 private:
  RobustLoss kernel_;
  double scale_;
};

Eigen::Matrix<double, 6, 6> root_of(const Information6d& information, std::size_t edge) {
  if (!information.allFinite()) throw Error("pose graph: edge " + std::to_string(edge) + " has a non-finite information matrix");
  if ((information - information.transpose()).cwiseAbs().maxCoeff() > 1e-6 * std::max(1.0, information.cwiseAbs().maxCoeff()))
    throw Error("pose graph: edge " + std::to_string(edge) + " has an information matrix that is not symmetric");
  const Eigen::SelfAdjointEigenSolver<Information6d> solver(0.5 * (information + information.transpose()));
  const Eigen::Matrix<double, 6, 1> values = solver.eigenvalues();
  if (values.minCoeff() < -1e-9 * std::max(1.0, values.maxCoeff()))
    throw Error("pose graph: edge " + std::to_string(edge) + " has an information matrix that is not positive semi-definite");
  return values.cwiseMax(0.0).cwiseSqrt().asDiagonal() * solver.eigenvectors().transpose();
}

double edge_chi2(const std::vector<Eigen::Isometry3d>& poses, const PoseGraphEdge& edge) {
  const Eigen::Matrix<double, 6, 1> error = pose_graph_error(poses[edge.from], poses[edge.to], edge.measurement);
  return error.dot(edge.information * error);
}

}  // namespace

Eigen::Matrix<double, 6, 1> pose_graph_error(const Eigen::Isometry3d& from_pose, const Eigen::Isometry3d& to_pose,
                                             const Eigen::Isometry3d& measurement) {
  const Eigen::Vector3d p_from = from_pose.translation(), p_to = to_pose.translation();
  return relative_error<double>(p_from, Eigen::Quaterniond(from_pose.rotation()), p_to, Eigen::Quaterniond(to_pose.rotation()),
                                measurement.translation(), Eigen::Quaterniond(measurement.rotation()));
}

double dcs_scale(double chi2, double phi) { return std::min(1.0, 2.0 * phi / (phi + chi2)); }

std::vector<std::size_t> pose_graph_components(std::size_t pose_count, const std::vector<PoseGraphEdge>& edges) {
  std::vector<std::size_t> parent(pose_count);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  const auto find = [&](std::size_t index) {
    while (parent[index] != index) index = parent[index] = parent[parent[index]];
    return index;
  };
  for (const PoseGraphEdge& edge : edges) {
    if (edge.from >= pose_count || edge.to >= pose_count) continue;
    const std::size_t a = find(edge.from), b = find(edge.to);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is the smallest pose of the component
  }
  std::vector<std::size_t> component(pose_count), number(pose_count, pose_count);
  std::size_t next = 0;
  for (std::size_t index = 0; index < pose_count; ++index) {
    const std::size_t root = find(index);
    if (number[root] == pose_count) number[root] = next++;
    component[index] = number[root];
  }
  return component;
}

PoseGraphSummary optimise_pose_graph(std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                     const PoseGraphOptions& options) {
  if (!(options.dcs_phi > 0.0)) throw Error("pose graph: dcs_phi must be positive");
  if (!(options.huber_threshold > 0.0)) throw Error("pose graph: huber_threshold must be positive");
  PoseGraphSummary summary;
  std::vector<Eigen::Matrix<double, 6, 6>> roots;
  roots.reserve(edges.size());
  for (std::size_t index = 0; index < edges.size(); ++index) {
    const PoseGraphEdge& edge = edges[index];
    if (edge.from >= poses.size() || edge.to >= poses.size())
      throw Error("pose graph: edge " + std::to_string(index) + " joins poses " + std::to_string(edge.from) + " and " +
                  std::to_string(edge.to) + ", but there are " + std::to_string(poses.size()));
    if (edge.from == edge.to) throw Error("pose graph: edge " + std::to_string(index) + " joins pose " + std::to_string(edge.from) + " to itself");
    roots.push_back(root_of(edge.information, index));
  }
  summary.component = pose_graph_components(poses.size(), edges);
  std::size_t components = 0;
  for (std::size_t value : summary.component) components = std::max(components, value + 1);
  summary.gauges.assign(components, poses.size());
  for (std::size_t index = 0; index < poses.size(); ++index)
    if (summary.gauges[summary.component[index]] == poses.size()) summary.gauges[summary.component[index]] = index;

  const auto total_cost = [&](std::vector<double>& chi2) {
    double cost = 0.0;
    chi2.resize(edges.size());
    for (std::size_t index = 0; index < edges.size(); ++index) {
      chi2[index] = edge_chi2(poses, edges[index]);
      const double value = chi2[index];
      cost += 0.5 * (edges[index].switchable ? evaluate_robust_loss(RobustLoss::Dcs, options.dcs_phi, value).rho
                     : edges[index].robust   ? evaluate_robust_loss(RobustLoss::Huber, options.huber_threshold, value).rho
                                             : value);
    }
    return cost;
  };
  summary.initial_cost = total_cost(summary.initial_chi2);

  std::vector<std::array<double, 3>> translations(poses.size());
  std::vector<std::array<double, 4>> rotations(poses.size());  // x, y, z, w: Eigen's storage order
  for (std::size_t index = 0; index < poses.size(); ++index) {
    Eigen::Map<Eigen::Vector3d>(translations[index].data()) = poses[index].translation();
    Eigen::Map<Eigen::Quaterniond>(rotations[index].data()) = Eigen::Quaterniond(poses[index].rotation()).normalized();
  }
  const bool any_switchable = std::any_of(edges.begin(), edges.end(), [](const PoseGraphEdge& edge) { return edge.switchable; });
  const int stages = any_switchable ? 2 : 1;
  for (int stage = 0; stage < stages && !edges.empty(); ++stage) {
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    ceres::EigenQuaternionManifold quaternion_manifold;
    for (std::size_t index = 0; index < edges.size(); ++index) {
      const PoseGraphEdge& edge = edges[index];
      if (edge.switchable && stage == 0) continue;
      auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 3, 4, 3, 4>(new RelativePoseCost{
          edge.measurement.translation(), Eigen::Quaterniond(edge.measurement.rotation()).normalized(), roots[index]});
      ceres::LossFunction* loss = nullptr;
      if (edge.switchable) loss = new KernelLoss(RobustLoss::Dcs, options.dcs_phi);
      else if (edge.robust) loss = new KernelLoss(RobustLoss::Huber, options.huber_threshold);
      problem.AddResidualBlock(cost, loss, translations[edge.from].data(), rotations[edge.from].data(), translations[edge.to].data(),
                               rotations[edge.to].data());
    }
    for (std::size_t index = 0; index < poses.size(); ++index) {
      if (!problem.HasParameterBlock(rotations[index].data())) continue;
      problem.SetManifold(rotations[index].data(), &quaternion_manifold);
      if (summary.gauges[summary.component[index]] == index) {
        problem.SetParameterBlockConstant(translations[index].data());
        problem.SetParameterBlockConstant(rotations[index].data());
      }
    }
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver_options.max_num_iterations = options.maximum_iterations;
    solver_options.function_tolerance = options.function_tolerance;
    solver_options.num_threads = 1;
    ceres::Solver::Summary solved;
    ceres::Solve(solver_options, &problem, &solved);
    summary.iterations += static_cast<int>(solved.iterations.size());
    summary.converged = solved.termination_type == ceres::CONVERGENCE;
    summary.report += (summary.report.empty() ? "" : " | ") + solved.BriefReport();
  }
  for (std::size_t index = 0; index < poses.size(); ++index) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Map<const Eigen::Quaterniond>(rotations[index].data()).normalized().toRotationMatrix();
    pose.translation() = Eigen::Map<const Eigen::Vector3d>(translations[index].data());
    poses[index] = pose;
  }
  summary.final_cost = total_cost(summary.final_chi2);
  summary.final_scale.resize(edges.size());
  for (std::size_t index = 0; index < edges.size(); ++index)
    summary.final_scale[index] = edges[index].switchable ? dcs_scale(summary.final_chi2[index], options.dcs_phi) : 1.0;
  return summary;
}

namespace {

/// Median of `values` (the upper middle one for an even count); 0 when empty.
double median_of(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// `pose` moved by a tangent step: translation + step.head(3), rotation exp(step.tail(3)) R.
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& pose, const Eigen::Matrix<double, 6, 1>& step) {
  Eigen::Isometry3d moved = pose;
  moved.translation() += step.head<3>();
  const double angle = step.tail<3>().norm();
  if (angle > 0.0) moved.linear() = Eigen::AngleAxisd(angle, step.tail<3>() / angle).toRotationMatrix() * pose.rotation();
  return moved;
}

}  // namespace

std::vector<EdgeRedundancy> edge_redundancies(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                              const PoseGraphOptions& options) {
  const std::size_t count = poses.size();
  for (std::size_t k = 0; k < edges.size(); ++k)
    if (edges[k].from >= count || edges[k].to >= count || edges[k].from == edges[k].to)
      throw Error("edge_redundancies: edge " + std::to_string(k) + " names a pose that does not exist or joins a pose to itself");
  // Gauge: the first pose of each connected component stays fixed, as in optimise_pose_graph.
  const std::vector<std::size_t> component = pose_graph_components(count, edges);
  std::vector<std::ptrdiff_t> column(count, -1);
  std::vector<bool> gauge_taken(count, false);
  Eigen::Index unknowns = 0;
  for (std::size_t pose = 0; pose < count; ++pose) {
    if (!gauge_taken[component[pose]]) {
      gauge_taken[component[pose]] = true;
      continue;
    }
    column[pose] = unknowns;
    unknowns += 6;
  }
  // Each edge's Jacobian (central differences on the tangent steps of both poses) and weight W = ρ'(χ²) Ω.
  constexpr double kStep = 1e-6;
  std::vector<Eigen::Matrix<double, 6, 12>> jacobians(edges.size());
  std::vector<Information6d> weights(edges.size());
  std::vector<Eigen::Triplet<double>> triplets;
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& edge = edges[k];
    const Eigen::Matrix<double, 6, 1> error = pose_graph_error(poses[edge.from], poses[edge.to], edge.measurement);
    const double chi2 = error.dot(edge.information * error);
    const double weight = edge.switchable ? evaluate_robust_loss(RobustLoss::Dcs, options.dcs_phi, chi2).derivative
                          : edge.robust   ? evaluate_robust_loss(RobustLoss::Huber, options.huber_threshold, chi2).derivative
                                          : 1.0;
    weights[k] = weight * edge.information;
    for (int side = 0; side < 2; ++side)
      for (int axis = 0; axis < 6; ++axis) {
        Eigen::Matrix<double, 6, 1> step = Eigen::Matrix<double, 6, 1>::Zero();
        step[axis] = kStep;
        const bool from_side = side == 0;
        const auto error_at = [&](const Eigen::Matrix<double, 6, 1>& delta) {
          return pose_graph_error(from_side ? perturbed(poses[edge.from], delta) : poses[edge.from],
                                  from_side ? poses[edge.to] : perturbed(poses[edge.to], delta), edge.measurement);
        };
        jacobians[k].col(6 * side + axis) = (error_at(step) - error_at(-step)) / (2.0 * kStep);
      }
    const Eigen::Matrix<double, 12, 12> block = jacobians[k].transpose() * weights[k] * jacobians[k];
    const std::array<std::ptrdiff_t, 2> columns = {column[edge.from], column[edge.to]};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        if (columns[a] < 0 || columns[b] < 0) continue;
        for (int row = 0; row < 6; ++row)
          for (int col = 0; col < 6; ++col)
            triplets.emplace_back(columns[a] + row, columns[b] + col, block(6 * a + row, 6 * b + col));
      }
  }
  std::vector<EdgeRedundancy> redundancy(edges.size());
  if (unknowns == 0) return redundancy;  // every pose a gauge: nothing is estimated, every residual is the measurement's own
  Eigen::SparseMatrix<double> normal(unknowns, unknowns);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  // Sparse Cholesky of the normal matrix; the covariance blocks each edge needs come from solving for
  // the six unit columns of each pose (the full inverse is dense, the blocks are not).
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(normal);
  if (factor.info() != Eigen::Success) throw Error("edge_redundancies: the normal matrix of the graph is singular");
  std::vector<Eigen::Matrix<double, 6, 6>> diagonal(count, Eigen::Matrix<double, 6, 6>::Zero());
  std::vector<Eigen::Matrix<double, 6, 6>> cross(edges.size(), Eigen::Matrix<double, 6, 6>::Zero());  // C(to, from)
  std::vector<std::vector<std::size_t>> edges_from(count);
  for (std::size_t k = 0; k < edges.size(); ++k) edges_from[edges[k].from].push_back(k);
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(unknowns, 6);
  for (std::size_t pose = 0; pose < count; ++pose) {
    if (column[pose] < 0) continue;
    unit.block(column[pose], 0, 6, 6).setIdentity();
    const Eigen::MatrixXd solved = factor.solve(unit);
    unit.block(column[pose], 0, 6, 6).setZero();
    diagonal[pose] = solved.block(column[pose], 0, 6, 6);
    for (const std::size_t k : edges_from[pose])
      if (column[edges[k].to] >= 0) cross[k] = solved.block(column[edges[k].to], 0, 6, 6);
  }
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& edge = edges[k];
    Eigen::Matrix<double, 12, 12> covariance;
    covariance << diagonal[edge.from], cross[k].transpose(), cross[k], diagonal[edge.to];
    // Covariance of the estimated relative pose J C Jᵀ; r = 3 - tr(W_bb (J C Jᵀ)_bb) per block b.
    const Information6d fitted = jacobians[k] * covariance * jacobians[k].transpose();
    redundancy[k].rotation = 3.0 - (weights[k].topLeftCorner<3, 3>() * fitted.topLeftCorner<3, 3>()).trace();
    redundancy[k].translation = 3.0 - (weights[k].bottomRightCorner<3, 3>() * fitted.bottomRightCorner<3, 3>()).trace();
    // A zero pivot (a pose no edge's information reaches) leaves the factorisation "successful" and
    // the covariance infinite.
    if (!std::isfinite(redundancy[k].rotation) || !std::isfinite(redundancy[k].translation))
      throw Error("edge_redundancies: the normal matrix of the graph is singular (edge " + std::to_string(k) + ")");
  }
  return redundancy;
}

namespace {

// A block this little redundant is fixed by its own measurement: its residual says nothing.
constexpr double kMinimumRedundancy = 0.05;

// χ² of an edge's rotation and translation blocks at `poses`, each under its diagonal block of the information.
std::pair<double, double> block_chi2(const std::vector<Eigen::Isometry3d>& poses, const PoseGraphEdge& edge) {
  const Eigen::Matrix<double, 6, 1> error = pose_graph_error(poses[edge.from], poses[edge.to], edge.measurement);
  return {error.head<3>().dot(edge.information.topLeftCorner<3, 3>() * error.head<3>()),
          error.tail<3>().dot(edge.information.bottomRightCorner<3, 3>() * error.tail<3>())};
}

}  // namespace

std::vector<VarianceFactors> estimate_variance_factors(const std::vector<Eigen::Isometry3d>& poses,
                                                       const std::vector<PoseGraphEdge>& edges,
                                                       const std::vector<std::size_t>& group, std::size_t group_count,
                                                       const std::vector<std::size_t>& pool, std::size_t minimum_edges,
                                                       const PoseGraphOptions& options) {
  if (group.size() != edges.size())
    throw Error("estimate_variance_factors: " + std::to_string(group.size()) + " group indices for " +
                std::to_string(edges.size()) + " edges");
  if (pool.size() != group_count) throw Error("estimate_variance_factors: one pool per group expected");
  for (std::size_t k = 0; k < edges.size(); ++k)
    if (group[k] >= group_count) throw Error("estimate_variance_factors: edge " + std::to_string(k) + " names no group");
  // Median of χ² with 3 degrees of freedom: the robust estimate's reference.
  constexpr double kChi2ThreeMedian = 2.365974;
  const std::vector<EdgeRedundancy> redundancy = edge_redundancies(poses, edges, options);
  std::vector<std::vector<double>> rotation(group_count), translation(group_count);
  std::vector<std::size_t> members(group_count, 0);
  std::map<std::size_t, std::pair<std::vector<double>, std::vector<double>>> pooled;
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& edge = edges[k];
    if (edge.switchable) continue;
    ++members[group[k]];
    const auto [rotation_chi2, translation_chi2] = block_chi2(poses, edge);
    auto& [pool_rotation, pool_translation] = pooled[pool[group[k]]];
    // Each block's χ² over its share of the 3 degrees of freedom the graph left it (E[χ²] = σ² r).
    if (redundancy[k].rotation > kMinimumRedundancy) {
      const double normalised = 3.0 / redundancy[k].rotation * rotation_chi2;
      rotation[group[k]].push_back(normalised);
      pool_rotation.push_back(normalised);
    }
    if (redundancy[k].translation > kMinimumRedundancy) {
      const double normalised = 3.0 / redundancy[k].translation * translation_chi2;
      translation[group[k]].push_back(normalised);
      pool_translation.push_back(normalised);
    }
  }
  std::vector<VarianceFactors> factors(group_count);
  for (std::size_t g = 0; g < group_count; ++g) {
    VarianceFactors& factor = factors[g];
    factor.edges = members[g];
    if (factor.edges == 0) continue;
    factor.pooled = factor.edges < minimum_edges;
    const auto& [pool_rotation, pool_translation] = pooled[pool[g]];
    const std::vector<double>& rotation_values = factor.pooled ? pool_rotation : rotation[g];
    const std::vector<double>& translation_values = factor.pooled ? pool_translation : translation[g];
    // A median this small is rounding, not a measured variance (every residual zero).
    constexpr double kUnmeasured = 1e-12;
    const double median_rotation = median_of(rotation_values), median_translation = median_of(translation_values);
    factor.measured = median_rotation > kUnmeasured && median_translation > kUnmeasured;
    if (median_rotation > kUnmeasured) factor.rotation = median_rotation / kChi2ThreeMedian;
    if (median_translation > kUnmeasured) factor.translation = median_translation / kChi2ThreeMedian;
  }
  return factors;
}

std::vector<EdgeOutlierStatistic> edge_outlier_statistics(const std::vector<Eigen::Isometry3d>& poses,
                                                          const std::vector<PoseGraphEdge>& edges, const PoseGraphOptions& options) {
  const std::vector<EdgeRedundancy> redundancy = edge_redundancies(poses, edges, options);
  std::vector<EdgeOutlierStatistic> statistics(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [rotation_chi2, translation_chi2] = block_chi2(poses, edges[k]);
    if (redundancy[k].rotation > kMinimumRedundancy) statistics[k].rotation = rotation_chi2 / redundancy[k].rotation;
    if (redundancy[k].translation > kMinimumRedundancy) statistics[k].translation = translation_chi2 / redundancy[k].translation;
  }
  return statistics;
}

DataSnooping snoop_pose_graph(std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                              const std::vector<bool>& testable, double threshold, std::size_t maximum_removals,
                              const PoseGraphOptions& options) {
  if (testable.size() != edges.size())
    throw Error("snoop_pose_graph: " + std::to_string(testable.size()) + " testable flags for " + std::to_string(edges.size()) + " edges");
  DataSnooping snooping;
  std::vector<bool> kept(edges.size(), true);
  while (true) {
    std::vector<PoseGraphEdge> remaining;
    std::vector<std::size_t> index_of;
    for (std::size_t k = 0; k < edges.size(); ++k)
      if (kept[k]) remaining.push_back(edges[k]), index_of.push_back(k);
    optimise_pose_graph(poses, remaining, options);
    const std::vector<EdgeOutlierStatistic> statistics = edge_outlier_statistics(poses, remaining, options);
    double worst = 0.0;
    std::size_t worst_edge = 0;
    for (std::size_t k = 0; k < remaining.size(); ++k)
      if (testable[index_of[k]] && statistics[k].largest() > worst) worst = statistics[k].largest(), worst_edge = index_of[k];
    if (!(worst > threshold)) break;
    if (snooping.removed.size() >= maximum_removals) {
      snooping.exhausted = true;
      break;
    }
    kept[worst_edge] = false;
    snooping.removed.push_back(worst_edge);
    snooping.statistic.push_back(worst);
  }
  return snooping;
}

Information6d scaled_information(const Information6d& information, double rotation_factor, double translation_factor) {
  Eigen::Matrix<double, 6, 1> scale;
  scale.head<3>().setConstant(1.0 / std::sqrt(rotation_factor));
  scale.tail<3>().setConstant(1.0 / std::sqrt(translation_factor));
  return scale.asDiagonal() * information * scale.asDiagonal();
}

}  // namespace quadrix
