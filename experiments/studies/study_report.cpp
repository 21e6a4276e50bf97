// Study report helpers (see study_report.h).
#include "experiments/studies/study_report.h"

#include "geometry/error.h"
#include "geometry/io.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>

namespace quadrix::report {
namespace {

std::vector<double> finite_only(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  return values;
}

}  // namespace

std::string number(double value, int precision) {
  if (!std::isfinite(value)) return "";
  std::ostringstream out;
  out << std::setprecision(precision) << value;
  return out.str();
}

std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "–";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

double median(std::vector<double> values) {
  values = finite_only(std::move(values));
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle), values.end());
  return values[middle];
}

double percentile(std::vector<double> values, double fraction) {
  values = finite_only(std::move(values));
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<std::size_t>(fraction * static_cast<double>(values.size())))];
}

void write_line_panels_svg(const std::string& path, const std::vector<PlotPanel>& panels, std::size_t columns) {
  columns = std::max<std::size_t>(1, columns);
  for (const PlotPanel& panel : panels) {
    for (const PlotSeries& series : panel.series)
      if (series.values.size() != panel.x_ticks.size())
        throw Error("plot '" + panel.title + "': series '" + series.name + "' has " + std::to_string(series.values.size()) +
                    " values for " + std::to_string(panel.x_ticks.size()) + " x ticks");
    if (panel.log_y && !(panel.y_low > 0.0 && panel.y_high > panel.y_low))
      throw Error("plot '" + panel.title + "': a log y axis needs 0 < y_low < y_high");
  }
  const double panel_width = 360, panel_height = 220, left_margin = 70, top_margin = 40, gap_x = 70, gap_y = 80;
  const std::size_t rows = (panels.size() + columns - 1) / columns;
  const PlotPanel* legend_source = nullptr;
  for (const PlotPanel& panel : panels)
    if (!panel.series.empty()) {
      legend_source = &panel;
      break;
    }
  const std::size_t legend_rows = legend_source ? (legend_source->series.size() + 3) / 4 : 0;
  const double width = left_margin + static_cast<double>(columns) * (panel_width + gap_x);
  const double height = top_margin + static_cast<double>(rows) * (panel_height + gap_y) + 20.0 * static_cast<double>(legend_rows) + 10.0;
  const auto dash_of = [](std::size_t index) { return index < kPalette.size() ? "" : " stroke-dasharray=\"6,3\""; };
  write_file_atomically(path, [&](std::ostream& out) {
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    for (std::size_t p = 0; p < panels.size(); ++p) {
      const PlotPanel& panel = panels[p];
      const double x0 = left_margin + static_cast<double>(p % columns) * (panel_width + gap_x);
      const double y0 = top_margin + static_cast<double>(p / columns) * (panel_height + gap_y);
      const double low = panel.log_y ? std::log10(panel.y_low) : panel.y_low;
      const double high = panel.log_y ? std::log10(panel.y_high) : panel.y_high;
      const auto y_of = [&](double value) {
        const double v = panel.log_y ? std::log10(std::max(value, panel.y_low)) : value;
        return y0 + panel_height * (high - std::clamp(v, low, high)) / (high - low);
      };
      const std::size_t ticks = panel.x_ticks.size();
      const auto x_of = [&](std::size_t index) {
        return ticks <= 1 ? x0 + panel_width / 2
                          : x0 + 20.0 + (panel_width - 40.0) * static_cast<double>(index) / static_cast<double>(ticks - 1);
      };
      out << "<text x=\"" << x0 << "\" y=\"" << y0 - 12 << "\" font-weight=\"bold\">" << panel.title << "</text>\n"
          << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << panel_width << "\" height=\"" << panel_height
          << "\" fill=\"none\" stroke=\"black\"/>\n";
      std::vector<double> grid;
      if (panel.log_y)
        for (double decade = std::ceil(low - 1e-9); decade <= high + 1e-9; decade += 1.0) grid.push_back(std::pow(10.0, decade));
      else
        for (int k = 0; k <= 4; ++k) grid.push_back(panel.y_low + (panel.y_high - panel.y_low) * k / 4.0);
      for (const double value : grid) {
        const double y = y_of(value);
        out << "<line x1=\"" << x0 << "\" y1=\"" << y << "\" x2=\"" << x0 + panel_width << "\" y2=\"" << y
            << "\" stroke=\"#ddd\"/>\n<text x=\"" << x0 - 5 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">"
            << number(value, 3) << panel.y_label << "</text>\n";
      }
      for (std::size_t i = 0; i < ticks; ++i)
        out << "<text x=\"" << x_of(i) << "\" y=\"" << y0 + panel_height + 15 << "\" text-anchor=\"middle\">" << panel.x_ticks[i]
            << "</text>\n";
      out << "<text x=\"" << x0 + panel_width / 2 << "\" y=\"" << y0 + panel_height + 32 << "\" text-anchor=\"middle\">"
          << panel.x_label << "</text>\n";
      for (std::size_t s = 0; s < panel.series.size(); ++s) {
        const PlotSeries& series = panel.series[s];
        const char* colour = kPalette[s % kPalette.size()];
        std::string points;
        const auto flush = [&] {
          if (!points.empty())
            out << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"2\"" << dash_of(s) << " points=\"" << points
                << "\"/>\n";
          points.clear();
        };
        for (std::size_t i = 0; i < ticks; ++i) {
          if (!std::isfinite(series.values[i])) {
            flush();
            continue;
          }
          const double x = x_of(i), y = y_of(series.values[i]);
          points += number(x, 6) + "," + number(y, 6) + " ";
          out << "<circle cx=\"" << number(x, 6) << "\" cy=\"" << number(y, 6) << "\" r=\"2.5\" fill=\"" << colour << "\"/>\n";
        }
        flush();
      }
    }
    if (legend_source) {
      const double legend_top = top_margin + static_cast<double>(rows) * (panel_height + gap_y) - 20.0;
      for (std::size_t s = 0; s < legend_source->series.size(); ++s) {
        const double x = left_margin + 200.0 * static_cast<double>(s % 4);
        const double y = legend_top + 20.0 * static_cast<double>(s / 4);
        out << "<line x1=\"" << x << "\" y1=\"" << y - 4 << "\" x2=\"" << x + 18 << "\" y2=\"" << y - 4 << "\" stroke=\""
            << kPalette[s % kPalette.size()] << "\" stroke-width=\"3\"" << dash_of(s) << "/>\n<text x=\"" << x + 24 << "\" y=\""
            << y << "\">" << legend_source->series[s].name << "</text>\n";
      }
    }
    out << "</svg>\n";
  });
}

}  // namespace quadrix::report
