#pragma once
/// \file PNG plots of time histories, amplitude spectra, ring-down envelopes and FRFs, drawn by
/// gnuplot through plot/gnuplot.hpp.
/// Each plot writes three files side by side: `<name>.dat` (the data, with units in a
/// comment line), `<name>.gp` (a gnuplot script that reads the data by file name, so the
/// folder can be moved and re-plotted) and `<name>.png`. Plotting never throws: a missing
/// gnuplot or a failure gives `written == false` and a note, and the run goes on.
#include <filesystem>
#include <string>
#include <vector>

#include "plot/gnuplot.hpp"
#include "spectral/harmonics.hpp"
#include "spectral/ringdown.hpp"
#include "spectral/spectrum.hpp"

namespace crackle::spectral {

using plot::PlotOptions;
using plot::PlotResult;

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

}  // namespace crackle::spectral
