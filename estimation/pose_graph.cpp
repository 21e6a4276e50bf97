// Pose graph in Ceres: translation (R^3) and quaternion (ceres::EigenQuaternionManifold, Ceres 2.1)
// blocks per pose, an autodiff relative-pose cost per edge weighted by the square root of its
// information, and the robust kernels of quadric_distance.h as ceres::LossFunctions.
#include "estimation/pose_graph.h"

#include "estimation/quadric_distance.h"
#include "geometry/error.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
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

}  // namespace quadrix
