// The dense search that settles an ambiguous answer (estimation/dense_search.h, verify_registration):
// point-to-plane ICP against a known transform, a colonnade that repeats along the motion but ends
// in a curved wall (settled at the truth), and a featureless corridor (not settled: the quadric
// answer stands, `ambiguous`). Scenes are sampled at random, each cloud on its own.
#include "estimation/dense_search.h"
#include "estimation/registration.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace quadrix {
namespace {


// A surface sampler: a uniform random point of the surface (world frame).
using Surface = std::function<Eigen::Vector3d(std::mt19937&)>;

Surface rectangle(const Eigen::Vector3d& corner, const Eigen::Vector3d& side_a, const Eigen::Vector3d& side_b) {
  return [=](std::mt19937& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    return Eigen::Vector3d(corner + unit(rng) * side_a + unit(rng) * side_b);
  };
}

// Samples `count` points over `surfaces` (weighted by `areas`) that lie within `range` of `sensor`
// (world frame), adds 1 cm noise and expresses them in the sensor's frame `world_from_sensor`.
PointCloud scan(const std::vector<Surface>& surfaces, const std::vector<double>& areas, const Eigen::Isometry3d& world_from_sensor,
                double range, std::size_t count, std::mt19937& rng) {
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> kept;
  while (kept.size() < count) {
    const Eigen::Vector3d p = surfaces[pick(rng)](rng);
    if ((p - world_from_sensor.translation()).norm() > range) continue;
    kept.push_back(world_from_sensor.inverse() * (p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))));
  }
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) cloud.positions.col(static_cast<Eigen::Index>(i)) = kept[i].cast<float>();
  return cloud;
}

// The models' ground, as modelling finds it: z = 0 in the world, z = -1 in each (level) sensor's frame.
void set_ground(RegistrationResult& result) {
  for (SceneModel* model : {&result.source_model, &result.target_model}) {
    model->has_ground = true;
    model->ground_normal = Eigen::Vector3d::UnitZ();
    model->ground_offset = 1.0;
  }
}

Eigen::Isometry3d pose(double x, double y, double yaw_degrees) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw_degrees * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 1.0);
  return t;
}

// Rectangles (and other samplers) with their areas, so points fall evenly over the scene.
struct Scene {
  std::vector<Surface> surfaces;
  std::vector<double> areas;
  void add(const Eigen::Vector3d& corner, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    surfaces.push_back(rectangle(corner, a, b));
    areas.push_back(a.cross(b).norm());
  }
};

// Ground, a long wall at y = -5 with a 0.5 m pillar every 2.5 m (it repeats along x), and a curved
// wall on the other side (radius 14 m, lowest at y = 6): only the curve tells shifts of 2.5 m apart.
Scene colonnade_with_curved_wall() {
  Scene scene;
  const Eigen::Vector3d up(0, 0, 3);
  scene.add({-30, -5, 0}, {60, 0, 0}, {0, 14, 0});
  scene.add({-30, -5, 0}, {60, 0, 0}, up);
  for (double x = -30; x < 30; x += 2.5) {
    scene.add({x, -4.6, 0}, {0.5, 0, 0}, up);
    scene.add({x, -5, 0}, {0, 0.4, 0}, up);
    scene.add({x + 0.5, -5, 0}, {0, 0.4, 0}, up);
  }
  const double radius = 14.0;
  scene.surfaces.push_back([radius](std::mt19937& rng) {
    std::uniform_real_distribution<double> angle(230.0 * kPi / 180.0, 310.0 * kPi / 180.0), height(0.0, 3.0);
    const double theta = angle(rng);
    return Eigen::Vector3d(radius * std::cos(theta), 20.0 + radius * std::sin(theta), height(rng));
  });
  scene.areas.push_back(radius * 80.0 * kPi / 180.0 * 3.0);
  return scene;
}

// A straight corridor 160 m long: floor, two walls 6 m apart, nothing else.
Scene featureless_corridor() {
  Scene scene;
  scene.add({-80, -3, 0}, {160, 0, 0}, {0, 6, 0});
  scene.add({-80, -3, 0}, {160, 0, 0}, {0, 0, 3});
  scene.add({-80, 3, 0}, {160, 0, 0}, {0, 0, 3});
  return scene;
}

// Both sides' scans of `scene`: the target's sensor at (0, 0, 1), the source's at `source_sensor`;
// `truth` maps source-frame points into the target frame.
struct ScannedPair {
  PointCloud source;
  PointCloud target;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
};

ScannedPair scan_pair(const Scene& scene, const Eigen::Isometry3d& source_sensor, double range, std::size_t count, std::mt19937& rng) {
  const Eigen::Isometry3d target_sensor = pose(0, 0, 0);
  ScannedPair pair;
  pair.target = scan(scene.surfaces, scene.areas, target_sensor, range, count, rng);
  pair.source = scan(scene.surfaces, scene.areas, source_sensor, range, count, rng);
  pair.truth = target_sensor.inverse() * source_sensor;
  return pair;
}

// A 100 x 30 m lot (ground at z = 0) with 30 boxes of random footprint (0.3-3 m a side) and
// height (0.8-4 m) at random places, each seen by its four walls.
Scene lot_of_boxes(std::mt19937& rng) {
  Scene lot;
  lot.add({-50, -15, 0}, {100, 0, 0}, {0, 30, 0});
  std::uniform_real_distribution<double> along(-48.0, 48.0), across(-14.0, 14.0), size(0.3, 3.0), height(0.8, 4.0);
  for (int object = 0; object < 30; ++object) {
    const double x = along(rng), y = across(rng), w = size(rng), d = size(rng), h = height(rng);
    lot.add({x, y, 0}, {w, 0, 0}, {0, 0, h});
    lot.add({x, y + d, 0}, {w, 0, 0}, {0, 0, h});
    lot.add({x, y, 0}, {0, d, 0}, {0, 0, h});
    lot.add({x + w, y, 0}, {0, d, 0}, {0, 0, h});
  }
  return lot;
}

// The colonnade scanned from 2 m along, 0.5 m across and 6 degrees turned, and an answer 2.5 m
// off the truth along it (two pillars).
struct OffColonnade {
  ScannedPair pair;
  Eigen::Isometry3d off;
};

OffColonnade off_colonnade(unsigned seed) {
  std::mt19937 rng(seed);
  OffColonnade colonnade{scan_pair(colonnade_with_curved_wall(), pose(2.0, 0.5, 6.0), 20.0, 40000, rng), {}};
  colonnade.off = colonnade.pair.truth;
  colonnade.off.pretranslate(Eigen::Vector3d(2.5, 0.4, 0.0));
  return colonnade;
}

TEST(DenseSearch, PointToPlaneIcpRecoversASmallOffset) {
  std::mt19937 rng(3);
  const ScannedPair pair = scan_pair(colonnade_with_curved_wall(), pose(1.0, 0.5, 4.0), 20.0, 40000, rng);
  const Eigen::Isometry3d& truth = pair.truth;
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::Isometry3d start = truth;
    start.pretranslate(Eigen::Vector3d(std::normal_distribution<double>(0.0, 0.2)(rng), std::normal_distribution<double>(0.0, 0.2)(rng), 0.05));
    start.rotate(Eigen::AngleAxisd(2.0 * kPi / 180.0, Eigen::Vector3d(0.2, 0.1, 1.0).normalized()));
    const DenseOptimum optimum = align_point_to_plane(pair.source, pair.target, start);
    EXPECT_LT(translation_error(optimum.transform, truth), 0.03) << "trial " << trial;
    EXPECT_LT(rotation_error_degrees(optimum.transform, truth), 0.2) << "trial " << trial;
    EXPECT_LT(optimum.median_residual, 0.02) << "trial " << trial;
    EXPECT_GT(optimum.overlap, 0.7) << "trial " << trial;
  }
}

// Starts that reach one local optimum count as one contender: twenty starts at the truth, with room
// to refine only two optima, still leave nothing unrefined, and every one of them ends refined at
// the same place.
TEST(DenseSearch, StartsReachingOneOptimumShareItsRefinement) {
  std::mt19937 rng(5);
  const ScannedPair pair = scan_pair(colonnade_with_curved_wall(), pose(1.0, 0.5, 4.0), 20.0, 40000, rng);
  DenseSearchOptions options;
  options.range = options.across_range = 0.0;  // one grid start: the answer
  options.max_refined = 2;
  const std::vector<Eigen::Isometry3d> same_starts(20, pair.truth);
  const DenseSearchResult search = search_weakest_direction(pair.source, pair.target, pair.truth, same_starts, {},
                                                            Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0, options);
  EXPECT_EQ(search.unrefined_contenders, 0u);
  const DenseOptimum& best = search.optima[search.best];
  EXPECT_LT(translation_error(best.transform, pair.truth), 0.05);
  for (std::size_t i = 0; i <= same_starts.size(); ++i) {  // the answer's start, then the twenty
    EXPECT_TRUE(search.optima[i].refined) << search.optima[i].start;
    EXPECT_DOUBLE_EQ(search.optima[i].overlap, best.overlap) << search.optima[i].start;
  }
  EXPECT_EQ(search.optima[1].start, "candidate 0") << "each start keeps its own name";
}

// One prepared pair serves searches with different samples and starts, and each gives what it
// gives when it prepares the clouds itself (the target normals it keeps are the same either way);
// a search that asks for another thinning or normal fit is refused.
TEST(DenseSearch, APreparedPairServesEverySearchAsItsOwnPreparationWould) {
  std::mt19937 rng(9);
  const ScannedPair pair = scan_pair(colonnade_with_curved_wall(), pose(2.0, 0.5, 6.0), 20.0, 40000, rng);
  Eigen::Isometry3d off = pair.truth;
  off.pretranslate(Eigen::Vector3d(2.5, 0.4, 0.0));
  DenseSearchOptions wide, few;
  few.source_samples = 900;
  few.range = few.across_range = 0.0;
  const DenseSearchPair prepared(pair.source, pair.target, wide);
  EXPECT_GT(prepared.source_points(), 1000u);
  EXPECT_GT(prepared.target_points(), 1000u);
  const std::vector<Eigen::Isometry3d> starts = {pair.truth};
  for (const DenseSearchOptions& options : {few, wide, few}) {
    const DenseSearchResult shared =
        search_weakest_direction(prepared, off, starts, {}, Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0, options);
    const DenseSearchResult own =
        search_weakest_direction(pair.source, pair.target, off, starts, {}, Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0, options);
    ASSERT_EQ(shared.optima.size(), own.optima.size());
    EXPECT_EQ(shared.best, own.best);
    EXPECT_EQ(shared.source_points, own.source_points);
    for (std::size_t i = 0; i < own.optima.size(); ++i) {
      EXPECT_EQ(shared.optima[i].overlap, own.optima[i].overlap) << own.optima[i].start;
      EXPECT_TRUE(shared.optima[i].transform.isApprox(own.optima[i].transform, 0.0)) << own.optima[i].start;
    }
    EXPECT_LT(translation_error(shared.optima[shared.best].transform, pair.truth), 0.05);
  }
  DenseSearchOptions coarser;
  coarser.voxel_size = 0.3;
  EXPECT_THROW(search_weakest_direction(prepared, off, starts, {}, std::nullopt, std::nullopt, 2.0, 5.0, coarser), Error);
  DenseSearchOptions other_normals;
  other_normals.normal_neighbours = 20;
  EXPECT_THROW(search_weakest_direction(prepared, off, starts, {}, std::nullopt, std::nullopt, 2.0, 5.0, other_normals), Error);
}

// refine_answer is the search's own refinement of its answer's start: the same optimum to the last
// bit, with the same overlap, and near the truth from 2.5 m off.
TEST(DenseSearch, RefiningTheAnswerGivesTheSearchsOptimumForIt) {
  std::mt19937 rng(17);
  const ScannedPair pair = scan_pair(colonnade_with_curved_wall(), pose(2.0, 0.5, 6.0), 20.0, 40000, rng);
  Eigen::Isometry3d off = pair.truth;
  off.pretranslate(Eigen::Vector3d(0.6, 0.3, 0.0));
  DenseSearchOptions options;
  options.range = options.across_range = 0.0;  // one grid start: the answer
  const DenseSearchPair prepared(pair.source, pair.target, options);
  const DenseSearchResult search =
      search_weakest_direction(prepared, off, {}, {}, Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0, options);
  const DenseOptimum& searched = search.optima.front();
  ASSERT_TRUE(searched.refined);
  const DenseOptimum refined = refine_answer(prepared, off, std::nullopt, options);
  EXPECT_TRUE(refined.refined);
  EXPECT_TRUE(refined.transform.isApprox(searched.transform, 0.0));
  EXPECT_EQ(refined.overlap, searched.overlap);
  EXPECT_LT(translation_error(refined.transform, pair.truth), 0.05);
}

// A screened-out optimum is neither the best nor the rival, and the best is picked among the
// others; a screen that rules out every optimum leaves the pick as it was.
TEST(DenseSearch, AScreenedOutOptimumIsNeitherTheBestNorTheRival) {
  const OffColonnade colonnade = off_colonnade(23);
  const ScannedPair& pair = colonnade.pair;
  const Eigen::Isometry3d& off = colonnade.off;
  const DenseSearchOptions options;
  const DenseSearchPair prepared(pair.source, pair.target, options);
  const auto search = [&](const OptimumScreen& screen) {
    return search_weakest_direction(prepared, off, {pair.truth}, {}, Eigen::Vector3d::UnitZ(), std::nullopt, 2.0, 5.0, options,
                                    screen);
  };
  const DenseSearchResult open = search({});
  ASSERT_LT(translation_error(open.optima[open.best].transform, pair.truth), 0.05);
  EXPECT_EQ(open.screened_out, 0u);
  const auto near_truth = [&](const Eigen::Isometry3d& transform) { return translation_error(transform, pair.truth) < 0.5; };
  const DenseSearchResult screened = search(near_truth);
  EXPECT_GE(screened.screened_out, 1u);
  EXPECT_FALSE(screened.optima[screened.best].screened_out);
  EXPECT_GT(translation_error(screened.optima[screened.best].transform, pair.truth), 0.5);
  if (screened.rival) {
    EXPECT_FALSE(screened.optima[*screened.rival].screened_out);
  }
  for (const DenseOptimum& optimum : screened.optima) {
    if (optimum.refined && near_truth(optimum.transform)) {
      EXPECT_TRUE(optimum.screened_out) << optimum.start;
    }
  }
  const DenseSearchResult all_out = search([](const Eigen::Isometry3d&) { return true; });
  EXPECT_EQ(all_out.best, open.best);
  EXPECT_EQ(all_out.margin, open.margin);
}

// ICP finds its point pairs in parallel blocks and sums them in point order: every optimum is the
// same to the last bit on one thread as on many.
TEST(DenseSearch, OptimaDoNotDependOnTheThreadCount) {
  const OffColonnade colonnade = off_colonnade(21);
  const ScannedPair& pair = colonnade.pair;
  const Eigen::Isometry3d& off = colonnade.off;
  const DenseSearchOptions options;
  const auto search = [&] {
    return search_weakest_direction(pair.source, pair.target, off, {pair.truth}, {}, Eigen::Vector3d::UnitZ(), std::nullopt,
                                    2.0, 5.0, options);
  };
  const DenseSearchResult many = search();
  const DenseSearchResult one = [&] {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    return search();
  }();
  ASSERT_EQ(one.optima.size(), many.optima.size());
  EXPECT_EQ(one.best, many.best);
  for (std::size_t i = 0; i < many.optima.size(); ++i) {
    EXPECT_EQ(one.optima[i].overlap, many.optima[i].overlap) << many.optima[i].start;
    EXPECT_EQ(one.optima[i].median_residual, many.optima[i].median_residual) << many.optima[i].start;
    EXPECT_TRUE(one.optima[i].transform.isApprox(many.optima[i].transform, 0.0)) << many.optima[i].start;
  }
  EXPECT_LT(translation_error(many.optima[many.best].transform, pair.truth), 0.05);
}

// An `ambiguous` answer two pillars off along the colonnade: verify_registration finds the truth.
TEST(DenseSearch, RepeatingWallWithCurvedEndIsSettledAtTheTruth) {
  std::mt19937 rng(7);
  const Scene scene = colonnade_with_curved_wall();
  for (int trial = 0; trial < 3; ++trial) {
    const ScannedPair pair = scan_pair(scene, pose(3.4 + 0.3 * trial, 0.2, 1.0 - trial), 18.0, 60000, rng);
    const Eigen::Isometry3d& truth = pair.truth;
    RegistrationResult result;
    result.status = RegistrationStatus::Ambiguous;
    result.transform = truth;
    result.transform.pretranslate(Eigen::Vector3d(-5.0, 0.0, 0.0));  // two pillar spacings off
    set_ground(result);
    const Eigen::Isometry3d wrong = result.transform;
    RegistrationOptions options;
    verify_registration(result, pair.source, pair.target, options);
    ASSERT_TRUE(result.dense_search.has_value());
    const DenseSearchResult& search = *result.dense_search;
    std::printf("trial %d: weakest (%.2f %.2f %.2f) share %.2f, best %s overlap %.3f, margin %.3f, RTE %.3f m, %s\n", trial,
                search.weakest_direction.x(), search.weakest_direction.y(), search.weakest_direction.z(), search.weakest_share,
                search.optima[search.best].start.c_str(), search.optima[search.best].overlap, search.margin,
                translation_error(result.transform, truth), result.message.c_str());
    EXPECT_GT(std::abs(search.weakest_direction.x()), 0.9) << "the colonnade constrains x least";
    EXPECT_EQ(result.status, RegistrationStatus::Ok) << result.message;
    EXPECT_LT(translation_error(result.transform, truth), 0.05);
    EXPECT_LT(rotation_error_degrees(result.transform, truth), 0.3);
    ASSERT_TRUE(search.rival.has_value()) << "the wrong answer's own optimum is a distinct rival";
    EXPECT_GT(translation_error(search.optima[*search.rival].transform, truth), 2.0);
    EXPECT_GE(search.margin, options.dense_search.decisive_margin);
    EXPECT_GT(result.timings_ms.at("dense_search"), 0.0);
    EXPECT_GT(translation_error(wrong, truth), 4.9);
    if (trial > 0) continue;
    // A preset that asks a settled answer to win by more than this one did keeps it as the answer,
    // `ambiguous`; asking for less leaves it `ok`.
    for (const double asked : {search.margin + 0.01, std::max(options.dense_search.decisive_margin, search.margin - 0.01)}) {
      RegistrationResult again;
      again.status = RegistrationStatus::Ambiguous;
      again.transform = wrong;
      set_ground(again);
      RegistrationOptions demanding = options;
      demanding.dense_search.ok_margin = asked;
      verify_registration(again, pair.source, pair.target, demanding);
      const bool unclear = asked > search.margin;
      EXPECT_EQ(again.findings.dense_search_unclear, unclear) << again.message;
      EXPECT_EQ(again.status, unclear ? RegistrationStatus::Ambiguous : RegistrationStatus::Ok) << again.message;
      EXPECT_TRUE(again.transform.isApprox(result.transform, 1e-12)) << "the settled answer stays the answer";
    }
  }
}

// The same colonnade with stray points added to the source (a fifth as many as scene points, but
// spread through the air, so more than the scene's after thinning; they never land on the
// target): the truth still wins clearly but lands less than the 40% floor of the source, so it is
// not `ok`; it becomes the best guess, `ambiguous`, instead of the answer two pillars off. The
// checks leave isolated points out by default; here every stray is kept (isolation_cell 0), as
// strays dense enough to keep each other company would be. With the default, fewer count, and the
// winner lands more of the source.
TEST(DenseSearch, ClearWinnerBelowTheFloorBecomesTheBestGuess) {
  std::mt19937 rng(13);
  ScannedPair pair = scan_pair(colonnade_with_curved_wall(), pose(3.7, 0.2, 0.0), 18.0, 60000, rng);
  const Eigen::Index scene_points = pair.source.positions.cols(), strays = scene_points / 5;
  pair.source.positions.conservativeResize(3, scene_points + strays);
  std::uniform_real_distribution<float> across(-20.0f, 20.0f), height(-0.4f, 2.0f);  // 0.6-3 m above the ground (z = -1)
  for (Eigen::Index i = scene_points; i < scene_points + strays; ++i)
    pair.source.positions.col(i) << across(rng), across(rng), height(rng);
  const auto verify = [&](const RegistrationOptions& options) {
    RegistrationResult result;
    result.status = RegistrationStatus::Ambiguous;
    result.transform = pair.truth;
    result.transform.pretranslate(Eigen::Vector3d(-5.0, 0.0, 0.0));
    set_ground(result);
    verify_registration(result, pair.source, pair.target, options);
    return result;
  };
  RegistrationOptions keep_strays;
  keep_strays.ambiguity.isolation_cell = 0.0;
  const RegistrationResult result = verify(keep_strays);
  ASSERT_TRUE(result.dense_search.has_value());
  const DenseSearchResult& search = *result.dense_search;
  std::printf("every stray kept: best %s overlap %.3f, margin %.3f: %s\n", search.optima[search.best].start.c_str(),
              search.optima[search.best].overlap, search.margin, result.message.c_str());
  EXPECT_EQ(result.counts.source_isolated_points, 0u);
  EXPECT_LT(search.optima[search.best].overlap, keep_strays.dense_search.minimum_overlap) << "the outliers keep it below the floor";
  EXPECT_GE(search.margin, keep_strays.dense_search.decisive_margin);
  EXPECT_EQ(result.status, RegistrationStatus::Ambiguous) << result.message;
  EXPECT_LT(translation_error(result.transform, pair.truth), 0.1) << result.message;
  EXPECT_NE(result.message.find("best guess"), std::string::npos) << result.message;

  const RegistrationResult filtered = verify(RegistrationOptions{});
  ASSERT_TRUE(filtered.dense_search.has_value());
  const DenseSearchResult& filtered_search = *filtered.dense_search;
  std::printf("isolated strays left out (%zu): best overlap %.3f: %s\n", filtered.counts.source_isolated_points,
              filtered_search.optima[filtered_search.best].overlap, filtered.message.c_str());
  EXPECT_GT(filtered.counts.source_isolated_points, 0u);
  EXPECT_GT(filtered_search.optima[filtered_search.best].overlap, search.optima[search.best].overlap);
  EXPECT_LT(translation_error(filtered.transform, pair.truth), 0.1) << filtered.message;
}

// Nothing tells positions along a straight corridor apart: not settled, the quadric answer stands.
TEST(DenseSearch, FeaturelessCorridorIsNotSettled) {
  std::mt19937 rng(11);
  // Both see the whole 160 m: a range limit would make the truth the shift that lines up the ends.
  const ScannedPair pair = scan_pair(featureless_corridor(), pose(2.0, 0.3, 1.0), 200.0, 60000, rng);
  const Eigen::Isometry3d& truth = pair.truth;
  RegistrationResult result;
  result.status = RegistrationStatus::Ambiguous;
  result.transform = truth;
  result.transform.pretranslate(Eigen::Vector3d(5.0, 0.0, 0.0));
  set_ground(result);
  const Eigen::Isometry3d answer = result.transform;
  RegistrationOptions options;
  options.source_extraction.maximum_range = 0.0;  // no range limit
  options.target_extraction.maximum_range = 0.0;
  verify_registration(result, pair.source, pair.target, options);
  ASSERT_TRUE(result.dense_search.has_value());
  const DenseSearchResult& search = *result.dense_search;
  std::printf("corridor: weakest (%.2f %.2f %.2f) share %.4f, margin %.4f: %s\n", search.weakest_direction.x(),
              search.weakest_direction.y(), search.weakest_direction.z(), search.weakest_share, search.margin,
              result.message.c_str());
  EXPECT_GT(std::abs(search.weakest_direction.x()), 0.99);
  EXPECT_LT(search.weakest_share, 0.01) << "no surface faces along the corridor";
  EXPECT_LT(search.margin, options.dense_search.decisive_margin);
  EXPECT_EQ(result.status, RegistrationStatus::Ambiguous) << result.message;
  EXPECT_TRUE(result.transform.isApprox(answer)) << "an unsettled search leaves the quadric answer";
}

// Thirty boxes of random sizes on a 100 x 30 m lot, scanned whole from two places 25 m apart facing
// opposite ways: the correlation of occupied space for the true rotation, searched 40 m around
// the source sensor put on the target's (a mirror answer's place), finds the true translation
// among its three best in every layout; for the rotation turned by 90 degrees, in at most one.
// (What it does on streets, whose façades repeat along them, is measured on the loop-closure sets:
// docs/registration.md, "Half turn".)
TEST(DenseSearch, OccupancyCorrelationFindsTheTranslationOfTheObjects) {
  const Eigen::Vector4d ground(0, 0, 1, 1);  // z = -1 in each level sensor's frame
  int found = 0, found_turned = 0;
  const int layouts = 10;
  for (int layout = 0; layout < layouts; ++layout) {
    std::mt19937 rng(100 + layout);
    const Scene lot = lot_of_boxes(rng);
    const ScannedPair pair = scan_pair(lot, pose(25, 1, 180), 200.0, 40000, rng);
    const auto finds_truth = [&](const Eigen::Matrix3d& rotation) {
      const std::vector<Eigen::Vector3d> best = correlate_translations(
          pair.source, pair.target, ground, ground, rotation, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 40.0, 3);
      EXPECT_LE(best.size(), 3u);
      return std::any_of(best.begin(), best.end(), [&](const Eigen::Vector3d& translation) {
        return (translation - pair.truth.translation()).head<2>().norm() < 1.5;
      });
    };
    found += finds_truth(pair.truth.linear());
    found_turned += finds_truth(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() * pair.truth.linear());
  }
  EXPECT_EQ(found, layouts);
  EXPECT_LE(found_turned, 1);
  // Nothing above the ground: no translation to offer.
  PointCloud flat;
  flat.positions = Eigen::Matrix3Xf::Zero(3, 10);
  flat.positions.row(2).setConstant(-1.0f);
  EXPECT_TRUE(correlate_translations(flat, flat, ground, ground, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
                                     Eigen::Vector3d::UnitZ(), 10.0, 3)
                  .empty());
}

// The correlation over yaw and ground translation (correlate_over_ground) on random lots of boxes:
// the source sensor anywhere 10-30 m from the target's, at any yaw, tilted up to 10 degrees (its
// own ground plane levels it). Its best pose must be the truth within 1 m and 2 degrees in every
// layout, and put the source's ground on the target's.
TEST(DenseSearch, CorrelationOverTheGroundFindsYawAndTranslation) {
  const int layouts = 10;
  int found = 0;
  for (int layout = 0; layout < layouts; ++layout) {
    std::mt19937 rng(300 + layout);
    const Scene lot = lot_of_boxes(rng);
    std::uniform_real_distribution<double> distance(10.0, 30.0), angle(-kPi, kPi), tilt(-10.0, 10.0);
    const double heading = angle(rng), away = distance(rng);
    Eigen::Isometry3d source_sensor = pose(away * std::cos(heading), 0.4 * away * std::sin(heading), angle(rng) * 180.0 / kPi);
    source_sensor.rotate(Eigen::AngleAxisd(tilt(rng) * kPi / 180.0, Eigen::Vector3d::UnitX()));
    source_sensor.rotate(Eigen::AngleAxisd(tilt(rng) * kPi / 180.0, Eigen::Vector3d::UnitY()));
    const ScannedPair pair = scan_pair(lot, source_sensor, 200.0, 40000, rng);
    // Ground z = 0 in the world: n = R^T e_z and d = t_z in the source sensor's frame.
    const Eigen::Vector3d source_normal = source_sensor.linear().transpose() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector4d source_ground(source_normal.x(), source_normal.y(), source_normal.z(), source_sensor.translation().z());
    const std::vector<GroundPose> poses = correlate_over_ground(pair.source, pair.target, source_ground, Eigen::Vector4d(0, 0, 1, 1));
    ASSERT_FALSE(poses.empty());
    EXPECT_LE(poses.size(), GroundCorrelationOptions{}.poses);
    const GroundPose& best = poses.front();
    const double translation_off = translation_error(best.transform, pair.truth);
    const double rotation_off = rotation_error_degrees(best.transform, pair.truth);
    std::printf("layout %d: %.1f m away, best share %.3f, %.2f m and %.2f deg off\n", layout, away, best.share, translation_off,
                rotation_off);
    found += translation_off < 1.0 && rotation_off < 2.0;
    for (std::size_t k = 1; k < poses.size(); ++k) EXPECT_LE(poses[k].share, poses[k - 1].share) << "best first";
    // The source's ground lands on the target's (z = -1 in the level target sensor's frame).
    const Eigen::Vector3d on_source_ground = source_sensor.inverse() * Eigen::Vector3d(3.0, -2.0, 0.0);
    EXPECT_NEAR((best.transform * on_source_ground).z(), -1.0, 1e-6);
  }
  EXPECT_EQ(found, layouts);
  // Nothing in the height band: no pose to offer.
  PointCloud flat;
  flat.positions = Eigen::Matrix3Xf::Zero(3, 10);
  flat.positions.row(2).setConstant(-1.0f);
  EXPECT_TRUE(correlate_over_ground(flat, flat, Eigen::Vector4d(0, 0, 1, 1), Eigen::Vector4d(0, 0, 1, 1)).empty());
  // A target spread over 40 km (too large a grid) and a stray value: no pose, no crash.
  PointCloud spread;
  spread.positions = Eigen::Matrix3Xf::Zero(3, 3);
  spread.positions.col(0) << -20000.0f, -20000.0f, 1.0f;
  spread.positions.col(1) << 20000.0f, 20000.0f, 1.0f;
  spread.positions.col(2) << 3e30f, 0.0f, 1.0f;
  EXPECT_TRUE(correlate_over_ground(spread, spread, Eigen::Vector4d(0, 0, 1, 1), Eigen::Vector4d(0, 0, 1, 1)).empty());
  // Options out of range are named.
  GroundCorrelationOptions options;
  options.maximum_height = options.minimum_height;
  try {
    correlate_over_ground(flat, flat, Eigen::Vector4d(0, 0, 1, 1), Eigen::Vector4d(0, 0, 1, 1), options);
    ADD_FAILURE() << "a band of no height was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'dense_search.correlation.maximum_height'"), std::string::npos) << error.what();
  }
  DenseSearchOptions dense;
  dense.correlation.yaw_step_degrees = 0.0;
  EXPECT_THROW(validate_dense_search_options(dense), Error);
}

TEST(DenseSearch, OptionsOutOfRangeAreNamed) {
  EXPECT_NO_THROW(validate_dense_search_options(DenseSearchOptions{}));
  const auto message = [](const DenseSearchOptions& options) {
    try {
      validate_dense_search_options(options);
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  DenseSearchOptions options;
  options.step = 0.0;
  EXPECT_NE(message(options).find("'dense_search.step'"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.normal_neighbours = 2;
  EXPECT_NE(message(options).find("'dense_search.normal_neighbours' must be at least 3"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.step_with_correlation = 0.0;
  EXPECT_NE(message(options).find("'dense_search.step_with_correlation' must be positive"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.range_with_correlation = -1.0;
  EXPECT_NE(message(options).find("'dense_search.range_with_correlation'"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.across_range_with_correlation = -1.0;
  EXPECT_NE(message(options).find("'dense_search.across_range_with_correlation'"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.ok_margin = -0.01;
  EXPECT_NE(message(options).find("'dense_search.ok_margin' must be non-negative"), std::string::npos) << message(options);
  options = DenseSearchOptions{};
  options.voxel_size = -0.1;
  PointCloud cloud;
  cloud.positions = Eigen::Matrix3Xf::Random(3, 100);
  EXPECT_THROW(align_point_to_plane(cloud, cloud, Eigen::Isometry3d::Identity(), options), Error);
}

}  // namespace
}  // namespace quadrix
