// Red team: what an adversarial user types must not crash `quadrix`, hang it, destroy a file or make
// it say `ok` when it is wrong. Every configuration key is walked with extreme values (refused at
// read time naming file and key, or accepted within its range), accepted extremes of the keys that
// set an amount of work run to an honest status on a small synthetic pair, and each reproduction of
// docs/reliability.md's table runs the built binary through a shell-free driver (fork + execv, a
// deadline, SIGKILL past it): odd outputs (devices, FIFOs, symlinks, folders, an input, another
// output, /proc), odd inputs (FIFOs, sizes, NaN, huge numbers), usage errors, interrupts.
#include "estimation/registration_config.h"
#include "experiments/synthetic/scanner_simulator.h"
#include "experiments/synthetic/synthetic_scene.h"
#include "fitting/extraction.h"
#include "geometry/error.h"
#include "geometry/io.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <variant>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// The driver: runs the built binary without a shell.

struct CommandRun {
  int exit_code = -1;     // when it exited
  int signal = 0;         // when a signal ended it
  bool timed_out = false; // killed at the deadline
  std::string output;     // stdout and stderr together
};

// Runs `quadrix args...` with output to a file; SIGKILL after `deadline_s`; with `interrupt_after_s`,
// sends `interrupt_signal` then.
CommandRun run_quadrix(const std::vector<std::string>& args, double deadline_s = 120.0,
                std::optional<double> interrupt_after_s = std::nullopt, int interrupt_signal = SIGTERM) {
  static int counter = 0;
  const std::string log = (fs::temp_directory_path() / ("quadrix_red_team_log_" + std::to_string(::getpid()) + "_" +
                                                        std::to_string(counter++)))
                              .string();
  std::vector<std::string> argv_strings{QUADRIX_EXECUTABLE};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t child = ::fork();
  if (child == 0) {
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(out, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  CommandRun run;
  const auto start = std::chrono::steady_clock::now();
  bool interrupted = false;
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child) break;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupt_after_s && !interrupted && elapsed >= *interrupt_after_s) {
      ::kill(child, interrupt_signal);
      interrupted = true;
    }
    if (elapsed > deadline_s) {
      ::kill(child, SIGKILL);
      ::waitpid(child, &status, 0);
      run.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) run.signal = WTERMSIG(status);
  std::ifstream in(log);
  run.output.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  fs::remove(log);
  return run;
}

std::string describe(const CommandRun& run) {
  return "exit " + std::to_string(run.exit_code) + ", signal " + std::to_string(run.signal) +
         (run.timed_out ? ", TIMED OUT" : "") + "\n" + run.output.substr(0, 3000);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

// A new empty folder of this process: ctest runs each test in its own process, in parallel, so the
// process id keeps one test from clearing another's files (the shared small pair included).
// The folders are removed when the process ends.
fs::path fresh_folder(const std::string& name) {
  struct Created {
    std::vector<fs::path> folders;
    ~Created() {
      std::error_code ignored;
      for (const fs::path& folder : folders) fs::remove_all(folder, ignored);
    }
  };
  static Created created;
  const fs::path folder = fs::temp_directory_path() / ("quadrix_red_team_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  created.folders.push_back(folder);
  return folder;
}

// A usage or input error: exit 2 within the deadline, no signal.
#define EXPECT_REFUSED(run, needle)                                                       \
  do {                                                                                     \
    const CommandRun& refused_run = (run);                                                        \
    EXPECT_EQ(refused_run.exit_code, 2) << describe(refused_run);                          \
    EXPECT_NE(refused_run.output.find(needle), std::string::npos) << describe(refused_run); \
  } while (0)

// ---------------------------------------------------------------------------------------------
// A small synthetic pair (VLP-16 on a street, two poses) written once for every test here.

struct Pair {
  fs::path folder;
  std::string source, target, truth;
  Eigen::Isometry3d truth_transform = Eigen::Isometry3d::Identity();
  PointCloud source_cloud, target_cloud;
};

const Pair& small_pair() {
  static const Pair pair = [] {
    Pair made;
    made.folder = fresh_folder("pair");
    const Scene scene = make_street_scene(7);
    const RayCaster caster(scene);
    const SensorModel sensor = sensor_preset("vlp16");
    const SimulatedScan source = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[0], 11, 0);
    const SimulatedScan target = simulate_scan(scene, caster, sensor, scene.default_lidar_poses[1], 12, 1);
    made.source_cloud.positions = source.cloud.positions;
    made.target_cloud.positions = target.cloud.positions;
    made.source = (made.folder / "source.ply").string();
    made.target = (made.folder / "target.ply").string();
    write_point_cloud(made.source, made.source_cloud);
    write_point_cloud(made.target, made.target_cloud);
    made.truth_transform = target.sensor_pose.inverse() * source.sensor_pose;
    made.truth = (made.folder / "truth.txt").string();
    write_pose_matrix(made.truth, made.truth_transform);
    return made;
  }();
  return pair;
}

// ---------------------------------------------------------------------------------------------
// The schema walk.

// The YAML of `value` at the dotted `path`: "a: {b: {c: value}}".
std::string nested_yaml(const std::string& path, const std::string& value) {
  std::string yaml, closing;
  std::size_t begin = 0;
  for (std::size_t dot = path.find('.'); dot != std::string::npos; begin = dot + 1, dot = path.find('.', begin)) {
    yaml += path.substr(begin, dot - begin) + ": {";
    closing += "}";
  }
  return yaml + path.substr(begin) + ": " + value + closing + "\n";
}

// The member of `key` as a number (ranged keys: each list entry checked by the caller).
std::vector<double> numbers_of(const RegistrationConfigMember& member) {
  return std::visit(
      [](auto* value) -> std::vector<double> {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, std::vector<double>>) return *value;
        else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) return {static_cast<double>(*value)};
        else return {};
      },
      member);
}

TEST(RedTeamSchema, EveryKeyHasARangeAndEveryPresetLiesInIt) {
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    if (!key.ranged) continue;
    EXPECT_LE(key.minimum, key.maximum) << key.path;
    EXPECT_TRUE(std::isfinite(key.minimum) && std::isfinite(key.maximum)) << key.path << ": every range is bounded";
  }
  // Every preset's own values are valid: its full YAML reads back.
  const fs::path folder = fresh_folder("presets");
  for (const std::string& preset : registration_preset_names()) {
    const RegistrationOptions options = registration_preset(preset);
    const std::string file = write_text(folder / (preset + ".yaml"), registration_config_yaml(options));
    RegistrationOptions read = options;
    EXPECT_NO_THROW(apply_registration_config(file, read)) << preset;
  }
}

// Every key, with every extreme a user might type: refused at read time by an Error naming the file
// and the key, or accepted with every resulting value inside the key's range.
TEST(RedTeamSchema, EveryKeyRefusesOrBoundsEveryExtremeValue) {
  const fs::path folder = fresh_folder("schema");
  const std::vector<std::string> extremes = {
      "0", "-1", "1", "1e300", "-1e300", "1e-300", ".nan", ".inf", "-.inf", "2147483648", "9223372036854775808",
      "18446744073709551616", "-9223372036854775809", "abc", "true", "''", "[1, 2]", "{a: 1}", "[]", "[.nan]",
      "[-1]", "[1e300]", "[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]", "[0, 0, 0]", "[1e308, 1e308, 1e308]", "~", "0x10", "1.5"};
  std::size_t refused = 0, accepted = 0;
  for (const RegistrationConfigKey& key : registration_config_keys()) {
    for (const std::string& value : extremes) {
      const std::string file = write_text(folder / "config.yaml", nested_yaml(key.path, value));
      RegistrationOptions options;
      try {
        apply_registration_config(file, options);
      } catch (const Error& error) {
        ++refused;
        const std::string message = error.what();
        EXPECT_NE(message.find(file), std::string::npos) << key.path << " = " << value << ": " << message;
        EXPECT_LT(message.size(), 1000u) << key.path << " = " << value;
        // A refusal names the key (a malformed file may be refused before any key is read).
        if (message.find("invalid YAML") == std::string::npos && message.find("must be a mapping") == std::string::npos) {
          EXPECT_NE(message.find(key.path), std::string::npos) << key.path << " = " << value << ": " << message;
        }
        continue;
      } catch (const std::exception& error) {
        ADD_FAILURE() << key.path << " = " << value << ": not a quadrix::Error: " << error.what();
        continue;
      }
      ++accepted;
      for (const ConfigSide side : {ConfigSide::Source, ConfigSide::Target})
        for (const double number : numbers_of(key.member(options, side))) {
          EXPECT_TRUE(std::isfinite(number)) << key.path << " = " << value;
          if (key.ranged) {
            EXPECT_TRUE((key.zero_allowed && number == 0.0) || (number >= key.minimum && number <= key.maximum))
                << key.path << " = " << value << " accepted as " << number << ", outside " << valid_range_text(key);
          }
        }
    }
  }
  EXPECT_GT(refused, 0u);
  EXPECT_GT(accepted, 0u);
}

// The keys that set an amount of work, at their largest accepted values (and the verification
// thresholds at their weakest), each run on the small synthetic pair: the run ends, and an `ok` is
// right (within the success rule, 2 m / 5 deg).
TEST(RedTeamSchema, AcceptedExtremesOfTheWorkKeysEndWithAnHonestStatus) {
  const Pair& pair = small_pair();
  const std::vector<std::string> keys = {
      "dense_search.normal_neighbours", "dense_search.iterations",      "dense_search.correlation.poses",
      "dense_search.range_with_correlation", "dense_search.correspondence_distance", "ambiguity.half_turn_samples",
      "ambiguity.half_turn_votes",      "dense_search.source_samples",  "matching.top_k_similar",
      "modelling.quadrics_per_class",   "dense_search.max_refined",     "ambiguity.translation_disagreement"};
  const fs::path folder = fresh_folder("extremes");
  for (const std::string& path : keys) {
    const RegistrationConfigKey* key = find_registration_config_key(path);
    ASSERT_NE(key, nullptr) << path;
    std::ostringstream value;
    value.precision(17);
    value << key->maximum;
    const std::string file = write_text(folder / "config.yaml", nested_yaml(path, value.str()));
    RegistrationOptions options = registration_preset("vlp16");
    ASSERT_NO_THROW(apply_registration_config(file, options)) << path;
    const RegistrationResult result = register_clouds(pair.source_cloud, pair.target_cloud, options);
    if (result.status == RegistrationStatus::Ok) {
      EXPECT_TRUE(registration_succeeded(result.transform, pair.truth_transform))
          << path << " = " << value.str() << ": ok and wrong";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Crashes.

TEST(RedTeamCrashes, AHugeTrunkHeightIsRefusedAndTheStemMeasureCannotOverflow) {
  const fs::path folder = fresh_folder("trunk");
  const Pair& pair = small_pair();
  const std::string config = write_text(folder / "trunk.yaml", "extraction: {trunks: {minimum_height: 5e18}}\n");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--config", config}),
                 "extraction.trunks.minimum_height");
  // The measure itself, given that height through the API: no stem is tall enough, no crash.
  Eigen::Matrix3Xd points(3, 40);
  std::vector<std::uint32_t> stem;
  for (int i = 0; i < 40; ++i) {
    points.col(i) = Eigen::Vector3d(10.0 + 0.2 * std::cos(i), 0.2 * std::sin(i), 0.1 * i);
    stem.push_back(static_cast<std::uint32_t>(i));
  }
  TrunkOptions options;
  options.minimum_height = 5e18;
  EXPECT_LT(stem_radius_across_view(points, stem, options, Eigen::Vector3d::Zero()), 0.0);
}

TEST(RedTeamCrashes, APoseOrOriginBeyondFloatRangeIsRefused) {
  const fs::path folder = fresh_folder("far_pose");
  const Pair& pair = small_pair();
  const std::string pose = write_text(folder / "far.txt", "1 0 0 1e39\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  const std::string identity = write_text(folder / "identity.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_REFUSED(run_quadrix({"model", pair.source, pair.target, "--poses", identity + "," + pose, "--no-page", "--out",
                              (folder / "m.json").string()}),
                 "no longer finite");
  EXPECT_FALSE(fs::exists(folder / "m.json"));
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--source-origin", "1e308,0,0"}), "--source-origin");
  EXPECT_REFUSED(run_quadrix({"model", pair.source, "--picture", (folder / "p.png").string(), "--view-azimuth", "inf",
                              "--no-page", "--out", (folder / "m.json").string()}),
                 "--view-azimuth");
}

// ---------------------------------------------------------------------------------------------
// Outputs.

TEST(RedTeamOutputs, NothingButARegularFileIsReplacedAndNoInputOrOtherOutputIsOverwritten) {
  const fs::path folder = fresh_folder("outputs");
  const Pair& pair = small_pair();
  const std::string source_copy = (folder / "scan.ply").string();
  fs::copy_file(pair.source, source_copy);
  const std::string before = read_text(source_copy);
  const std::vector<std::string> model = {"model", source_copy, "--preset", "vlp16", "--no-page"};
  const auto with = [&model](std::vector<std::string> more) {
    std::vector<std::string> args = model;
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  // The scan as its own output, through its path or a symlink to it.
  EXPECT_REFUSED(run_quadrix(with({"--out", source_copy})), "same file");
  fs::create_symlink(source_copy, folder / "link.json");
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "link.json").string()})), "same file");
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "m.json").string(), "--mesh", source_copy})), "same file");
  EXPECT_EQ(read_text(source_copy), before);
  // Two outputs on one path.
  const std::string m = (folder / "m.json").string();
  EXPECT_REFUSED(run_quadrix(with({"--out", m, "--binary", m})), "same file");
  EXPECT_FALSE(fs::exists(m));
  // A FIFO, a symlink to it, a folder, a dangling symlink, /proc.
  ASSERT_EQ(::mkfifo((folder / "fifo").c_str(), 0644), 0);
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "fifo").string()})), "not a regular file");
  EXPECT_TRUE(fs::is_fifo(folder / "fifo"));
  fs::create_symlink(folder / "fifo", folder / "fifo_link");
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "fifo_link").string()})), "not a regular file");
  EXPECT_TRUE(fs::is_fifo(folder / "fifo"));
  fs::create_directories(folder / "a_folder");
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "a_folder").string()})), "is a folder");
  fs::create_symlink(folder / "nothing", folder / "dangling");
  EXPECT_REFUSED(run_quadrix(with({"--out", (folder / "dangling").string()})), "symlink to nothing");
  EXPECT_REFUSED(run_quadrix(with({"--out", "/proc/self/quadrix.json"})), "system folder");
  EXPECT_REFUSED(run_quadrix(with({"--out", "/dev/null"})), "system folder");
  // A missing parent folder is created.
  const CommandRun made = run_quadrix(with({"--out", (folder / "m0" / "deeper" / "model.json").string()}));
  EXPECT_EQ(made.exit_code, 0) << describe(made);
  EXPECT_TRUE(fs::is_regular_file(folder / "m0" / "deeper" / "model.json"));
  // view never replaces what it shows.
  const std::string model_json = (folder / "m0" / "deeper" / "model.json").string();
  const std::string model_text = read_text(model_json);
  EXPECT_REFUSED(run_quadrix({"view", model_json, "--out", model_json}), "same file");
  EXPECT_EQ(read_text(model_json), model_text);
  // No temporary is left anywhere.
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

TEST(RedTeamOutputs, ARegisterFolderChangesWholeOrNotAtAllAndAForeignFolderIsRefusedBeforeTheWork) {
  const fs::path folder = fresh_folder("register_out");
  const Pair& pair = small_pair();
  const std::string out = (folder / "out").string();
  const CommandRun first = run_quadrix({"register", pair.source, pair.target, "--no-page", "--out", out});
  ASSERT_EQ(first.exit_code, 0) << describe(first);
  std::vector<std::pair<std::string, std::string>> old_files;
  for (const fs::directory_entry& entry : fs::directory_iterator(out))
    old_files.emplace_back(entry.path().filename().string(), read_text(entry.path()));
  std::sort(old_files.begin(), old_files.end());
  // Interrupted at several moments: the folder is the old one or a whole new one, never a mix, and
  // nothing temporary is left beside it.
  const std::string config = write_text(folder / "other.yaml", "matching: {top_k_similar: 19}\n");
  for (const double after_s : {0.2, 0.8, 1.6}) {
    const CommandRun interrupted =
        run_quadrix({"register", pair.source, pair.target, "--no-page", "--config", config, "--out", out}, 120.0, after_s);
    EXPECT_FALSE(interrupted.timed_out) << describe(interrupted);
    std::vector<std::pair<std::string, std::string>> files;
    for (const fs::directory_entry& entry : fs::directory_iterator(out))
      files.emplace_back(entry.path().filename().string(), read_text(entry.path()));
    std::sort(files.begin(), files.end());
    const bool all_old = files == old_files;
    bool all_new = files.size() == old_files.size();
    for (std::size_t i = 0; all_new && i < files.size(); ++i) all_new = files[i].first == old_files[i].first;
    if (!all_old) {
      // A whole new folder: its report names the configuration of the interrupted run's own merged cloud.
      EXPECT_TRUE(all_new) << "after " << after_s << " s: the folder's file set changed";
      const std::string report = read_text(fs::path(out) / "report.json");
      EXPECT_NE(report.find("\"status\""), std::string::npos);
    }
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder)) {
      const std::string name = entry.path().filename().string();
      EXPECT_EQ(name.find(".tmp-"), std::string::npos) << entry.path();
      EXPECT_EQ(name.find(".staging-"), std::string::npos) << entry.path();
    }
    old_files = files;
  }
  // A folder holding something register does not write is refused before any work.
  write_text(fs::path(out) / "notes.txt", "mine");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--out", out}), "notes.txt");
  EXPECT_EQ(read_text(fs::path(out) / "notes.txt"), "mine");
  (void)start;
  // An output that is a file, or under /proc: refused (exit 2) before the work.
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--out", pair.source}), "not a folder");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--out", "/proc/quadrix"}), "system folder");
}

// Every entry below `folder`: relative path -> bytes (a folder: "<folder>").
std::map<std::string, std::string> folder_snapshot(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder))
    files[fs::relative(entry.path(), folder).string()] = entry.is_directory() ? "<folder>" : read_text(entry.path());
  return files;
}

// Staging folders and temporary files anywhere below `folder`.
std::vector<std::string> leftovers(const fs::path& folder) {
  std::vector<std::string> found;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".staging-") != std::string::npos || name.find(".tmp-") != std::string::npos)
      found.push_back(entry.path().string());
  }
  return found;
}

std::vector<std::string> with_out(std::vector<std::string> args, const fs::path& out) {
  args.push_back("--out");
  args.push_back(out.string());
  return args;
}

// Every command that writes a folder: a first run fills it; a second run with other options (so its
// folder differs) interrupted by SIGTERM halfway through the first run's time leaves the first
// folder byte for byte, or (if it finished first) a whole new one; run to the end it replaces the
// folder whole (its file set is that of the same run into a fresh folder); nothing temporary is left.
TEST(RedTeamOutputs, EveryCommandsOutputFolderChangesWholeOrNotAtAll) {
  const fs::path parent = fresh_folder("folder_commands");
  const Pair& pair = small_pair();
  const std::string pairs_tsv = write_text(parent / "pairs.tsv",
                                           "id\tsource\ttarget\tgt\tkind\n" "small\t" + pair.source + "\t" + pair.target +
                                               "\t" + pair.truth + "\tsynthetic\n");
  const std::string scans_tsv = write_text(parent / "SCANS.tsv", "session\tscan\todometry\na\t" + pair.target + "\t-\na\t" +
                                                                     pair.source + "\t-\n");
  struct FolderCommand {
    std::string name;
    std::vector<std::string> first, second;
  };
  const std::vector<FolderCommand> commands = {
      {"synth", {"synth", "street", "--seed", "1", "--sensor", "vlp16", "--poses", "0,0,1.8,0;6,0,1.8,10"},
       {"synth", "street", "--seed", "2", "--sensor", "vlp16", "--poses", "0,0,1.8,0"}},
      {"synth_drive", {"synth", "drive", "--sessions", "vlp16", "--scans", "2", "--seed", "1"},
       {"synth", "drive", "--sessions", "vlp16", "--scans", "3", "--seed", "2"}},
      {"fitter_segments", {"fitter-segments", "--scans", "1", "--object-scans", "1", "--seed", "1"},
       {"fitter-segments", "--scans", "1", "--object-scans", "1", "--seed", "2"}},
      {"compare_fitters",
       {"compare-fitters", "--types", "plane", "--noise", "0", "--partiality", "1", "--outliers", "0", "--trials", "1",
        "--no-real", "--no-scans", "--threads", "1"},
       {"compare-fitters", "--types", "plane,sphere", "--noise", "0", "--partiality", "1", "--outliers", "0", "--trials",
        "1", "--no-real", "--no-scans", "--threads", "1"}},
      {"compare_refiners",
       {"compare-refiners", "--scenes", "street", "--losses", "none", "--outlier-fractions", "0", "--noise", "0.01",
        "--trials", "1", "--no-real", "--threads", "1"},
       {"compare-refiners", "--scenes", "street", "--losses", "none,huber", "--outlier-fractions", "0", "--noise", "0.01",
        "--trials", "1", "--no-real", "--threads", "1"}},
      {"bench", {"bench", "--pairs", pairs_tsv, "--method", "quadrix", "--no-progress", "--preset", "vlp16"},
       {"bench", "--pairs", pairs_tsv, "--method", "quadrix", "--no-progress", "--preset", "vlp16", "--yaw-range", "30"}},
      {"map", {"map", scans_tsv, "--preset", "vlp16"}, {"map", scans_tsv, "--preset", "vlp16", "--map-voxel", "0.5"}},
  };
  int interrupted_runs = 0;
  for (const FolderCommand& command : commands) {
    SCOPED_TRACE(command.name);
    const fs::path out = parent / command.name;
    const auto start = std::chrono::steady_clock::now();
    const CommandRun first = run_quadrix(with_out(command.first, out));
    const double first_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_EQ(first.exit_code, 0) << describe(first);
    const std::map<std::string, std::string> old_files = folder_snapshot(out);
    ASSERT_FALSE(old_files.empty());
    // Interrupted halfway: the old folder byte for byte, or a whole new one if the run won the race.
    const CommandRun interrupted = run_quadrix(with_out(command.second, out), 120.0, 0.5 * first_s);
    EXPECT_FALSE(interrupted.timed_out) << describe(interrupted);
    if (interrupted.signal == SIGTERM) {
      ++interrupted_runs;
      EXPECT_TRUE(folder_snapshot(out) == old_files) << "the interrupted run changed the folder";
    } else {
      EXPECT_EQ(interrupted.exit_code, 0) << describe(interrupted);
    }
    EXPECT_EQ(leftovers(parent), std::vector<std::string>{});
    // Run to the end: the folder is replaced whole (the file set of a fresh run's folder).
    const CommandRun second = run_quadrix(with_out(command.second, out));
    ASSERT_EQ(second.exit_code, 0) << describe(second);
    const fs::path fresh = parent / (command.name + "_fresh");
    ASSERT_EQ(run_quadrix(with_out(command.second, fresh)).exit_code, 0);
    std::vector<std::string> names, fresh_names;
    for (const auto& [name, bytes] : folder_snapshot(out)) names.push_back(name);
    for (const auto& [name, bytes] : folder_snapshot(fresh)) fresh_names.push_back(name);
    EXPECT_EQ(names, fresh_names);
    EXPECT_FALSE(folder_snapshot(out) == old_files);
    EXPECT_EQ(leftovers(parent), std::vector<std::string>{});
  }
  std::printf("interrupted %d of %zu commands\n", interrupted_runs, commands.size());
  EXPECT_GE(interrupted_runs, 4) << "too few runs were interrupted to test anything";

  // compare-fitters and compare-refiners share their folder (papers/studies holds both studies):
  // another file there stays, and their own files are replaced together.
  write_text(parent / "compare_fitters" / "notes.txt", "mine");
  const CommandRun shared = run_quadrix(with_out(commands[3].first, parent / "compare_fitters"));
  EXPECT_EQ(shared.exit_code, 0) << describe(shared);
  EXPECT_EQ(read_text(parent / "compare_fitters" / "notes.txt"), "mine");
  EXPECT_TRUE(fs::exists(parent / "compare_fitters" / "fitters.md"));
  EXPECT_EQ(leftovers(parent), std::vector<std::string>{});

  // Checked before the work: a folder holding a file the command does not write, a file, an input.
  write_text(parent / "synth" / "notes.txt", "mine");
  EXPECT_REFUSED(run_quadrix(with_out(commands[0].first, parent / "synth")), "notes.txt");
  EXPECT_EQ(read_text(parent / "synth" / "notes.txt"), "mine");
  EXPECT_REFUSED(run_quadrix(with_out(commands[0].first, pairs_tsv)), "not a folder");
  EXPECT_REFUSED(run_quadrix({"bench", "merge", (parent / "bench").string(), "--out", (parent / "bench").string()}),
                 "holds the input");
  const fs::path holding_input = parent / "holding_input";
  fs::create_directories(holding_input);
  fs::copy_file(pair.source, holding_input / "map.ply");  // a name map writes, but an input
  const std::string inner_scans = write_text(parent / "inner.tsv", "session\tscan\todometry\na\t" + pair.target +
                                                                       "\t-\na\t" + (holding_input / "map.ply").string() + "\t-\n");
  EXPECT_REFUSED(run_quadrix(with_out({"map", inner_scans, "--preset", "vlp16"}, holding_input)), "holds the input");
  EXPECT_REFUSED(run_quadrix(with_out(commands[0].first, "/proc/quadrix_out")), "system folder");
}

// A plane of many points (a flat 100 x 100 m square, 1 cm of noise) registered onto itself: one
// plane leaves three motions free, so the answer is `degenerate`, said as such, and comes quickly
// (a 3 M-point plane ran 82 s before, 300 k points 38 s; the time is not asserted, the deadline only
// turns a hang into a failure).
TEST(RedTeamHangs, ALargeSinglePlaneIsDegenerate) {
  const fs::path folder = fresh_folder("plane");
  std::mt19937 random(5);
  std::uniform_real_distribution<float> across(-50.0f, 50.0f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  PointCloud plane;
  plane.positions.resize(3, 600000);
  for (Eigen::Index i = 0; i < plane.positions.cols(); ++i)
    plane.positions.col(i) = Eigen::Vector3f(across(random), across(random), noise(random));
  const std::string path = (folder / "plane.ply").string();
  write_point_cloud(path, plane);
  const CommandRun run = run_quadrix({"register", path, path, "--verbose"}, 300.0);
  ASSERT_EQ(run.exit_code, 0) << describe(run);
  EXPECT_NE(run.output.find("status degenerate"), std::string::npos) << describe(run);
  EXPECT_NE(run.output.find("lie on one plane"), std::string::npos) << describe(run);
  EXPECT_EQ(run.output.find("status ok"), std::string::npos) << describe(run);
}

// ---------------------------------------------------------------------------------------------
// Inputs.

TEST(RedTeamInputs, AFifoAsCloudTruthConfigOrLabelsIsRefusedInsteadOfBlocking) {
  const fs::path folder = fresh_folder("fifo_inputs");
  const Pair& pair = small_pair();
  const std::string fifo = (folder / "pipe.ply").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::string fifo_yaml = (folder / "pipe.yaml").string();
  ASSERT_EQ(::mkfifo(fifo_yaml.c_str(), 0644), 0);
  const std::string fifo_txt = (folder / "pipe.txt").string();
  ASSERT_EQ(::mkfifo(fifo_txt.c_str(), 0644), 0);
  EXPECT_REFUSED(run_quadrix({"register", fifo, pair.target}, 20.0), "not a regular file");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--gt", fifo_txt}, 20.0), "not a regular file");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--config", fifo_yaml}, 20.0), "not a regular file");
  EXPECT_REFUSED(run_quadrix({"config", "--preset", "vlp16", "--config", fifo_yaml}, 20.0), "not a regular file");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--labels-source", fifo_txt}, 20.0),
                 "not a regular file");
}

TEST(RedTeamInputs, SizesAreCheckedFirstAndMessagesStayShort) {
  const fs::path folder = fresh_folder("sizes");
  const Pair& pair = small_pair();
  // A configuration over 1 MiB is refused before it is parsed.
  {
    std::ofstream big(folder / "big.yaml");
    big << "matching: {thresholds: [";
    for (int i = 0; i < 300000; ++i) big << "0.1, ";
    big << "0.2]}\n";
  }
  EXPECT_REFUSED(run_quadrix({"config", "--preset", "vlp16", "--config", (folder / "big.yaml").string()}), "bytes");
  // A .pcd.bin whose size is not a multiple of 20 bytes.
  write_text(folder / "odd.pcd.bin", std::string(1001, 'x'));
  EXPECT_REFUSED(run_quadrix({"info", (folder / "odd.pcd.bin").string()}), "not a multiple of 20");
  // A 4 MB token where a number belongs: the message stays short.
  const std::string token(4 << 20, 'z');
  write_text(folder / "pose.txt", token + " 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  const CommandRun long_token = run_quadrix({"register", pair.source, pair.target, "--gt", (folder / "pose.txt").string()});
  EXPECT_REFUSED(long_token, "is not a number");
  EXPECT_LT(long_token.output.size(), 2000u);
  write_text(folder / "value.yaml", "sensor: " + std::string(500000, 'q') + "\n");
  const CommandRun long_value = run_quadrix({"config", "--preset", "vlp16", "--config", (folder / "value.yaml").string()});
  EXPECT_REFUSED(long_value, "sensor");
  EXPECT_LT(long_value.output.size(), 2000u);
  // A NaN on the first line of a pose file is reported on line 1.
  write_text(folder / "nan.txt", "nan 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--gt", (folder / "nan.txt").string()}), "line 1:");
}

// ---------------------------------------------------------------------------------------------
// Exit codes.

TEST(RedTeamExitCodes, UsageAndInputErrorsExitWithTwo) {
  const fs::path folder = fresh_folder("exit_codes");
  const Pair& pair = small_pair();
  EXPECT_EQ(run_quadrix({"register", pair.source}).exit_code, 2);                 // a missing argument
  EXPECT_EQ(run_quadrix({"register", pair.source, pair.target, "--bogus"}).exit_code, 2);  // an unknown option
  EXPECT_EQ(run_quadrix({"view", pair.source, "--points", "0", "--out", "x.html"}).exit_code, 2);  // out of range
  EXPECT_EQ(run_quadrix({}).exit_code, 2);                                          // no subcommand
  EXPECT_EQ(run_quadrix({"--help"}).exit_code, 0);
  const std::string huge = write_text(folder / "huge.yaml", "ambiguity: {half_turn_samples: 9223372036854775808}\n");
  EXPECT_REFUSED(run_quadrix({"config", "--preset", "vlp16", "--config", huge}), "ambiguity.half_turn_samples");
  EXPECT_REFUSED(run_quadrix({"register", pair.source, pair.target, "--config", huge}), "ambiguity.half_turn_samples");
  // quadrix config refuses what register would: the same read, the same ranges.
  for (const char* setting : {"matching: {top_k_similar: 0}", "estimation: {max_iterations: 0}",
                                     "matching: {clique_threads: -1}", "modelling: {augmentation_voxel: 0}",
                                     "estimation: {ground_weight: -1}", "dense_search: {correspondence_distance: 2}"}) {
    const std::string file = write_text(folder / "setting.yaml", std::string(setting) + "\n");
    const CommandRun run = run_quadrix({"config", "--preset", "vlp16", "--config", file});
    EXPECT_EQ(run.exit_code, 2) << setting << "\n" << describe(run);
    EXPECT_NE(run.output.find(file), std::string::npos) << describe(run);
  }
  // A model JSON of the wrong shape given to view names the file.
  const std::string json = write_text(folder / "model.json", "{\"quadrics\": \"not a list\", \"records\": 7}\n");
  const CommandRun view = run_quadrix({"view", json, "--out", (folder / "page.html").string()});
  EXPECT_EQ(view.exit_code, 2) << describe(view);
  EXPECT_NE(view.output.find("model.json"), std::string::npos) << describe(view);
}

// ---------------------------------------------------------------------------------------------
// The verification cannot be switched off by the dense search's own parameters.

TEST(RedTeamVerification, TheLargestAcceptedCorrespondenceDistanceGivesNoWrongOkOn3dtk) {
  QUADRIX_REQUIRE_SHARED_DATA("3dtk/scan000_RH_m.xyz");
  const fs::path folder = fresh_folder("3dtk");
  const RegistrationConfigKey* key = find_registration_config_key("dense_search.correspondence_distance");
  ASSERT_NE(key, nullptr);
  std::ostringstream value;
  value << key->maximum;
  const std::string config = write_text(folder / "cd.yaml", "dense_search: {correspondence_distance: " + value.str() + "}\n");
  const std::string refused = write_text(folder / "cd2.yaml", "dense_search: {correspondence_distance: 2}\n");
  const auto data = [](const std::string& name) { return testing::shared_data_path("3dtk/" + name); };
  EXPECT_REFUSED(run_quadrix({"register", data("scan001_RH_m.xyz"), data("scan000_RH_m.xyz"), "--config", refused}),
                 "dense_search.correspondence_distance");
  for (const auto& [source, target, truth] :
       {std::tuple{"scan001_RH_m.xyz", "scan000_RH_m.xyz", "T_scan000_from_scan001_RH_m.txt"},
        std::tuple{"scan002_RH_m.xyz", "scan001_RH_m.xyz", "T_scan001_from_scan002_RH_m.txt"}}) {
    const CommandRun run = run_quadrix({"register", data(source), data(target), "--gt", data(truth), "--config", config});
    ASSERT_EQ(run.exit_code, 0) << describe(run);
    const bool ok = run.output.find("status ok") != std::string::npos;
    const bool failure = run.output.find("FAILURE") != std::string::npos;
    EXPECT_FALSE(ok && failure) << source << " -> " << target << " at correspondence_distance " << value.str() << ": ok and wrong\n"
                                << run.output;
  }
}

}  // namespace
}  // namespace quadrix
