// Self-registration of `quadrix` subcommands: each command_<name>.cpp defines one static
// CommandRegistration, so adding a command never edits main.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace quadrix::cli {

/// Adds one subcommand (with its options and callback) to the top-level app.
using CommandAdder = std::function<void(CLI::App& app)>;

/// Registers a subcommand at static-initialisation time; `order` sorts the --help listing.
struct CommandRegistration {
  /// Records `add` to be called by main() in ascending `order`.
  CommandRegistration(int order, CommandAdder add);
};

/// The --help group of the commands that reproduce the paper's studies (fitter-segments,
/// compare-fitters, compare-refiners, paper), listed apart from the user's commands.
inline constexpr const char* kResearchCommands = "Research commands (the paper's studies)";

/// Calls every registered adder on `app`, in order (used by main()).
void add_registered_commands(CLI::App& app);

}  // namespace quadrix::cli
