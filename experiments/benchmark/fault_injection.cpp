// Seeded corruptions of a source cloud for `quadrix bench --corrupt` (see fault_injection.h).
#include "experiments/benchmark/fault_injection.h"

#include "geometry/constants.h"
#include "geometry/error.h"

#include <cmath>
#include <random>

namespace quadrix {
namespace {

// Keeps the points whose `keep` entry is true, with every per-point field.
PointCloud keep_points(const PointCloud& cloud, const std::vector<bool>& keep) {
  std::size_t kept_count = 0;
  for (const bool kept : keep) kept_count += kept ? 1 : 0;
  PointCloud kept;
  kept.positions.resize(3, static_cast<Eigen::Index>(kept_count));
  for (auto& [name, values] : cloud.extra_fields) kept.extra_fields[name].reserve(kept_count);
  std::size_t next = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!keep[i]) continue;
    kept.positions.col(static_cast<Eigen::Index>(next++)) = cloud.positions.col(static_cast<Eigen::Index>(i));
    if (!cloud.intensity.empty()) kept.intensity.push_back(cloud.intensity[i]);
    if (!cloud.labels.empty()) kept.labels.push_back(cloud.labels[i]);
    if (!cloud.colors.empty()) kept.colors.push_back(cloud.colors[i]);
    for (auto& [name, values] : cloud.extra_fields) kept.extra_fields[name].push_back(values[i]);
  }
  return kept;
}

// Appends `count` points drawn uniformly in the bounding box of the cloud, with zero fields.
PointCloud add_outliers(const PointCloud& cloud, std::size_t count, std::mt19937_64& random) {
  PointCloud noisy = cloud;
  if (cloud.empty()) return noisy;
  const Eigen::Vector3f low = cloud.positions.rowwise().minCoeff();
  const Eigen::Vector3f high = cloud.positions.rowwise().maxCoeff();
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const Eigen::Index old_size = cloud.positions.cols();
  noisy.positions.conservativeResize(3, old_size + static_cast<Eigen::Index>(count));
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3f where(unit(random), unit(random), unit(random));
    noisy.positions.col(old_size + static_cast<Eigen::Index>(k)) = low + where.cwiseProduct(high - low);
  }
  const std::size_t new_size = noisy.size();
  if (!noisy.intensity.empty()) noisy.intensity.resize(new_size, 0.0f);
  if (!noisy.labels.empty()) noisy.labels.resize(new_size, 0u);
  if (!noisy.colors.empty()) noisy.colors.resize(new_size, {0, 0, 0});
  for (auto& [name, values] : noisy.extra_fields) values.resize(new_size, 0.0f);
  return noisy;
}

PointCloud duplicate_points(const PointCloud& cloud) {
  PointCloud doubled;
  doubled.positions.resize(3, 2 * cloud.positions.cols());
  doubled.positions << cloud.positions, cloud.positions;
  const auto twice = [](auto values) {
    const std::size_t size = values.size();
    values.reserve(2 * size);
    for (std::size_t i = 0; i < size; ++i) values.push_back(values[i]);
    return values;
  };
  doubled.intensity = twice(cloud.intensity);
  doubled.labels = twice(cloud.labels);
  doubled.colors = twice(cloud.colors);
  for (const auto& [name, values] : cloud.extra_fields) doubled.extra_fields[name] = twice(values);
  return doubled;
}

// The number after `prefix` in `name` (e.g. 30 in "drop-30"); false when `name` has another form.
bool parse_amount(const std::string& name, const std::string& prefix, double& amount) {
  if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size()) return false;
  const std::string number = name.substr(prefix.size());
  std::size_t used = 0;
  try {
    amount = std::stod(number, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == number.size() && std::isfinite(amount);
}

[[noreturn]] void throw_bad_corruption(const std::string& name, const std::string& why) {
  throw Error("--corrupt " + name + ": " + why +
              " (expected drop-P with 0 < P < 100, sector-D with 0 < D < 360, outliers-P with 0 < P <= 1000, "
              "noise-S with 0 < S <= 10, duplicate, scale-F with 0.5 <= F <= 2, or none)");
}

}  // namespace

std::vector<std::string> standard_corruption_names() {
  return {"drop-30",     "drop-60",     "drop-90",   "sector-90", "outliers-10", "outliers-30",
          "outliers-50", "noise-0.1", "noise-0.5", "duplicate", "scale-1.001"};
}

Corruption parse_corruption(const std::string& name) {
  Corruption corruption;
  corruption.name = name == "none" ? "" : name;
  double amount = 0.0;
  if (name.empty() || name == "none") return corruption;
  if (name == "duplicate") {
    corruption.kind = CorruptionKind::DuplicatePoints;
  } else if (parse_amount(name, "drop-", amount)) {
    if (!(amount > 0.0 && amount < 100.0)) throw_bad_corruption(name, "the percentage is out of range");
    corruption = {CorruptionKind::DropPoints, amount / 100.0, name};
  } else if (parse_amount(name, "sector-", amount)) {
    if (!(amount > 0.0 && amount < 360.0)) throw_bad_corruption(name, "the wedge angle is out of range");
    corruption = {CorruptionKind::DropSector, amount, name};
  } else if (parse_amount(name, "outliers-", amount)) {
    if (!(amount > 0.0 && amount <= 1000.0)) throw_bad_corruption(name, "the percentage is out of range");
    corruption = {CorruptionKind::AddOutliers, amount / 100.0, name};
  } else if (parse_amount(name, "noise-", amount)) {
    if (!(amount > 0.0 && amount <= 10.0)) throw_bad_corruption(name, "the noise in metres is out of range");
    corruption = {CorruptionKind::AddNoise, amount, name};
  } else if (parse_amount(name, "scale-", amount)) {
    if (!(amount >= 0.5 && amount <= 2.0)) throw_bad_corruption(name, "the factor is out of range");
    corruption = {CorruptionKind::Scale, amount, name};
  } else {
    throw_bad_corruption(name, "unknown corruption");
  }
  return corruption;
}

PointCloud corrupt_cloud(const PointCloud& cloud, const Corruption& corruption, std::uint64_t seed,
                         const Eigen::Vector3d& sensor_origin) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  switch (corruption.kind) {
    case CorruptionKind::None:
      return cloud;
    case CorruptionKind::DropPoints: {
      std::vector<bool> keep(cloud.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) keep[i] = unit(random) >= corruption.amount;
      return keep_points(cloud, keep);
    }
    case CorruptionKind::DropSector: {
      // The wedge [start, start + amount) of azimuth about the sensor's vertical, start uniform.
      const double start = 360.0 * unit(random);
      std::vector<bool> keep(cloud.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d offset = cloud.point(i) - sensor_origin;
        const double azimuth = std::atan2(offset.y(), offset.x()) * 180.0 / kPi;
        const double from_start = std::fmod(azimuth - start + 720.0, 360.0);
        keep[i] = from_start >= corruption.amount;
      }
      return keep_points(cloud, keep);
    }
    case CorruptionKind::AddOutliers:
      return add_outliers(cloud, static_cast<std::size_t>(std::llround(corruption.amount * double(cloud.size()))),
                          random);
    case CorruptionKind::AddNoise: {
      PointCloud noisy = cloud;
      std::normal_distribution<float> noise(0.0f, static_cast<float>(corruption.amount));
      for (Eigen::Index i = 0; i < noisy.positions.cols(); ++i) {
        if (unit(random) >= kNoisyPointFraction) continue;
        noisy.positions.col(i) += Eigen::Vector3f(noise(random), noise(random), noise(random));
      }
      return noisy;
    }
    case CorruptionKind::DuplicatePoints:
      return duplicate_points(cloud);
    case CorruptionKind::Scale: {
      PointCloud scaled = cloud;
      const Eigen::Vector3f origin = sensor_origin.cast<float>();
      scaled.positions = ((cloud.positions.colwise() - origin) * static_cast<float>(corruption.amount)).colwise() + origin;
      return scaled;
    }
  }
  return cloud;
}

}  // namespace quadrix
