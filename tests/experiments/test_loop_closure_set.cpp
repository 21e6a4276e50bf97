// The synthetic loop-closure set: a second pass of a street keeps its static structure and changes
// its parked cars and pedestrians; the set's pairs land in their distance bins with exact ground
// truth; a far mirror answer of the tuning set is not `ok`.
#include "estimation/registration.h"
#include "estimation/registration_config.h"
#include "experiments/benchmark/bench_pairs.h"
#include "experiments/synthetic/loop_closure_set.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_output.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "geometry/constants.h"
#include "geometry/error.h"
#include "geometry/io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

std::string text_of(const fs::path& path) {
  std::ifstream file(path);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

// Names of the primitives of `scene` with `label`, or of every other label when `other` is set.
std::set<std::string> names_of(const Scene& scene, SemanticLabel label, bool other = false) {
  std::set<std::string> names;
  for (const ScenePrimitive& primitive : scene.primitives)
    if ((primitive.label == label) != other) names.insert(primitive.name);
  return names;
}

TEST(StreetPass, KeepsTheStreetAndChangesCarsAndPedestrians) {
  for (const std::uint64_t seed : {3u, 17u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scene street = make_street_scene(seed);
    const StreetPass first = make_street_pass(seed, 1, 3.0);
    const StreetPass second = make_street_pass(seed, 2, 3.0);
    for (const StreetPass* pass : {&first, &second}) {
      for (std::size_t i = 0; i < pass->scene.primitives.size(); ++i) EXPECT_EQ(pass->scene.primitives[i].id, i);
      // Everything but cars and pedestrians is the street's own.
      std::set<std::string> static_names = names_of(pass->scene, SemanticLabel::Car, true);
      for (const std::string& name : names_of(pass->scene, SemanticLabel::Person)) static_names.erase(name);
      EXPECT_EQ(static_names, names_of(street, SemanticLabel::Car, true));
      const std::size_t pedestrians = names_of(pass->scene, SemanticLabel::Person).size();
      EXPECT_GE(pedestrians, 6u);
      EXPECT_LE(pedestrians, 14u);
    }
    // The passes see different parked cars: some of the street's cars left, some new ones came.
    const std::set<std::string> cars_first = names_of(first.scene, SemanticLabel::Car);
    const std::set<std::string> cars_second = names_of(second.scene, SemanticLabel::Car);
    EXPECT_NE(cars_first, cars_second);
    EXPECT_LT(cars_first.size() + cars_second.size(), 4 * names_of(street, SemanticLabel::Car).size());
    // Pass 1 drives +x, pass 2 drives -x, one scan every 3 m over [-48, 48].
    ASSERT_EQ(first.poses.size(), 33u);
    ASSERT_EQ(second.poses.size(), 32u);
    for (const Eigen::Isometry3d& pose : first.poses) EXPECT_GT(pose.linear().col(0).x(), std::cos(5.0 * kPi / 180.0));
    for (const Eigen::Isometry3d& pose : second.poses) EXPECT_LT(pose.linear().col(0).x(), -std::cos(5.0 * kPi / 180.0));
    EXPECT_LT(first.poses.front().translation().x(), first.poses.back().translation().x());
    EXPECT_GT(second.poses.front().translation().x(), second.poses.back().translation().x());
    // Deterministic.
    EXPECT_EQ(primitives_json(make_street_pass(seed, 2, 3.0).scene, 50), primitives_json(second.scene, 50));
  }
  EXPECT_THROW(make_street_pass(1, 0, 3.0), Error);
  EXPECT_THROW(make_street_pass(1, 1, 0.0), Error);
}

// A third pass drives the first one's way, half a spacing later, with its own parked cars.
TEST(StreetPass, AThirdPassDrivesTheFirstOnesWayBetweenItsScans) {
  const std::uint64_t seed = 3;
  const StreetPass first = make_street_pass(seed, 1, 3.0);
  const StreetPass third = make_street_pass(seed, 3, 3.0);
  EXPECT_NE(names_of(first.scene, SemanticLabel::Car), names_of(third.scene, SemanticLabel::Car));
  ASSERT_EQ(third.poses.size(), 32u);
  for (const Eigen::Isometry3d& pose : third.poses) EXPECT_GT(pose.linear().col(0).x(), std::cos(5.0 * kPi / 180.0));
  for (std::size_t i = 0; i < third.poses.size(); ++i)
    EXPECT_NEAR(third.poses[i].translation().x() - first.poses[i].translation().x(), 1.5, 1e-9);
}

// One street, few scans (13 + 12), 4 + 8k m apart along it: every bin has pairs; three drawn a bin.
LoopClosureSetOptions small_set_options() {
  LoopClosureSetOptions options;
  options.first_seed = 5;
  options.streets = 1;
  options.scan_spacing = 8.0;
  options.pairs_per_bin = 3;
  return options;
}

TEST(LoopClosureSet, PairsLieInTheirBinsWithExactGroundTruth) {
  const fs::path folder = fs::temp_directory_path() / ("quadrix_loop_set_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  const LoopClosureSetOptions options = small_set_options();
  const std::vector<LoopClosureSetPair> pairs = write_loop_closure_set(folder.string(), options);
  std::map<std::string, int> per_bin;
  for (const LoopClosureSetPair& pair : pairs) ++per_bin[pair.bin];
  EXPECT_EQ(per_bin, (std::map<std::string, int>{{"0-10", 3}, {"10-20", 3}, {"20-30", 3}}));
  const std::vector<BenchPair> read = read_pairs_tsv((folder / "pairs.tsv").string());
  ASSERT_EQ(read.size(), pairs.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    SCOPED_TRACE(read[k].id);
    EXPECT_EQ(read[k].id, pairs[k].id);
    EXPECT_EQ(read[k].kind, pairs[k].bin);
    ASSERT_TRUE(read[k].ground_truth.has_value());
    // The truth maps the source's sensor pose onto the target's: p_target = T p_source.
    const Eigen::Isometry3d source_pose = read_pose_matrix((folder / fs::path(pairs[k].source).parent_path() /
                                                             ("pose_" + pairs[k].source.substr(pairs[k].source.size() - 7, 3) + ".txt")).string());
    const Eigen::Isometry3d target_pose = read_pose_matrix((folder / fs::path(pairs[k].target).parent_path() /
                                                             ("pose_" + pairs[k].target.substr(pairs[k].target.size() - 7, 3) + ".txt")).string());
    EXPECT_TRUE(read[k].ground_truth->isApprox(target_pose.inverse() * source_pose, 1e-9));
    const double distance = read[k].ground_truth->translation().norm();
    const std::size_t dash = pairs[k].bin.find('-');
    EXPECT_GE(distance, std::stod(pairs[k].bin.substr(0, dash)));
    EXPECT_LT(distance, std::stod(pairs[k].bin.substr(dash + 1)));
    EXPECT_GT(pairs[k].rotation, 160.0);  // the second pass drives the other way
    EXPECT_GT(read_point_cloud(read[k].source).size(), 10000u);
    EXPECT_FALSE(read_point_cloud(read[k].target).labels.empty());
  }
  // Same options, same bytes.
  const fs::path again = folder / "again";
  write_loop_closure_set(again.string(), options);
  EXPECT_EQ(text_of(folder / "pairs.tsv"), text_of(again / "pairs.tsv"));
  LoopClosureSetOptions bad = options;
  bad.bins = {{10.0, 5.0}};
  EXPECT_THROW(write_loop_closure_set((folder / "bad").string(), bad), Error);
  bad = options;
  bad.streets = 0;
  EXPECT_THROW(write_loop_closure_set((folder / "bad").string(), bad), Error);
  fs::remove_all(folder);
}


// With the second pass driving the same way (forward-looking sensors), every pair faces one way.
TEST(LoopClosureSet, ASecondPassTheSameWayGivesPairsFacingOneWay) {
  const fs::path folder = fs::temp_directory_path() / ("quadrix_loop_set_same_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  LoopClosureSetOptions options = small_set_options();
  options.same_direction = true;
  const std::vector<LoopClosureSetPair> pairs = write_loop_closure_set(folder.string(), options);
  std::map<std::string, int> per_bin;
  for (const LoopClosureSetPair& pair : pairs) {
    ++per_bin[pair.bin];
    EXPECT_LT(pair.rotation, 10.0) << pair.id;  // heading jitter of +-4 deg on each pass
    const Eigen::Isometry3d truth = read_pose_matrix((folder / pair.truth).string());
    EXPECT_NEAR(truth.translation().norm(), pair.distance, 0.01) << pair.id;
  }
  EXPECT_EQ(per_bin, (std::map<std::string, int>{{"0-10", 3}, {"10-20", 3}, {"20-30", 3}}));
  fs::remove_all(folder);
}

// A cross-sensor set: the sources scanned by a VLP-16, the targets by the HDL-64E, over the same
// drives and pairs as the single-sensor set.
TEST(LoopClosureSet, ASourceSensorScansTheSecondPassWithAnotherSensor) {
  const fs::path folder = fs::temp_directory_path() / ("quadrix_loop_set_cross_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  LoopClosureSetOptions options = small_set_options();
  const std::vector<LoopClosureSetPair> alike = write_loop_closure_set((folder / "alike").string(), options);
  options.source_sensor = sensor_preset("vlp16");
  const std::vector<LoopClosureSetPair> cross = write_loop_closure_set((folder / "cross").string(), options);
  ASSERT_EQ(cross.size(), alike.size());
  const std::vector<BenchPair> read = read_pairs_tsv((folder / "cross" / "pairs.tsv").string());
  ASSERT_EQ(read.size(), cross.size());
  for (std::size_t k = 0; k < cross.size(); ++k) {
    SCOPED_TRACE(cross[k].id);
    EXPECT_EQ(cross[k].id, alike[k].id);
    EXPECT_EQ(read[k].sensor, "vlp16->hdl64");
    EXPECT_EQ(text_of(folder / "cross" / cross[k].truth), text_of(folder / "alike" / alike[k].truth));
    // The target is the same HDL-64E scan; the source has a VLP-16's 16 rings, a fraction of the points.
    EXPECT_EQ(text_of(folder / "cross" / cross[k].target), text_of(folder / "alike" / alike[k].target));
    const std::size_t vlp16_points = read_point_cloud((folder / "cross" / cross[k].source).string()).size();
    const std::size_t hdl64_points = read_point_cloud((folder / "alike" / alike[k].source).string()).size();
    EXPECT_LT(4 * vlp16_points, hdl64_points) << vlp16_points << " against " << hdl64_points;
    EXPECT_GT(vlp16_points, 5000u);
  }
  fs::remove_all(folder);
}

// A pair as write_loop_closure_set draws it: street `seed`, its pass-2 scan `source_scan` turned by
// `yaw_degrees` about the up axis (as `quadrix bench --yaw-range` turns a source) against its pass-1
// scan `target_scan`, with the ground truth; each pass scanned by the sensor named.
struct TurnedStreetPair {
  PointCloud source, target;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
};

TurnedStreetPair turned_street_pair(std::uint64_t seed, std::size_t source_scan, std::size_t target_scan, double yaw_degrees,
                                    const std::string& source_sensor = "hdl64", const std::string& target_sensor = "hdl64") {
  const StreetPass first = make_street_pass(seed, 1, 3.0);
  const StreetPass second = make_street_pass(seed, 2, 3.0);
  const SyntheticRun first_run = run_synthetic(first.scene, sensor_preset(target_sensor), first.poses, seed * 2 + 1);
  const SyntheticRun second_run = run_synthetic(second.scene, sensor_preset(source_sensor), second.poses, seed * 2 + 2);
  const Eigen::Isometry3d turn(Eigen::AngleAxisd(yaw_degrees * kPi / 180.0, Eigen::Vector3d::UnitZ()));
  TurnedStreetPair pair;
  pair.source = second_run.scans[source_scan].cloud;
  pair.source.positions = (turn.linear() * pair.source.positions.cast<double>()).cast<float>().eval();
  pair.target = first_run.scans[target_scan].cloud;
  pair.truth = relative_transform(first.poses[target_scan], second.poses[source_scan]) * turn.inverse();
  return pair;
}

// A mirror answer of the synthetic tuning set (street 1002, pass-2 scan 24 against pass-1 scan 0,
// 23 m apart, the source turned by -30.96 degrees as `quadrix bench --yaw-range 180 --seed 3` turned
// it). When the ground segmentation still grew the ground from its densest patch, every candidate
// put the source sensor where the target's is, facing the wrong way (`mirror` below, the answer the
// pipeline gave then), and with that wrong ground the overlap guard measured it at 0.43 of the
// source, above the floor; only the half-turn check's correlation starts caught it. Now the
// pipeline answers right, and the mirror answer, measured against the right ground, lands 0.21 of
// the source on the target: below the floor, so it is not `ok` with or without those starts.
TEST(LoopClosureSet, TheTuningSetsFormerMirrorPairIsRightAndItsMirrorAnswerIsNotOk) {
  const TurnedStreetPair pair = turned_street_pair(1002, 24, 0, -30.959890334646229);
  const PointCloud& source = pair.source;
  const PointCloud& target = pair.target;
  const Eigen::Isometry3d& truth = pair.truth;
  const RegistrationOptions options = resolve_registration_options("auto", source, "auto", target);
  const RegistrationResult registered = register_clouds(source, target, options);
  EXPECT_TRUE(registration_succeeded(registered.transform, truth)) << registered.message;
  EXPECT_EQ(registered.status, RegistrationStatus::Ok) << registered.message;

  Eigen::Matrix4d mirror_matrix;
  mirror_matrix << 0.88486608817966439, -0.46584035443876776, 0.0021840709652934946, -1.5730221439402488,
      0.46582617625902223, 0.88486238173516774, 0.0049536755913971182, -0.013710787129907217,
      -0.004240224229499363, -0.0033659421162295831, 0.99998534535869787, 0.0012317761231226327, 0, 0, 0, 1;
  const Eigen::Isometry3d mirror(mirror_matrix);
  ASSERT_FALSE(registration_succeeded(mirror, truth));
  for (const std::size_t starts : {options.ambiguity.half_turn_correlation_starts, std::size_t(0)}) {
    RegistrationOptions tried = options;
    tried.ambiguity.half_turn_correlation_starts = starts;
    RegistrationResult answer = registered;
    answer.status = RegistrationStatus::Ok;
    answer.findings = RegistrationFindings{};
    answer.message = "candidate of level 0";
    answer.transform = mirror;
    answer.overlap.reset();
    answer.half_turn.reset();
    check_overlap(answer, source, target, tried.ambiguity);
    check_half_turn(answer, source, target, tried, false);
    EXPECT_NE(answer.status, RegistrationStatus::Ok) << answer.message;
    EXPECT_TRUE(answer.findings.overlaps_too_little) << answer.message;
  }
}

// An `ok` answer 25 m wrong that the floor let through, found on the validation set (street 2004,
// pass-2 scan 26 against pass-1 scan 15, 25 m apart) under another draw of yaws than the one the
// set is reported with (`--yaw-range 180 --seed 3` on its 20-30 m rows alone turned the source by
// 119.22 degrees). The quadric answer lands 0.50 of the source on the target (the truth 0.60),
// above the floor, so AmbiguityOptions::confirm_below sends it to the dense search, whose
// correlation over the ground starts at the truth. When it was found its half turn fitted worse;
// since the up axis is fitted to the ground's points the half-turn check catches it too (its rival
// lands 0.60 against 0.34), so the test switches that check off to keep confirm_below the only
// guard between this answer and `ok`; the free-space check catches it as well (its façades stand
// where the other sensor saw through: summed 0.595), so it is switched off too. The ratio of the two
// best candidate scores, 0.8501, sits at the edge of score_ratio (0.85): the bench's rotation put
// it on the `ok` side, so this test moves score_ratio to 0.851 to do the same. It was found with
// every point in range modelled; leaving the street's few isolated points out of the modelling moves
// those scores, so the test keeps every point (extraction isolation_cell 0) to keep its premise.
TEST(LoopClosureSet, AnOkAnswerLandingLittleOfTheSourceIsConfirmedByTheDenseSearch) {
  const TurnedStreetPair pair = turned_street_pair(2004, 26, 15, 119.22322349171716);
  const PointCloud& source = pair.source;
  const PointCloud& target = pair.target;
  const Eigen::Isometry3d& truth = pair.truth;
  RegistrationOptions options = resolve_registration_options("auto", source, "auto", target);
  options.ambiguity.score_ratio = 0.851;
  options.source_extraction.isolation_cell = options.target_extraction.isolation_cell = 0.0;
  options.ambiguity.half_turn_margin = -1.0;
  options.ambiguity.free_space_limit = -1.0;
  for (const double confirm_below : {options.ambiguity.confirm_below, 0.0}) {
    RegistrationOptions tried = options;
    tried.ambiguity.confirm_below = confirm_below;
    const RegistrationResult result = register_clouds(source, target, tried);
    const bool right = registration_succeeded(result.transform, truth);
    std::printf("confirm_below %.2f: %s\n", confirm_below, result.message.c_str());
    if (confirm_below > 0.0) {
      EXPECT_TRUE(right) << result.message;
      EXPECT_NE(result.message.find("the dense search must confirm it"), std::string::npos) << result.message;
      EXPECT_TRUE(result.findings.settled_by_dense_search) << result.message;
    } else {  // what makes the pair a test: without the rule the answer is `ok` and wrong
      EXPECT_TRUE(result.status == RegistrationStatus::Ok && !right) << result.message;
    }
  }
}

// An `ok` answer tilted 5.6 deg, found on the cross-sensor validation set (`quadrix synth
// loop-closures --seed 2001 --sensor vlp16 --source-sensor hdl64`: street 2002, the HDL-64E's
// pass-2 scan 19 onto the VLP-16's pass-1 scan 12, 4.1 m apart) before the refinement weighed the
// ground's tilt by its lever arm, so the test weighs it unscaled (1 m). Both grounds are level, and
// the answer turns one 5.5 deg off the other: the grounds' agreement makes it `ambiguous`. Every
// other check passes it, so without that one it is `ok` and wrong.
TEST(LoopClosureSet, ATiltedAnswerAcrossSensorsIsNotOk) {
  const TurnedStreetPair pair = turned_street_pair(2002, 19, 12, 0.0, "hdl64", "vlp16");
  RegistrationOptions options = resolve_registration_options("auto", pair.source, "auto", pair.target);
  options.estimation.level_ground_lever_arm = 1.0;
  for (const double limit : {options.ambiguity.ground_tilt_limit_degrees, -1.0}) {
    RegistrationOptions tried = options;
    tried.ambiguity.ground_tilt_limit_degrees = limit;
    const RegistrationResult result = register_clouds(pair.source, pair.target, tried);
    const bool right = registration_succeeded(result.transform, pair.truth);
    std::printf("ground tilt limit %.1f: %s\n", limit, result.message.c_str());
    if (limit >= 0.0) {
      EXPECT_FALSE(result.status == RegistrationStatus::Ok && !right) << result.message;
      EXPECT_TRUE(result.findings.grounds_disagree) << result.message;
    } else {  // what makes the pair a test
      EXPECT_TRUE(result.status == RegistrationStatus::Ok && !right) << result.message;
    }
  }
}

// The same pair with the ground's tilt weighed by the default lever arm. The tilted answer's pitch
// came from a far object's centre, 3 m higher in the VLP-16's scan, which sees more of it, than in
// the HDL-64E's. Once a tilt costs what it does to the ground points, the quadric answer stays level
// (0.36 deg) and slides 1.9 m instead; the checks send it to the dense search, which settles it: the
// answer is `ok`, right and level.
TEST(LoopClosureSet, AGroundWeighedByItsLeverArmKeepsACrossSensorAnswerLevel) {
  const TurnedStreetPair pair = turned_street_pair(2002, 19, 12, 0.0, "hdl64", "vlp16");
  const RegistrationOptions options = resolve_registration_options("auto", pair.source, "auto", pair.target);
  ASSERT_GT(options.estimation.level_ground_lever_arm, 1.0);
  const RegistrationResult result = register_clouds(pair.source, pair.target, options);
  std::printf("%s\n", result.message.c_str());
  EXPECT_EQ(result.status, RegistrationStatus::Ok) << result.message;
  EXPECT_TRUE(registration_succeeded(result.transform, pair.truth)) << result.message;
  EXPECT_LT(rotation_error_degrees(result.transform, pair.truth), 1.0) << result.message;
  EXPECT_FALSE(result.findings.grounds_disagree) << result.message;
}

}  // namespace
}  // namespace quadrix
