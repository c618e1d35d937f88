#include "spectral/plot.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace crackle::spectral {
namespace fs = std::filesystem;
namespace {

std::string order_label(double order) {
  const long twice = std::lround(2.0 * order);
  return twice % 2 == 0 ? std::to_string(twice / 2) : std::to_string(twice) + "/2";
}


/// Written whole or not at all: a temporary beside it, renamed over it.
void write_text(const fs::path& path, const std::string& text) {
  const fs::path temporary = fs::path(path).concat(".tmp");
  std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  std::error_code error;
  if (!out || (fs::rename(temporary, path, error), error)) {
    fs::remove(temporary, error);
    throw IoError("cannot write " + path.string());
  }
}

std::string terminal_lines(const PlotOptions& options) {
  const std::string size = std::to_string(options.width) + "," + std::to_string(options.height);
  return "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
         "  set terminal pngcairo size " + size + " noenhanced\n"
         "} else {\n"
         "  set terminal png size " + size + " noenhanced\n"
         "}\n";
}

/// gnuplot on a written script in the PNG's folder; the PNG checked.
void run_script(const fs::path& png, const fs::path& script, const PlotOptions& options, PlotResult& result) {
  const fs::path folder = png.has_parent_path() ? png.parent_path() : fs::path(".");
  const fs::path gnuplot = find_executable(options.gnuplot);
  if (gnuplot.empty()) {
    result.note = "gnuplot ('" + options.gnuplot + "') not found: " + png.filename().string() +
                  " not drawn; data and script written";
    return;
  }
  std::error_code ignored;
  fs::remove(png, ignored);
  const std::string command = "cd " + shell_quote(folder.string()) + " && " + shell_quote(gnuplot.string()) + " " +
                              shell_quote(script.filename().string()) + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) {
    result.note = "could not start gnuplot";
    return;
  }
  char buffer[512];
  std::string output;
  while (std::fgets(buffer, sizeof buffer, pipe)) {
    if (output.size() < 4000) output += buffer;
  }
  const int status = ::pclose(pipe);
  std::error_code error;
  const bool made = fs::is_regular_file(png, error) && fs::file_size(png, error) > 0;
  result.written = status == 0 && made;
  result.note = result.written ? output : "gnuplot failed (status " + std::to_string(status) + "): " + output;
}

/// Writes data and script, runs gnuplot in the PNG's folder, checks the PNG.
PlotResult draw(const fs::path& png, const std::string& data, const std::string& script_body,
                const PlotOptions& options) {
  PlotResult result;
  result.png = png;
  result.data = fs::path(png).replace_extension(".dat");
  result.script = fs::path(png).replace_extension(".gp");
  try {
    std::string script = "# gnuplot script written by crackle; run: gnuplot " +
                         result.script.filename().string() + "\n" + terminal_lines(options) +
                         "set output " + gnuplot_quote(png.filename().string()) + "\n" +
                         "set title " + gnuplot_quote(options.title) + "\nset grid\n" + script_body;
    write_text(result.data, data);
    write_text(result.script, script);
    run_script(png, result.script, options, result);
  } catch (const std::exception& error) {
    result.written = false;
    result.note = error.what();
  }
  return result;
}

}  // namespace

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

/// A gnuplot single-quoted string (no escapes inside except '' for ').
std::string gnuplot_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return quoted + "'";
}

/// Full path of the executable, or empty.
fs::path find_executable(const std::string& name) {
  if (name.empty()) return {};
  const auto runnable = [](const fs::path& path) {
    std::error_code error;
    return fs::is_regular_file(path, error) && ::access(path.c_str(), X_OK) == 0;
  };
  if (name.find('/') != std::string::npos) return runnable(name) ? fs::path(name) : fs::path();
  const char* path_variable = std::getenv("PATH");
  if (!path_variable) return {};
  std::stringstream entries(path_variable);
  std::string directory;
  while (std::getline(entries, directory, ':')) {
    if (directory.empty()) continue;
    const fs::path candidate = fs::path(directory) / name;
    if (runnable(candidate)) return candidate;
  }
  return {};
}

PlotResult run_gnuplot(const fs::path& png, const fs::path& script, const PlotOptions& options) {
  PlotResult result;
  result.png = png;
  result.script = script;
  try {
    run_script(png, script, options, result);
  } catch (const std::exception& error) {
    result.written = false;
    result.note = error.what();
  }
  return result;
}

PlotResult plot_script(const fs::path& png, const std::string& data, const std::string& script_body,
                       const PlotOptions& options) {
  return draw(png, data, script_body, options);
}

bool gnuplot_available(const PlotOptions& options) {
  return !find_executable(options.gnuplot).empty();
}

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
  return draw(png, data, body, options);
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
  return draw(png, data, body, options);
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
  return draw(png, data, body, options);
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
  return draw(png, data, body, options);
}

}  // namespace crackle::spectral
