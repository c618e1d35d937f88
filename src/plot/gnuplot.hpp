#pragma once
/// \file gnuplot for every figure of crackle: a figure is `<name>.dat` (the data, units in a comment
/// line), `<name>.gp` (a script that reads the data by file name, so the folder can be moved and
/// re-plotted) and `<name>.png`, written whole. Plotting never throws: a missing gnuplot or a
/// failure gives `written == false` and a note, and the command goes on. Also the shell and gnuplot
/// quoting and the PATH lookup the commands share.
#include <filesystem>
#include <string>

namespace crackle::plot {

/// Labels and the gnuplot to use.
struct PlotOptions {
  std::string title;                    ///< plot title (may be empty)
  std::string quantity = "displacement";  ///< what the signal is, for the y label
  std::string unit = "m";               ///< unit of the signal
  std::string gnuplot = "gnuplot";      ///< executable: a name looked up in PATH, or a path
  int width = 1000, height = 600;       ///< the PNG's size [pixels]
  /// false: the data and the script are written, gnuplot is not run (a figure that may never be
  /// looked at, drawn later by run_gnuplot on its script: an accuracy refinement run's).
  bool draw = true;
};

/// Outcome of a plot.
struct PlotResult {
  bool written = false;  ///< the PNG exists and is not empty
  std::string note;      ///< why not, or gnuplot's messages
  std::filesystem::path data, script, png;
};

/// A word quoted for the POSIX shell.
std::string shell_quote(const std::string& text);
/// A gnuplot single-quoted string (no escapes inside except '' for ').
std::string gnuplot_quote(const std::string& text);
/// Full path of an executable (a path, or a bare name looked up in PATH), or empty.
std::filesystem::path find_executable(const std::string& name);

/// Whether the gnuplot of the options can be found (PATH lookup for a bare name).
bool gnuplot_available(const PlotOptions& options);

/// Runs gnuplot on `script`, already written in the PNG's folder and drawing `png` there (the
/// folder is gnuplot's working directory), and checks the PNG. For figures of several data files;
/// the others are plot_script's.
PlotResult run_gnuplot(const std::filesystem::path& png, const std::filesystem::path& script,
                       const PlotOptions& options);

/// Any plot: writes `data` as `<name>.dat` and a script of `script_body` (after the terminal,
/// output, title and grid lines) as `<name>.gp`, and runs gnuplot in the PNG's folder.
PlotResult plot_script(const std::filesystem::path& png, const std::string& data, const std::string& script_body,
                       const PlotOptions& options);

}  // namespace crackle::plot
