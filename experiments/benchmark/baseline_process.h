// Runs a baseline in its own process: `quadrix bench` hands the (perturbed) clouds to the
// quadrix-baselines executable through temporary files and reads its JSON result back
// (experiments/baselines/baseline_protocol.h). Open3D is thereby loaded only by that executable.
#pragma once

#include "experiments/baselines/baseline_protocol.h"
#include "geometry/point_cloud.h"

#include <string>

namespace quadrix {

/// Path of the quadrix-baselines executable: $QUADRIX_BASELINES when set, else the file of that name
/// beside the running program (build/bin or the install's bin), else the build tree's.
std::string baseline_executable();

/// Runs baseline `method` on `source` -> `target` in a child process of baseline_executable(). The
/// timings are those the child measured (file transfer and start-up excluded). Throws quadrix::Error
/// with the child's message when it exits with an error (unknown method, invalid option) or cannot start.
BaselineResult run_baseline_process(const std::string& method, const PointCloud& source, const PointCloud& target,
                                    const BaselineOptions& options);

}  // namespace quadrix
