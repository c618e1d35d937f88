#pragma once
/// \file PNG line plots of study results against the varied keys, drawn by gnuplot. Each plot
/// writes `<name>.dat`, `<name>.gp` (re-plot with `gnuplot <name>.gp` in its folder) and
/// `<name>.png`. Plotting never throws: without gnuplot the data and scripts are still written.
#include <filesystem>
#include <string>
#include <vector>

#include "study/plan.hpp"
#include "study/results.hpp"

namespace crackle::study {

/// One line of a plot.
struct Series {
  std::string title;
  std::vector<double> x, y;
};

struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<Series> series;
};

/// Outcome of one plot or of a set of plots.
struct PlotReport {
  std::vector<std::string> written;  ///< PNG files drawn (names relative to the plot folder)
  std::vector<std::string> notes;    ///< what was not drawn, and why
};

/// Draws one line plot (points joined, one line per series) into `png`; `gnuplot` is a name
/// looked up in PATH or a path. Returns an empty string on success, else a note.
std::string plot_lines(const std::filesystem::path& png, const LinePlot& plot, const std::string& gnuplot);

/// Every damage index and first-mode frequency of the table against each varied key, into
/// `folder` as `<column>_vs_<key>.png`. In mode grid the other keys' values make one line each.
/// A key with non-numeric values (or lists whose entries do not vary) is skipped with a note.
PlotReport plot_study(const StudyPlan& plan, const StudyTable& table, const std::filesystem::path& folder,
                      const std::string& gnuplot);

}  // namespace crackle::study
