#include "plot/gnuplot.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"

namespace crackle::plot {
namespace fs = std::filesystem;
namespace {

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
    if (!options.draw) {
      result.note = "not drawn (its script " + result.script.filename().string() + " is written)";
      return result;
    }
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

}  // namespace crackle::plot
