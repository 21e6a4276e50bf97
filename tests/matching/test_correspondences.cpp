// Correspondence initialisation on synthetic models with known truth: the target model is the
// source model moved by a random pose, shuffled, with extra unrelated elements.
#include "matching/correspondences.h"

#include "geometry/error.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace quadrix {
namespace {

struct ModelPair {
  SceneModel source;
  SceneModel target;
  Eigen::Isometry3d source_to_target = Eigen::Isometry3d::Identity();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> truth;  // (source record, target record)
};

/// Classes and the types they are fitted as, as the modelling stage assigns them.
const std::vector<std::pair<ElementClass, QuadricType>> kClasses = {
    {ElementClass::Plane, QuadricType::Plane},
    {ElementClass::Line, QuadricType::Line},
    {ElementClass::Object, QuadricType::Ellipsoid},
    {ElementClass::Trunk, QuadricType::EllipticCylinder},
};

QuadricRecord random_record(std::uint32_t label, std::mt19937_64& random) {
  std::uniform_real_distribution<double> position(-40.0, 40.0);
  std::uniform_real_distribution<double> size(0.2, 6.0);
  QuadricRecord record;
  record.label = label;
  record.full_scale = {size(random), size(random), size(random)};
  record.full_center = {position(random), position(random), position(random) * 0.1};
  return record;
}

ModelPair make_pair(std::uint64_t seed, int per_class, int extra_per_class, int augmented) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  ModelPair pair;
  pair.source_to_target.linear() = Eigen::AngleAxisd(normal(random), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pair.source_to_target.translation() = Eigen::Vector3d(normal(random), normal(random), 0.1 * normal(random)) * 5.0;
  std::vector<std::pair<QuadricRecord, QuadricType>> target_elements;
  std::vector<int> truth_source;
  for (const auto& [element_class, type] : kClasses) {
    const auto label = static_cast<std::uint32_t>(element_class);
    for (int i = 0; i < per_class; ++i) {
      const QuadricRecord record = random_record(label, random);
      pair.source.records.push_back(record);
      pair.source.types.push_back(type);
      QuadricRecord moved = record;
      moved.full_center = pair.source_to_target * record.full_center;
      moved.full_scale += Eigen::Vector3d(normal(random), normal(random), normal(random)) * 0.01;
      target_elements.emplace_back(moved, type);
      truth_source.push_back(static_cast<int>(pair.source.records.size()) - 1);
    }
    for (int i = 0; i < extra_per_class; ++i) {
      target_elements.emplace_back(random_record(label, random), type);
      truth_source.push_back(-1);
    }
  }
  std::vector<std::size_t> order(target_elements.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), random);
  for (std::size_t k = 0; k < order.size(); ++k) {
    pair.target.records.push_back(target_elements[order[k]].first);
    pair.target.types.push_back(target_elements[order[k]].second);
    if (truth_source[order[k]] >= 0)
      pair.truth.emplace_back(static_cast<std::uint32_t>(truth_source[order[k]]), static_cast<std::uint32_t>(k));
  }
  pair.source.augmented_begin = pair.source.records.size();
  pair.target.augmented_begin = pair.target.records.size();
  std::uniform_real_distribution<float> histogram(0.0f, 100.0f);
  for (int i = 0; i < augmented; ++i) {
    QuadricRecord point = random_record(static_cast<std::uint32_t>(ElementClass::Plane), random);
    std::array<float, kFpfhSize> descriptor{};
    for (float& value : descriptor) value = histogram(random);
    pair.source.records.push_back(point);
    pair.source.types.push_back(QuadricType::Point);
    pair.source.augmented_descriptors.push_back(descriptor);
    point.full_center = pair.source_to_target * point.full_center;
    for (float& value : descriptor) value += 0.5f * static_cast<float>(normal(random));
    pair.target.records.push_back(point);
    pair.target.types.push_back(QuadricType::Point);
    pair.target.augmented_descriptors.push_back(descriptor);
    pair.truth.emplace_back(static_cast<std::uint32_t>(pair.source.records.size() - 1),
                            static_cast<std::uint32_t>(pair.target.records.size() - 1));
  }
  return pair;
}

bool contains(const CorrespondenceSet& set, std::uint32_t source, std::uint32_t target) {
  return std::any_of(set.correspondences.begin(), set.correspondences.end(),
                     [&](const Correspondence& c) { return c.source == source && c.target == target; });
}

TEST(Correspondences, EveryTruePairIsKeptAndLabelsNeverMix) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ModelPair pair = make_pair(seed, 30, 10, 40);
    const CorrespondenceSet set = establish_correspondences(pair.source, pair.target);
    EXPECT_EQ(set.shared_classes, kClasses.size());
    for (const auto& [source, target] : pair.truth) EXPECT_TRUE(contains(set, source, target)) << "seed " << seed;
    for (const Correspondence& c : set.correspondences) {
      EXPECT_EQ(pair.source.records[c.source].label, pair.target.records[c.target].label);
      EXPECT_EQ(c.augmented, c.source >= pair.source.augmented_begin);
      EXPECT_EQ(c.augmented, c.target >= pair.target.augmented_begin);
    }
    // Upper bound of the paper: K_e * K_s * M_∩ + N_∩^a, here with 40 elements per class.
    EXPECT_LE(set.quadric_matches, 40u * 20u * kClasses.size());
    EXPECT_EQ(set.augmented_matches, 40u);
    const CorrespondenceQuality quality =
        evaluate_correspondences(pair.source, pair.target, set.correspondences, pair.source_to_target);
    EXPECT_GE(quality.inliers, pair.truth.size());
    EXPECT_TRUE(quality.recalled);
    EXPECT_GT(quality.inlier_ratio, 0.0);
  }
}

TEST(Correspondences, TruePartnersCountEveryMovedQuadricAndNoAugmentedPoint) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const ModelPair pair = make_pair(seed, 12, 6, 30);
    const std::size_t moved_quadrics = 12 * kClasses.size();
    // Every moved quadric has its partner; an unrelated extra lands within 0.5 m of another only by
    // chance, and the 30 augmented points (each with an exact partner) are never counted.
    const std::size_t found = count_true_partners(pair.source, pair.target, pair.source_to_target);
    EXPECT_GE(found, moved_quadrics) << "seed " << seed;
    EXPECT_LE(found, pair.source.augmented_begin) << "seed " << seed;
    // Under a transform 10 m off, almost none line up.
    Eigen::Isometry3d off = pair.source_to_target;
    off.pretranslate(Eigen::Vector3d(10.0, 0.0, 0.0));
    EXPECT_LT(count_true_partners(pair.source, pair.target, off), moved_quadrics / 4) << "seed " << seed;
    // A partner must share the label.
    SceneModel relabelled = pair.target;
    for (std::size_t i = 0; i < relabelled.augmented_begin; ++i) relabelled.records[i].label += 100;
    EXPECT_EQ(count_true_partners(pair.source, relabelled, pair.source_to_target), 0u) << "seed " << seed;
  }
}

TEST(Correspondences, TopKLimitsAndMutualAgreement) {
  const ModelPair pair = make_pair(99, 50, 0, 0);
  CorrespondenceOptions options;
  options.top_k_similar = 1;
  const CorrespondenceSet set = establish_correspondences(pair.source, pair.target, options);
  // With K_s = 1 every element appears at most once on each side, and only mutual best matches survive.
  std::vector<int> source_uses(pair.source.records.size(), 0), target_uses(pair.target.records.size(), 0);
  for (const Correspondence& c : set.correspondences) {
    ++source_uses[c.source];
    ++target_uses[c.target];
  }
  EXPECT_LE(*std::max_element(source_uses.begin(), source_uses.end()), 1);
  EXPECT_LE(*std::max_element(target_uses.begin(), target_uses.end()), 1);
  // Ellipsoids and trunks have distinct scales, so their true pairs are mutual best matches.
  for (const auto& [source, target] : pair.truth) {
    const QuadricType type = pair.source.types[source];
    if (type == QuadricType::Ellipsoid || type == QuadricType::EllipticCylinder) {
      EXPECT_TRUE(contains(set, source, target));
    }
  }
}

TEST(Correspondences, ScaleSimilarityMasksDegenerateAxes) {
  QuadricRecord a, b;
  a.full_scale = {1.0, 2.0, 3.0};
  b.full_scale = {1.5, 2.0, 7.0};
  EXPECT_DOUBLE_EQ(scale_similarity(a, b, QuadricType::Ellipsoid), -std::sqrt(0.25 + 16.0));
  EXPECT_DOUBLE_EQ(scale_similarity(a, b, QuadricType::Plane), 0.0);  // I_s = [0, 0, 0]
}

TEST(Correspondences, MissingClassesAndEmptyModels) {
  ModelPair pair = make_pair(5, 10, 0, 0);
  SceneModel empty;
  EXPECT_TRUE(establish_correspondences(pair.source, empty).correspondences.empty());
  EXPECT_TRUE(establish_correspondences(empty, empty).correspondences.empty());
  const CorrespondenceQuality quality = evaluate_correspondences(empty, empty, {}, Eigen::Isometry3d::Identity());
  EXPECT_EQ(quality.count, 0u);
  EXPECT_FALSE(quality.recalled);
}

TEST(Correspondences, InconsistentModelIsAnError) {
  ModelPair pair = make_pair(6, 5, 0, 0);
  pair.target.types.pop_back();
  try {
    establish_correspondences(pair.source, pair.target);
    FAIL() << "expected quadrix::Error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("target model"));
  }
}

}  // namespace
}  // namespace quadrix
