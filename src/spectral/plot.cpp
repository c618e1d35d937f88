#include "spectral/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"

namespace crackle::spectral {
namespace fs = std::filesystem;
namespace {

std::string order_label(double order) {
  const long twice = std::lround(2.0 * order);
  return twice % 2 == 0 ? std::to_string(twice / 2) : std::to_string(twice) + "/2";
}

}  // namespace

using plot::gnuplot_quote;

PlotResult plot_time_history(const fs::path& png, const std::vector<double>& values,
                             const Sampling& sampling, const PlotOptions& options) {
  std::string data = "# time [s]  " + options.quantity + " [" + options.unit + "]\n";
  for (std::size_t i = 0; i < values.size(); ++i) {
    data += shortest_text(sampling.start_time + static_cast<double>(i) * sampling.time_step);
    data += ' ';
    data += shortest_text(values[i]);
    data += '\n';
  }
  const std::string body =
      "set autoscale xfix\nset xlabel 'time [s]'\nset ylabel " +
      gnuplot_quote(options.quantity + " [" + options.unit + "]") + "\n" + "plot " +
      gnuplot_quote(fs::path(png).replace_extension(".dat").filename().string()) +
      " using 1:2 with lines linewidth 1 notitle\n";
  return plot::plot_script(png, data, body, options);
}

PlotResult plot_spectrum(const fs::path& png, const AmplitudeSpectrum& spectrum,
                         double excitation_frequency_hz, const std::vector<double>& orders,
                         const PlotOptions& options) {
  std::string data = "# frequency [Hz]  amplitude [" + options.unit + "]\n";
  double largest = 0.0;
  for (std::size_t k = 0; k < spectrum.frequency_hz.size(); ++k) {
    data += shortest_text(spectrum.frequency_hz[k]);
    data += ' ';
    data += shortest_text(std::abs(spectrum.amplitude[k]));  // a log scale: bin 0 (the signed mean) by size
    data += '\n';
    if (std::isfinite(spectrum.amplitude[k])) largest = std::max(largest, std::abs(spectrum.amplitude[k]));
  }
  const double floor = largest > 0.0 ? 1e-14 * largest : 1e-300;
  std::string body = "set logscale y\nset xlabel 'frequency [Hz]'\nset ylabel " +
                     gnuplot_quote("amplitude [" + options.unit + "]") + "\n";
  double highest = 0.0;
  if (excitation_frequency_hz > 0.0) {
    for (double order : orders) {
      if (order <= 0.0) continue;
      highest = std::max(highest, order);
      const std::string x = shortest_text(order * excitation_frequency_hz);
      body += "set arrow from " + x + ", graph 0 to " + x +
              ", graph 1 nohead dashtype 2 linecolor rgb 'gray50'\n";
      body += "set label " + gnuplot_quote(order_label(order)) + " at " + x +
              ", graph 0.96 center front\n";
    }
    if (highest > 0.0) {
      body += "set xrange [0:" + shortest_text((highest + 0.5) * excitation_frequency_hz) + "]\n";
    }
  }
  body += "plot " + gnuplot_quote(fs::path(png).replace_extension(".dat").filename().string()) +
          " using 1:($2 > " + shortest_text(floor) + " ? $2 : " + shortest_text(floor) +
          ") with lines linewidth 1.5 notitle\n";
  return plot::plot_script(png, data, body, options);
}

PlotResult plot_ringdown_envelope(const fs::path& png, const RingdownAnalysis& analysis,
                                  const PlotOptions& options) {
  std::string data = "# window centre time [s], then the amplitude [" + options.unit + "] of the orders";
  for (const RingdownHarmonic& harmonic : analysis.harmonics) data += " " + order_label(harmonic.order);
  data += "\n";
  for (const EnvelopeWindow& window : analysis.envelope) {
    data += shortest_text(0.5 * (window.start_time + window.end_time));
    for (double amplitude : window.amplitude) {
      data += ' ';
      data += shortest_text(std::abs(amplitude));
    }
    data += '\n';
  }
  std::string body = "set logscale y\nset xlabel 'time [s]'\nset ylabel " +
                     gnuplot_quote("amplitude [" + options.unit + "]") + "\nset key outside right\nplot ";
  const std::string file = gnuplot_quote(fs::path(png).replace_extension(".dat").filename().string());
  for (std::size_t k = 0; k < analysis.harmonics.size(); ++k) {
    body += (k ? ", " : "") + file + " using 1:($" + std::to_string(k + 2) + " > 0 ? $" + std::to_string(k + 2) +
            " : NaN) with linespoints linewidth 1.5 pointtype 7 pointsize 0.6 title " +
            gnuplot_quote(order_label(analysis.harmonics[k].order) + " f");
  }
  body += "\n";
  return plot::plot_script(png, data, body, options);
}

PlotResult plot_frf(const fs::path& png, const FrequencyResponse& frf, const std::vector<double>& reference_hz,
                    const PlotOptions& options) {
  std::string data = "# frequency [Hz]  |H| [" + options.unit + "]  arg H [rad]\n";
  for (std::size_t k = 0; k < frf.frequency_hz.size(); ++k) {
    data += shortest_text(frf.frequency_hz[k]) + ' ' + shortest_text(frf.magnitude[k]) + ' ' +
            shortest_text(frf.phase_rad[k]) + '\n';
  }
  std::string body = "set logscale y\nset xlabel 'frequency [Hz]'\nset ylabel " +
                     gnuplot_quote("|H| [" + options.unit + "]") + "\n";
  for (double f : reference_hz) {
    const std::string x = shortest_text(f);
    body += "set arrow from " + x + ", graph 0 to " + x + ", graph 1 nohead dashtype 2 linecolor rgb 'gray50'\n";
  }
  body += "plot " + gnuplot_quote(fs::path(png).replace_extension(".dat").filename().string()) +
          " using 1:($2 > 0 ? $2 : NaN) with lines linewidth 1.5 notitle\n";
  return plot::plot_script(png, data, body, options);
}

}  // namespace crackle::spectral
