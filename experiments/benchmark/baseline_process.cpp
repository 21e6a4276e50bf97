// Baselines in a child process (baseline_process.h).
#include "experiments/benchmark/baseline_process.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

extern char** environ;

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// A fresh folder under the system's temporary directory, removed with everything in it on scope exit.
class TemporaryFolder {
 public:
  TemporaryFolder() {
    static std::atomic<unsigned long> counter{0};
    path_ = fs::temp_directory_path() /
            ("quadrix-baseline-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1)));
    fs::create_directories(path_);
  }
  ~TemporaryFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string read_text(const fs::path& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// Positions only: the baselines use nothing else, and the files stay small.
void write_positions(const fs::path& path, const PointCloud& cloud) {
  PointCloud positions;
  positions.positions = cloud.positions;
  write_point_cloud(path.string(), positions);
}

// Runs `arguments` with stdout and stderr into the given files; returns the exit code (-1: killed by a signal).
int run_child(const std::vector<std::string>& arguments, const fs::path& standard_output, const fs::path& standard_error) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, standard_output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, standard_error.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<char*> argv;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  pid_t child = 0;
  const int spawned = posix_spawn(&child, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw Error("cannot start " + arguments[0] + ": " + std::strerror(spawned));
  int status = 0;
  while (waitpid(child, &status, 0) < 0)
    if (errno != EINTR) throw Error("waiting for " + arguments[0] + ": " + std::strerror(errno));
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

std::string baseline_executable() {
  if (const char* from_environment = std::getenv("QUADRIX_BASELINES")) return from_environment;
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path beside = self.parent_path() / "quadrix-baselines";
    if (fs::exists(beside)) return beside.string();
  }
  return QUADRIX_BUILD_TREE_BASELINES_EXECUTABLE;
}

BaselineResult run_baseline_process(const std::string& method, const PointCloud& source, const PointCloud& target,
                                    const BaselineOptions& options) {
  const std::string executable = baseline_executable();
  if (!fs::exists(executable))
    throw Error("baseline executable not found: " + executable + " (build the quadrix-baselines target or set QUADRIX_BASELINES)");
  const TemporaryFolder folder;
  const fs::path source_file = folder.path() / "source.ply";
  const fs::path target_file = folder.path() / "target.ply";
  const fs::path options_file = folder.path() / "options.json";
  write_positions(source_file, source);
  write_positions(target_file, target);
  std::ofstream(options_file) << baseline_options_to_json(options);
  const fs::path output = folder.path() / "result.json";
  const fs::path errors = folder.path() / "errors.txt";
  const int exit_code = run_child({executable, method, source_file.string(), target_file.string(), "--options",
                                   options_file.string()},
                                  output, errors);
  if (exit_code != 0) {
    std::string message = read_text(errors);
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
    throw Error(message.empty() ? executable + " exited with code " + std::to_string(exit_code) : message);
  }
  return baseline_result_from_json(read_text(output));
}

}  // namespace quadrix
