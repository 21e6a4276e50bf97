// The README's C++ example is docs/examples/register_two_clouds.cpp, shown verbatim between its
// markers, and the compiled example registers the paper's KITTI demo pair (0 -> 4438) correctly.
#include "estimation/registration.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace quadrix {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

TEST(ReadmeExample, TheReadmeShowsTheCompiledFileVerbatim) {
  const std::string readme = read_text(std::string(QUADRIX_SOURCE_DIR) + "/README.md");
  const std::string example = read_text(std::string(QUADRIX_SOURCE_DIR) + "/docs/examples/register_two_clouds.cpp");
  ASSERT_FALSE(example.empty());
  const std::string begin_marker = "<!-- example: docs/examples/register_two_clouds.cpp -->";
  const std::size_t begin = readme.find(begin_marker);
  ASSERT_NE(begin, std::string::npos) << "README.md lacks the marker " << begin_marker;
  const std::size_t end = readme.find("<!-- end example -->", begin);
  ASSERT_NE(end, std::string::npos) << "README.md lacks the end marker";
  const std::string block = readme.substr(begin, end - begin);
  const std::size_t code_begin = block.find("```cpp\n");
  const std::size_t code_end = block.rfind("```");
  ASSERT_NE(code_begin, std::string::npos);
  ASSERT_GT(code_end, code_begin);
  EXPECT_EQ(block.substr(code_begin + 7, code_end - code_begin - 7), example);
}

TEST(ReadmeExample, RegistersThePaperDemoPair) {
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/000000.bin");
  QUADRIX_REQUIRE_SHARED_DATA("kitti00/velodyne/004438.ply");
  const std::string command = std::string(QUADRIX_EXAMPLE_EXECUTABLE) + " " +
                              testing::shared_data_path("kitti00/velodyne/000000.bin") + " " +
                              testing::shared_data_path("kitti00/velodyne/004438.ply");
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), static_cast<int>(buffer.size()), pipe)) output += buffer.data();
  const int exit_code = pclose(pipe);
  ASSERT_EQ(exit_code, 0) << output;
  std::istringstream lines(output);
  Eigen::Matrix4d matrix;
  for (int row = 0; row < 4; ++row)
    for (int column = 0; column < 4; ++column) ASSERT_TRUE(lines >> matrix(row, column)) << output;
  const Eigen::Isometry3d truth = read_pose_matrix(testing::shared_data_path("kitti00/gt/T_004438_from_000000.txt"));
  Eigen::Isometry3d estimate;
  estimate.matrix() = matrix;
  // The printed matrix has 6 significant digits; the paper's success rule is 2 m / 5 deg.
  EXPECT_TRUE(registration_succeeded(estimate, truth)) << output;
  EXPECT_NE(output.find("ok:"), std::string::npos) << output;
}

}  // namespace
}  // namespace quadrix
