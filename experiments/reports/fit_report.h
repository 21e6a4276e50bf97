// One quadric fit as JSON, shared by `quadrix fit` and the Python module's quadrix.fit so the two
// cannot drift: fitter, status, message, type, points, the plain shape parameters (shape: radius,
// axis, height, apex, half-angle, normal, offset... as the type has them), the normalised q (paper
// Eq. 2), scale, rotation (unit quaternion w, x, y, z, as model records) and rotation_matrix
// (row-major), center, degeneracy indicators (I_s, I_R, I_t), statistical pose, residuals, f_p2s, times.
#pragma once

#include "fitting/quadric_fitter.h"

#include <cstddef>
#include <string>

namespace quadrix {

/// `fit` of `point_count` points by `fitter_name` as a JSON object text (non-finite numbers are
/// null), indented by `indent` spaces (-1: one line). `points` (the fitted ones) give lines,
/// cylinders and cones their extent and height along the axis (omitted without them).
std::string fit_report_json(const QuadricFit& fit, const std::string& fitter_name, std::size_t point_count,
                            int indent = 2, const Eigen::Matrix3Xd& points = Eigen::Matrix3Xd());

}  // namespace quadrix
