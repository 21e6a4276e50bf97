// Helpers shared by the I/O tests: scratch files, raw byte writers, random clouds with every field.
#pragma once

#include "geometry/point_cloud.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace quadrix::testing {

/// A fresh empty directory for one test, removed at destruction.
class ScratchDirectory {
 public:
  ScratchDirectory() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("quadrix_io_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
             std::to_string(std::random_device{}()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  /// Full path of `name` inside the directory.
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  /// The directory itself.
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Writes `bytes` to `path` verbatim.
inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(stream.good()) << path;
}

/// Reads `path` verbatim.
inline std::string read_bytes(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
}

/// Appends the raw (machine, i.e. little-endian) bytes of `value`.
template <typename T>
void append_raw(std::string& bytes, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes.append(raw, sizeof(T));
}

/// Appends the big-endian bytes of `value`.
template <typename T>
void append_big_endian(std::string& bytes, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes.push_back(raw[sizeof(T) - 1 - i]);
}

/// A random cloud (fixed seed) with positions, and optionally intensity, labels, colours and two extra fields.
inline PointCloud random_cloud(std::size_t points, unsigned seed, bool all_fields = true) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<float> coordinate(-80.0f, 80.0f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> label(0, 0xFFFFFFFFu);
  std::uniform_int_distribution<int> channel(0, 255);
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Eigen::Index>(points));
  for (std::size_t i = 0; i < points; ++i)
    for (int axis = 0; axis < 3; ++axis) cloud.positions(axis, static_cast<Eigen::Index>(i)) = coordinate(generator);
  if (!all_fields) return cloud;
  for (std::size_t i = 0; i < points; ++i) {
    cloud.intensity.push_back(unit(generator));
    cloud.labels.push_back(label(generator));
    cloud.colors.push_back({static_cast<std::uint8_t>(channel(generator)), static_cast<std::uint8_t>(channel(generator)),
                            static_cast<std::uint8_t>(channel(generator))});
    cloud.extra_fields["normal_x"].push_back(unit(generator) * 2.0f - 1.0f);
    cloud.extra_fields["curvature"].push_back(unit(generator) * 1e-7f);
  }
  return cloud;
}

/// Expects two clouds to be bit-identical in every field.
inline void expect_clouds_equal(const PointCloud& expected, const PointCloud& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  EXPECT_TRUE(expected.positions == actual.positions);
  EXPECT_EQ(expected.intensity, actual.intensity);
  EXPECT_EQ(expected.labels, actual.labels);
  EXPECT_EQ(expected.colors, actual.colors);
  EXPECT_EQ(expected.extra_fields, actual.extra_fields);
}

}  // namespace quadrix::testing
