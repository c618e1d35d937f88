#pragma once
/// \file PNG plots of time histories and amplitude spectra, drawn by gnuplot.
/// Each plot writes three files side by side: `<name>.dat` (the data, with units in a
/// comment line), `<name>.gp` (a gnuplot script that reads the data by file name, so the
/// folder can be moved and re-plotted) and `<name>.png`. Plotting never throws: a missing
/// gnuplot or a failure gives `written == false` and a note, and the run goes on.
#include <filesystem>
#include <string>
#include <vector>

#include "spectral/harmonics.hpp"
#include "spectral/ringdown.hpp"
#include "spectral/spectrum.hpp"

namespace crackle::spectral {

/// Labels and the gnuplot to use.
struct PlotOptions {
  std::string title;                    ///< plot title (may be empty)
  std::string quantity = "displacement";  ///< what the signal is, for the y label
  std::string unit = "m";               ///< unit of the signal
  std::string gnuplot = "gnuplot";      ///< executable: a name looked up in PATH, or a path
  int width = 1000, height = 600;       ///< the PNG's size [pixels]
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

/// (a) Time history x(t_i), t_i = start_time + i dt, as lines: time [s] vs quantity [unit].
PlotResult plot_time_history(const std::filesystem::path& png, const std::vector<double>& values,
                             const Sampling& sampling, const PlotOptions& options);

/// (b) Amplitude spectrum on a log y-scale, with dashed vertical lines labelled "1/2", "1",
/// "2", ... at the given orders of the excitation frequency f (orders 0 are not marked). The
/// x-range ends half an order above the highest order when f > 0. Values below 1e-14 of the
/// largest amplitude are drawn at that floor (the data file keeps them as they are).
PlotResult plot_spectrum(const std::filesystem::path& png, const AmplitudeSpectrum& spectrum,
                         double excitation_frequency_hz, const std::vector<double>& orders,
                         const PlotOptions& options);

/// (c) Ring-down envelope: the amplitude of every order of a ring-down analysis against the centre
/// time of its envelope window, on a log y-scale (an exponential decay is a straight line), one
/// line per order labelled "1/2", "1", "2", ...
PlotResult plot_ringdown_envelope(const std::filesystem::path& png, const RingdownAnalysis& analysis,
                                  const PlotOptions& options);

/// (d) Frequency-response magnitude |H(f)| on a log y-scale, with dashed vertical lines at the
/// given reference frequencies [Hz] (modal frequencies; none when empty). `options.unit` is the
/// unit of H (e.g. "m/N").
PlotResult plot_frf(const std::filesystem::path& png, const FrequencyResponse& frf,
                    const std::vector<double>& reference_hz, const PlotOptions& options);

/// Runs gnuplot on `script`, already written in the PNG's folder and drawing `png` there (the
/// folder is gnuplot's working directory), and checks the PNG. For figures of several data files;
/// the others are plot_script's.
PlotResult run_gnuplot(const std::filesystem::path& png, const std::filesystem::path& script,
                       const PlotOptions& options);

/// Any plot: writes `data` as `<name>.dat` and a script of `script_body` (after the terminal,
/// output, title and grid lines) as `<name>.gp`, and runs gnuplot in the PNG's folder.
PlotResult plot_script(const std::filesystem::path& png, const std::string& data, const std::string& script_body,
                       const PlotOptions& options);

}  // namespace crackle::spectral
