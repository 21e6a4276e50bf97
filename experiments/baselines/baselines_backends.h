// Internal to the baselines: the per-library entry points behind run_baseline (baselines.cpp),
// each defined in its own translation unit so Open3D and PCL headers never meet.
#pragma once

#include "experiments/baselines/baselines.h"

#include <chrono>
#include <ctime>

namespace quadrix::baselines_detail {

/// Open3D 0.16 FPFH + RegistrationRANSACBasedOnFeatureMatching (baselines_open3d.cpp).
BaselineResult run_open3d_ransac(const PointCloud& source, const PointCloud& target, const BaselineOptions& options);

/// Open3D 0.16 FPFH + FastGlobalRegistrationBasedOnFeatureMatching (baselines_open3d.cpp).
BaselineResult run_open3d_fgr(const PointCloud& source, const PointCloud& target, const BaselineOptions& options);

/// PCL 1.13 FPFH + SampleConsensusPrerejective (baselines_pcl.cpp).
BaselineResult run_pcl_prerejective(const PointCloud& source, const PointCloud& target, const BaselineOptions& options);

/// Fewest down-sampled points per cloud a baseline attempts to register (3 for a rigid transform).
constexpr std::size_t minimum_points = 3;

/// CPU time consumed so far by the calling thread, ms (CLOCK_THREAD_CPUTIME_ID).
inline double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

/// Wall-clock stopwatch for the per-stage timings.
class Stopwatch {
 public:
  /// Milliseconds since construction or the previous lap, then restarts.
  double lap_ms() {
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return elapsed;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace quadrix::baselines_detail
