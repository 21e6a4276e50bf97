// `quadrix`: the command line. Subcommands live in command_*.cpp and register themselves.
#include "experiments/command_line/command_registry.h"
#include "geometry/error.h"

#include <algorithm>
#include <cstdio>
#include <exception>
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

int main(int argc, char** argv) {
  CLI::App app{"quadrix: quadric primitives for point-cloud modelling and global registration"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "quadrix 0.1.0");
  quadrix::cli::add_registered_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  } catch (const quadrix::Error& error) {
    std::fprintf(stderr, "quadrix: error: %s\n", error.what());
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "quadrix: internal error: %s\n", error.what());
    return 3;
  }
  return 0;
}
