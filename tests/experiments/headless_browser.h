// Opens a page in Debian's chromium, headless, from disk with no network, and reports what the
// browser made of it: the DOM after the scripts ran, the console, the page's own markers
// (data-ready-ms, data-error) and the statistics of a 1280x800 screenshot. One browser run takes
// both the DOM and the screenshot (Chromium's headless mode accepts --dump-dom with --screenshot),
// which halves the page tests' time against a run for each. For the page tests only: include it from
// one translation unit per test executable (it defines stb_image's implementation).
#pragma once

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace quadrix::test {

/// The browser the page tests run; they skip when it is not installed.
inline const char* const kChromium = "/usr/bin/chromium";

/// Whether the page tests' browser is installed.
inline bool chromium_available() { return std::filesystem::exists(kChromium); }

/// The whole content of a file ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A new folder under the system's temporary folder, named after `name` and the clock.
inline std::filesystem::path fresh_directory(const std::string& name) {
  const std::filesystem::path directory =
      std::filesystem::temp_directory_path() /
      ("quadrix_page_" + name + "_" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  std::filesystem::create_directories(directory);
  return directory;
}

/// What the browser made of a page.
struct BrowserView {
  std::string dom;              ///< the DOM after the scripts ran (--dump-dom)
  std::string console;          ///< chromium's console lines (INFO:CONSOLE)
  double ready_ms = -1.0;       ///< data-ready-ms: performance.now() when the first frame was drawn
  std::string error;            ///< data-error, empty when none
  int canvas_colours = 0;       ///< distinct colours in the 3-D view's part of the screenshot
  double canvas_drawn = 0.0;    ///< fraction of that part that is not the white background
};

/// The chromium command line; `webgl` false: a browser that cannot create a WebGL context (WebGL
/// and the 3-D APIs off, no software GL), as a locked-down browser or a remote desktop without GPU.
inline std::string chromium_command(const std::filesystem::path& profile, bool webgl = true) {
  return std::string(kChromium) +
         (webgl ? " --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader"
                : " --headless --no-sandbox --disable-gpu --disable-webgl --disable-3d-apis") +
         " --disable-quic --no-first-run"
         " --disable-background-networking --disable-component-update --disable-sync --enable-logging=stderr --v=0"
         " --window-size=1280,800 --user-data-dir='" + profile.string() + "'";
}

/// Opens `page` (with an optional "#..." fragment) once in a fresh profile, dumping the DOM and taking
/// a 1280x800 screenshot; the 3-D view is the window's left part (the side panel is 360 px wide).
inline BrowserView open_in_browser(const std::filesystem::path& page, const std::string& fragment = "", bool webgl = true) {
  const std::filesystem::path work = fresh_directory("browser");
  const std::string url = "'file://" + std::filesystem::absolute(page).string() + fragment + "'";
  const std::filesystem::path dom_path = work / "dom.html", log_path = work / "browser.log", shot = work / "shot.png";
  BrowserView view;
  EXPECT_EQ(std::system(("timeout 120 " + chromium_command(work / "profile", webgl) + " --screenshot='" + shot.string() + "' --dump-dom " +
                         url + " > '" + dom_path.string() + "' 2> '" + log_path.string() + "'")
                            .c_str()),
            0)
      << read_text(log_path);
  view.dom = read_text(dom_path);
  std::istringstream lines(read_text(log_path));
  for (std::string line; std::getline(lines, line);)
    if (line.find(":CONSOLE") != std::string::npos) view.console += line + "\n";
  std::smatch match;
  if (std::regex_search(view.dom, match, std::regex("data-ready-ms=\"([0-9.]+)\""))) view.ready_ms = std::stod(match[1]);
  if (std::regex_search(view.dom, match, std::regex("data-error=\"([^\"]*)\""))) view.error = match[1];
  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load(shot.string().c_str(), &width, &height, &channels, 3);
  EXPECT_NE(pixels, nullptr) << shot << ": not a PNG the screenshot should have written";
  if (pixels != nullptr) {
    std::set<unsigned> colours;
    std::size_t drawn = 0, total = 0;
    for (int y = 40; y < height - 40; ++y)
      for (int x = 10; x < width - 380; ++x) {
        const unsigned char* p = pixels + 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
        colours.insert((unsigned{p[0]} << 16) | (unsigned{p[1]} << 8) | p[2]);
        drawn += (p[0] < 245 || p[1] < 245 || p[2] < 245) ? 1 : 0;
        ++total;
      }
    view.canvas_colours = static_cast<int>(colours.size());
    view.canvas_drawn = total ? static_cast<double>(drawn) / static_cast<double>(total) : 0.0;
    stbi_image_free(pixels);
  }
  std::filesystem::remove_all(work);
  return view;
}

}  // namespace quadrix::test
