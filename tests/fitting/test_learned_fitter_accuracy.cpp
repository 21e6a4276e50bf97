// Accuracy of the learned fitter on held-apart segments cut from simulated scans
// (experiments/synthetic/scan_segments.h, seed 11: neither the training seed 101 nor the study's
// seed 7), measured with the fitter study's own metrics (run_fitter_study, scan segments only).
// The thresholds below were set from one measurement each, stated next to them; they are not
// reproductions of training outputs (those are checked by the golden test).
#include "experiments/studies/fitter_study.h"
#include "fitting/quadric_fitter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace quadrix {
namespace {

/// Median of the finite values (NaN when there are none).
double median_of(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

/// Medians of one fitter on the partial (visible fraction <= 50%) segments of one type.
struct PartialMedians {
  std::size_t segments = 0;  ///< partial segments of the type
  double axis_deg = 0.0;     ///< median axis error, degrees (NaN for spheres)
  double centre_m = 0.0;     ///< median centre error, metres
};

/// The study on held-apart scan segments only (no synthetic grid, no real data), statistical and
/// learned. One test holds every check: ctest runs each test in its own process, and the study
/// takes most of the time.
class HeldApartStudy {
 public:
  HeldApartStudy() {
    FitterStudyOptions options;
    options.types.clear();
    options.fitters = {"statistical", "learned"};
    options.automatic_type = false;
    options.real_data = false;
    options.scan_seed = 11;
    options.scan_scene_scans = 4;
    options.scan_object_scans = 250;
    options.scan_segments_per_type = 1000;
    result_ = run_fitter_study(options);
  }

  PartialMedians partial(const std::string& fitter, QuadricType type) const {
    PartialMedians medians;
    std::vector<double> axes, centres;
    for (const FitterStudyRow& row : result_.rows) {
      if (row.source != "scan" || row.fitter != fitter || row.true_type != type || row.visible_fraction > 0.5) continue;
      ++medians.segments;
      axes.push_back(row.axis_error_deg);
      centres.push_back(row.centre_error);
    }
    medians.axis_deg = median_of(axes);
    medians.centre_m = median_of(centres);
    std::cout << fitter << ' ' << quadric_type_name(type) << ": " << medians.segments << " partial segments, median axis "
              << medians.axis_deg << " deg, centre " << medians.centre_m << " m\n";
    return medians;
  }

  FitterStudyResult result_;
};

// Thresholds: the medians measured with the committed weights on this set (seed 11: 4 scene scans,
// 250 object scans) plus about 30% for the float noise of other compilers and CPUs.

TEST(LearnedFitterHeldApart, PartialCylindersConesAndSpheres) {
  const HeldApartStudy study;
  {
    SCOPED_TRACE("circular cylinders");
    const PartialMedians learned = study.partial("learned", QuadricType::CircularCylinder);
    const PartialMedians statistical = study.partial("statistical", QuadricType::CircularCylinder);
    ASSERT_GE(learned.segments, 100u);  // measured 136
    // Measured: learned centre 5.33 cm against statistical 13.6 cm; threshold 7 cm.
    EXPECT_LT(learned.centre_m, 0.07);
    EXPECT_LT(learned.centre_m, statistical.centre_m);
    // Measured: learned axis 0.75 deg; threshold 1.0 deg. The statistical axis (largest-variance
    // direction, 0.58 deg here) stays better on these elongated segments (docs/learned_fitter.md
    // says why): not asserted the other way.
    EXPECT_LT(learned.axis_deg, 1.0);
  }
  {
    SCOPED_TRACE("circular cones");
    const PartialMedians learned = study.partial("learned", QuadricType::CircularCone);
    const PartialMedians statistical = study.partial("statistical", QuadricType::CircularCone);
    ASSERT_GE(learned.segments, 30u);  // measured 46
    // Measured: learned axis 9.92 deg against statistical 41.5 deg; threshold 13 deg.
    EXPECT_LT(learned.axis_deg, 13.0);
    EXPECT_LT(learned.axis_deg, statistical.axis_deg);
    // Measured: learned apex 0.88 m against statistical 2.24 m; threshold 1.15 m.
    EXPECT_LT(learned.centre_m, 1.15);
    EXPECT_LT(learned.centre_m, statistical.centre_m);
  }
  {
    SCOPED_TRACE("spheres");
    const PartialMedians learned = study.partial("learned", QuadricType::Sphere);
    const PartialMedians statistical = study.partial("statistical", QuadricType::Sphere);
    ASSERT_GE(learned.segments, 40u);  // measured 53
    // Measured: learned centre 3.33 cm against statistical 77 cm; threshold 4.4 cm.
    EXPECT_LT(learned.centre_m, 0.044);
    EXPECT_LT(learned.centre_m, statistical.centre_m);
  }
}

}  // namespace
}  // namespace quadrix
