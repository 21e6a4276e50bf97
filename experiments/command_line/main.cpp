// `quadrix`: the command line. Subcommands live in command_*.cpp and register themselves.
#include "experiments/command_line/command_registry.h"
#include "geometry/error.h"
#include "geometry/removed_on_signal.h"

#include <malloc.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace quadrix::cli {
namespace {
std::vector<std::pair<int, CommandAdder>>& registry() {
  static std::vector<std::pair<int, CommandAdder>> commands;
  return commands;
}
}  // namespace

CommandRegistration::CommandRegistration(int order, CommandAdder add) {
  registry().emplace_back(order, std::move(add));
}

void add_registered_commands(CLI::App& app) {
  auto& commands = registry();
  std::stable_sort(commands.begin(), commands.end(),
                   [](const auto& left, const auto& right) { return left.first < right.first; });
  for (auto& command : commands) command.second(app);
}

}  // namespace quadrix::cli

namespace {

// glibc's allocator returns large freed blocks to the kernel (munmap, heap trimming), so every
// stage that allocates a cloud-sized buffer pays page faults again to zero fresh pages. A command
// runs a pipeline of such stages over clouds of similar size, so it keeps freed memory for reuse:
// blocks below 32 MiB come from the heap, which grows 64 MiB at a time and is not trimmed. On the
// 14 KITTI pairs of pairs.tsv (`quadrix bench`) this took the page faults from 35-52 k to 13 k
// and the CPU time by 3-7% (perf stat, four runs each), at the price of a process keeping its
// peak heap until it exits (docs/registration.md, "Time").
void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TOP_PAD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

// `message` cut to at most 1,000 characters (its start and its end kept): a value quoted from a
// file (a 100 MB token) is not echoed whole.
std::string bounded(const std::string& message) {
  constexpr std::size_t kHead = 640, kTail = 320;
  if (message.size() <= kHead + kTail + 40) return message;
  return message.substr(0, kHead) + " ... (" + std::to_string(message.size() - kHead - kTail) +
         " characters left out) ... " + message.substr(message.size() - kTail);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();
  CLI::App app{"quadrix: quadric primitives for point-cloud modelling and global registration"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "quadrix 0.1.0");
  quadrix::cli::add_registered_commands(app);
  quadrix::remove_on_signals();  // an interrupted command leaves no temporary file behind
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version end here with 0; every usage error is a usage error: 2 (CLI11's own
    // codes, 105-114, would read as something else).
    return app.exit(error) == 0 ? 0 : 2;
  } catch (const quadrix::Error& error) {
    std::fprintf(stderr, "quadrix: error: %s\n", bounded(error.what()).c_str());
    return 2;
  } catch (const std::filesystem::filesystem_error& error) {
    // A path the system refused (permission, a full or read-only disk): the user's to fix, not a fault.
    std::fprintf(stderr, "quadrix: error: %s\n", bounded(error.what()).c_str());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "quadrix: internal error: %s\n", bounded(error.what()).c_str());
    return 3;
  }
  return 0;
}
