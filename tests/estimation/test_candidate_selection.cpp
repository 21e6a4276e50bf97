// Candidate selection (Algorithm 1, Optimal Transformation Selection): SNN, scores, the winner.
#include "estimation/candidate_selection.h"
#include "estimation/synthetic_scene.h"
#include "geometry/constants.h"
#include "geometry/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <tuple>

namespace quadrix {
namespace {

using testing::make_scene;
using testing::SceneSpec;

// The truth among `count - 1` candidates perturbed by 0.5-3 m and 3-10 degrees, at a random slot.
std::vector<Eigen::Isometry3d> candidates_around(std::mt19937& rng, const Eigen::Isometry3d& truth, int count,
                                                 std::size_t* truth_index) {
  std::uniform_real_distribution<double> translation(0.5, 3.0);
  std::uniform_real_distribution<double> degrees(3.0, 10.0);
  std::vector<Eigen::Isometry3d> candidates;
  for (int k = 0; k < count - 1; ++k)
    candidates.push_back(testing::perturbation(rng, translation(rng), degrees(rng) * kPi / 180.0) * truth);
  *truth_index = std::uniform_int_distribution<std::size_t>(0, candidates.size())(rng);
  candidates.insert(candidates.begin() + static_cast<std::ptrdiff_t>(*truth_index), truth);
  return candidates;
}

TEST(CandidateSelection, SemanticNearestNeighboursAreOneToOnePerLabel) {
  std::mt19937 rng(41);
  const auto scene = make_scene(rng, SceneSpec{});
  const auto pairs = semantic_nearest_neighbors(scene.source, scene.target, scene.truth);
  ASSERT_EQ(pairs.size(), scene.source.size());
  std::vector<bool> seen(scene.target.size(), false);
  for (const RecordCorrespondence& pair : pairs) {
    EXPECT_EQ(scene.source[pair.source_index].label, scene.target[pair.target_index].label);
    EXPECT_FALSE(seen[pair.target_index]);
    seen[pair.target_index] = true;
    EXPECT_EQ(pair.source_index, pair.target_index);  // at the truth every element finds itself
  }
  // A label missing in the target gives no pair; a distance cap drops far pairs.
  std::vector<QuadricRecord> target = scene.target;
  for (QuadricRecord& record : target)
    if (record.label == scene.source[0].label) record.label = 999;
  EXPECT_EQ(semantic_nearest_neighbors(scene.source, target, scene.truth).size(), scene.source.size() - 2);
  EXPECT_TRUE(semantic_nearest_neighbors(scene.source, scene.target, testing::perturbation(rng, 100.0, 0.0) * scene.truth, 1.0).empty());
}

// The brute-force definition of SNN: every same-label pair within the cap, sorted by
// (distance, source, target), taken greedily one-to-one.
std::vector<RecordCorrespondence> brute_force_snn(const std::vector<QuadricRecord>& source,
                                                  const std::vector<QuadricRecord>& target,
                                                  const Eigen::Isometry3d& transform, double max_distance) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> all;
  for (std::size_t i = 0; i < source.size(); ++i)
    for (std::size_t j = 0; j < target.size(); ++j) {
      if (source[i].label != target[j].label) continue;
      const double distance = (transform * source[i].full_center - target[j].full_center).norm();
      if (distance <= max_distance) all.emplace_back(distance, i, j);
    }
  std::sort(all.begin(), all.end());
  std::vector<bool> source_used(source.size(), false), target_used(target.size(), false);
  std::vector<RecordCorrespondence> pairs;
  for (const auto& [distance, i, j] : all) {
    if (source_used[i] || target_used[j]) continue;
    source_used[i] = target_used[j] = true;
    pairs.push_back({i, j});
  }
  return pairs;
}

TEST(CandidateSelection, SemanticNearestNeighboursEqualTheBruteForceGreedyAssignment) {
  std::mt19937 rng(43);
  for (int trial = 0; trial < 40; ++trial) {
    // Crowded clouds with few labels, many shared nearest targets, and (every 4th trial) centres
    // on an integer grid so exact distance ties occur.
    const bool grid = trial % 4 == 0;
    std::uniform_real_distribution<double> coordinate(-5.0, 5.0);
    std::uniform_int_distribution<int> cell(-3, 3);
    std::uniform_int_distribution<std::uint32_t> label(0, 2);
    auto random_records = [&](std::size_t count) {
      std::vector<QuadricRecord> records(count);
      for (QuadricRecord& record : records) {
        record.label = label(rng);
        record.full_center = grid ? Eigen::Vector3d(cell(rng), cell(rng), cell(rng))
                                  : Eigen::Vector3d(coordinate(rng), coordinate(rng), coordinate(rng));
      }
      return records;
    };
    const auto source = random_records(std::uniform_int_distribution<std::size_t>(0, 300)(rng));
    const auto target = random_records(std::uniform_int_distribution<std::size_t>(0, 300)(rng));
    const Eigen::Isometry3d transform = grid ? Eigen::Isometry3d::Identity() : testing::perturbation(rng, 1.0, 0.3);
    const double cap = trial % 3 == 0 ? 1.5 : std::numeric_limits<double>::infinity();
    const auto expected = brute_force_snn(source, target, transform, cap);
    const auto actual = semantic_nearest_neighbors(source, target, transform, cap);
    ASSERT_EQ(actual.size(), expected.size()) << "trial " << trial;
    for (std::size_t n = 0; n < expected.size(); ++n) {
      EXPECT_EQ(actual[n].source_index, expected[n].source_index) << "trial " << trial << " pair " << n;
      EXPECT_EQ(actual[n].target_index, expected[n].target_index) << "trial " << trial << " pair " << n;
    }
  }
}

TEST(CandidateSelection, PicksTheTrueCandidateAmongPerturbedOnes) {
  std::mt19937 rng(42);
  int correct = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const auto scene = make_scene(rng, SceneSpec{});
    std::size_t truth_index = 0;
    const auto candidates = candidates_around(rng, scene.truth, 8, &truth_index);
    const SelectionResult result = select_candidate(scene.source, scene.target, candidates);
    ASSERT_EQ(result.status, SelectionStatus::Ok);
    ASSERT_EQ(result.scores.size(), candidates.size());
    correct += result.best_index == truth_index ? 1 : 0;
    EXPECT_NEAR(result.scores[truth_index].score, 0.0, 1e-9);  // exact scene: zero distance at the truth
    EXPECT_LT(result.best_to_second_ratio, 0.01);                // and a clear choice
    EXPECT_TRUE(result.best_transform.isApprox(candidates[result.best_index]));
    for (std::size_t k = 0; k < result.scores.size(); ++k) {
      EXPECT_EQ(result.scores[k].index, k);
      EXPECT_GT(result.scores[k].term_count, result.scores[k].pair_count);  // augmentation adds terms
    }
  }
  EXPECT_EQ(correct, 50);
}

TEST(CandidateSelection, NoisyScenesStillPreferTheTruth) {
  std::mt19937 rng(43);
  SceneSpec spec;
  spec.rotation_noise = 0.5 * kPi / 180.0;
  spec.translation_noise = 0.03;
  int correct = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const auto scene = make_scene(rng, spec);
    std::size_t truth_index = 0;
    const auto candidates = candidates_around(rng, scene.truth, 6, &truth_index);
    SelectionOptions options;
    options.source_ground_normal = Eigen::Vector3d::UnitZ();
    options.target_ground_normal = scene.truth.linear() * Eigen::Vector3d::UnitZ();
    const SelectionResult result = select_candidate(scene.source, scene.target, candidates, options);
    ASSERT_EQ(result.status, SelectionStatus::Ok);
    correct += result.best_index == truth_index ? 1 : 0;
  }
  EXPECT_GE(correct, 95) << correct << "/100";
}

TEST(CandidateSelection, EmptyOrUnscorableInputIsAStatus) {
  std::mt19937 rng(44);
  const auto scene = make_scene(rng, SceneSpec{});
  EXPECT_EQ(select_candidate(scene.source, scene.target, {}).status, SelectionStatus::NoCandidates);
  std::vector<QuadricRecord> relabelled = scene.target;
  for (QuadricRecord& record : relabelled) record.label += 1000;
  const SelectionResult none = select_candidate(scene.source, relabelled, {scene.truth});
  EXPECT_EQ(none.status, SelectionStatus::NoValidScore);
  EXPECT_EQ(none.scores.size(), 1u);
  EXPECT_TRUE(std::isinf(none.scores[0].score));
  SelectionOptions bad;
  bad.dcs_phi = 0.0;
  EXPECT_THROW(select_candidate(scene.source, scene.target, {scene.truth}, bad), Error);
  Eigen::Isometry3d not_finite = scene.truth;
  not_finite.translation().x() = std::nan("");
  EXPECT_THROW(select_candidate(scene.source, scene.target, {not_finite}), Error);
}

}  // namespace
}  // namespace quadrix
