// Shared pieces of the study reports (`quadrix compare-fitters`, `quadrix compare-refiners`):
// number formatting for CSV and Markdown, medians and percentiles that ignore non-finite values,
// the plot palette, and a small SVG writer for grids of line panels.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace quadrix::report {

/// A value with `precision` significant digits for CSV files; empty for NaN or infinity.
std::string number(double value, int precision = 6);
/// A value with a fixed number of decimals for Markdown; "–" for NaN or infinity.
std::string fixed(double value, int decimals);
/// Median of the finite values (the upper middle one for an even count); NaN when none is finite.
double median(std::vector<double> values);
/// The value at `fraction` (0..1) of the sorted finite values; NaN when none is finite.
double percentile(std::vector<double> values, double fraction);

/// Line colours of every study plot, in series order.
inline constexpr std::array<const char*, 8> kPalette = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                                         "#9467bd", "#8c564b", "#e377c2", "#17becf"};

/// One line of a panel: a value per x tick (NaN leaves a gap in the line).
struct PlotSeries {
  std::string name;            ///< legend text
  std::vector<double> values;  ///< y per x tick, same length as the panel's x_ticks
};

/// One panel of a figure: categorical x ticks, a linear or log10 y axis.
struct PlotPanel {
  std::string title;                  ///< bold text above the panel
  std::string x_label;                ///< text under the x axis
  std::string y_label;                ///< unit shown beside the y tick values (e.g. "%", " ms")
  std::vector<std::string> x_ticks;   ///< x positions, evenly spaced
  std::vector<PlotSeries> series;     ///< lines, coloured by their index in kPalette (then dashed after 8)
  double y_low = 0.0;                 ///< bottom of the y axis (log10 axis: must be > 0)
  double y_high = 100.0;              ///< top of the y axis
  bool log_y = false;                 ///< log10 y axis with a grid line per decade
};

/// Writes panels in a grid of `columns` columns with one shared legend (names from the first panel
/// holding series) as a standalone SVG, atomically. Throws quadrix::Error when a series' length
/// differs from its panel's tick count or a log axis has a non-positive bound.
void write_line_panels_svg(const std::string& path, const std::vector<PlotPanel>& panels, std::size_t columns);

}  // namespace quadrix::report
