// The free-space check (estimation/free_space.h) on hand-built scans whose answer is known: a
// sensor's nearest return per direction, points in front of it counted each way, the low points
// and the tolerance left out, and bad input refused.
#include "estimation/free_space.h"

#include "geometry/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace quadrix {
namespace {

// Points as a cloud.
PointCloud cloud_of(const std::vector<Eigen::Vector3d>& points) {
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = points[i].cast<float>();
  return cloud;
}

// A scan from a sensor 1.73 m above the ground of a world with a wall across the view at x = 12
// (8 m high, y in [-10, 10]) and the ground before it, in the sensor's frame (z up, sensor at the
// origin). The wall is only what the sensor sees: the world behind it is hidden.
PointCloud scan_from(double sensor_x) {
  std::vector<Eigen::Vector3d> points;
  for (double y = -10.0; y <= 10.0; y += 0.1)
    for (double z = 0.0; z <= 8.0; z += 0.1) points.emplace_back(12.0 - sensor_x, y, z - 1.73);
  for (double x = 2.0; x <= 12.0 - sensor_x; x += 0.2)
    for (double y = -6.0; y <= 6.0; y += 0.2) points.emplace_back(x, y, -1.73);
  return cloud_of(points);
}

// The ground of such a scan: z = -1.73 as (n, offset) with n up.
const Eigen::Vector4d kGround(0.0, 0.0, 1.0, 1.73);

TEST(RangeImage, HoldsTheNearestReturnOfEachDirectionAroundItsSensor) {
  const PointCloud wall = cloud_of({{10.0, 0.0, 0.0}, {14.0, 0.0, 0.0}, {0.0, 5.0, 0.0}});
  const RangeImage image(wall, Eigen::Vector3d::Zero());
  ASSERT_TRUE(image.nearest_return({5.0, 0.0, 0.0}).has_value());
  EXPECT_NEAR(*image.nearest_return({5.0, 0.0, 0.0}), 10.0, 1e-5) << "the nearer of the two returns ahead";
  EXPECT_NEAR(*image.nearest_return({0.0, 50.0, 0.0}), 5.0, 1e-5);
  EXPECT_FALSE(image.nearest_return({0.0, -5.0, 0.0}).has_value()) << "no return in that direction";
  EXPECT_FALSE(image.nearest_return({5.0, 0.0, 1.0}).has_value()) << "11 deg up is another elevation cell";
  EXPECT_FALSE(image.nearest_return(Eigen::Vector3d::Zero()).has_value()) << "the sensor itself has no direction";
  // Elevation cells are centred on whole degrees: a ring at 1 deg (a VLP-16's) holds the middle of
  // the cell from 0.5 to 1.5 deg, whatever the last bits of its angle.
  const auto at_elevation = [](double degrees, double range) -> Eigen::Vector3d {
    const double elevation = degrees * M_PI / 180.0, azimuth = 10.0 * M_PI / 180.0;
    return Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)) * range;
  };
  const RangeImage ring(cloud_of({at_elevation(1.0, 20.0), at_elevation(1.0 + 1e-9, 21.0), at_elevation(1.0 - 1e-9, 22.0)}),
                        Eigen::Vector3d::Zero());
  EXPECT_NEAR(*ring.nearest_return(at_elevation(1.4, 5.0)), 20.0, 1e-4) << "the ring's returns share a cell";
  EXPECT_NEAR(*ring.nearest_return(at_elevation(0.6, 5.0)), 20.0, 1e-4);
  EXPECT_FALSE(ring.nearest_return(at_elevation(0.4, 5.0)).has_value());
  EXPECT_FALSE(ring.nearest_return(at_elevation(1.6, 5.0)).has_value());
  // Around another sensor position, directions and ranges are taken from there.
  const RangeImage moved(wall, Eigen::Vector3d(1.0, 0.0, 0.0));
  EXPECT_NEAR(*moved.nearest_return({6.0, 0.0, 0.0}), 9.0, 1e-5);
  EXPECT_THROW(RangeImage(wall, Eigen::Vector3d(std::nan(""), 0.0, 0.0)), Error);
}

TEST(MeasureFreeSpace, TheTruthLeavesTheOtherSensorsFreeSpaceEmptyAndAShiftFillsIt) {
  // The source sensor stands 3 m nearer the wall than the target's; truth: x_target = x_source + 3.
  const PointCloud source = scan_from(3.0), target = scan_from(0.0);
  const RangeImage source_image(source, Eigen::Vector3d::Zero()), target_image(target, Eigen::Vector3d::Zero());
  const Eigen::Isometry3d truth(Eigen::Translation3d(3.0, 0.0, 0.0));
  const FreeSpaceMeasure right = measure_free_space(source, target, source_image, target_image, truth, kGround, kGround, 2.0);
  EXPECT_GT(right.source_tested, 1000u);
  EXPECT_GT(right.target_tested, 1000u);
  EXPECT_EQ(right.source_in_target_free_space, 0.0);
  EXPECT_EQ(right.target_in_source_free_space, 0.0);
  // Two metres short: the source's wall stands in the target sensor's free space, and the target's
  // wall, moved back, behind the source's (hidden, not free): one way only.
  const Eigen::Isometry3d short_of_it(Eigen::Translation3d(1.0, 0.0, 0.0));
  const FreeSpaceMeasure wrong = measure_free_space(source, target, source_image, target_image, short_of_it, kGround, kGround, 2.0);
  EXPECT_GT(wrong.source_in_target_free_space, 0.95);
  EXPECT_EQ(wrong.target_in_source_free_space, 0.0);
  EXPECT_GT(wrong.sum(), 0.95);
  // The other way round, two metres too far: the target's wall lands in the source's free space.
  const Eigen::Isometry3d beyond(Eigen::Translation3d(5.0, 0.0, 0.0));
  const FreeSpaceMeasure far = measure_free_space(source, target, source_image, target_image, beyond, kGround, kGround, 2.0);
  EXPECT_EQ(far.source_in_target_free_space, 0.0);
  EXPECT_GT(far.target_in_source_free_space, 0.95);
  // Within the tolerance (0.3 m short, at most ~0.45 m along the widest rays; 0.5 allowed) nothing is counted.
  const Eigen::Isometry3d close(Eigen::Translation3d(2.7, 0.0, 0.0));
  EXPECT_EQ(measure_free_space(source, target, source_image, target_image, close, kGround, kGround, 2.0).sum(), 0.0);
}

TEST(MeasureFreeSpace, PointsLowerThanTheHeightAreNotTested) {
  const PointCloud source = scan_from(3.0), target = scan_from(0.0);
  const RangeImage source_image(source, Eigen::Vector3d::Zero()), target_image(target, Eigen::Vector3d::Zero());
  const Eigen::Isometry3d short_of_it(Eigen::Translation3d(1.0, 0.0, 0.0));
  // Of the source wall's rows the target sensor had returns behind (up to ~6.9 m high), those
  // higher than 2 m are ~49 and those higher than 5 m ~19; all of them stand in its free space.
  const FreeSpaceMeasure high = measure_free_space(source, target, source_image, target_image, short_of_it, kGround, kGround, 2.0);
  const FreeSpaceMeasure top = measure_free_space(source, target, source_image, target_image, short_of_it, kGround, kGround, 5.0);
  EXPECT_LT(top.source_tested, high.source_tested * 6 / 10);
  EXPECT_GT(top.source_tested, high.source_tested * 3 / 10);
  EXPECT_GT(top.source_in_target_free_space, 0.95);
  // Above 9 m nothing stands: nothing is tested, and the shares are 0.
  const FreeSpaceMeasure none = measure_free_space(source, target, source_image, target_image, short_of_it, kGround, kGround, 9.0);
  EXPECT_EQ(none.source_tested + none.target_tested, 0u);
  EXPECT_EQ(none.sum(), 0.0);
  EXPECT_THROW(measure_free_space(source, target, source_image, target_image, short_of_it, kGround, kGround, 2.0, -0.1), Error);
}

}  // namespace
}  // namespace quadrix
