// Runs a fuzz harness without libFuzzer: every regular file named on the command line, or found
// (recursively, in name order) in a folder named there, is passed once to LLVMFuzzerTestOneInput.
// ctest runs each harness this way over its seeds/ and regressions/ folders, so every reproducer
// stays a regression test. A folder that does not exist is skipped (regressions/<harness> appears
// with its first reproducer); running no input at all is a failure.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int argument = 1; argument < argc; ++argument) {
    const fs::path path(argv[argument]);
    std::error_code code;
    if (fs::is_directory(path, code)) {
      std::vector<fs::path> found;
      for (const fs::directory_entry& entry : fs::recursive_directory_iterator(path))
        if (entry.is_regular_file()) found.push_back(entry.path());
      std::sort(found.begin(), found.end());
      inputs.insert(inputs.end(), found.begin(), found.end());
    } else if (fs::is_regular_file(path, code)) {
      inputs.push_back(path);
    } else {
      std::fprintf(stderr, "replay: skipping %s (no such file or folder)\n", path.c_str());
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "replay: no input files; usage: %s FILE_OR_FOLDER...\n", argc > 0 ? argv[0] : "replay");
    return 1;
  }
  for (const fs::path& input : inputs) {
    std::fprintf(stderr, "replay: %s\n", input.c_str());
    std::fflush(stderr);
    std::ifstream stream(input, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    if (stream.bad()) {
      std::fprintf(stderr, "replay: cannot read %s\n", input.c_str());
      return 1;
    }
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::fprintf(stderr, "replay: %zu inputs passed\n", inputs.size());
  return 0;
}
