#include "study/plot.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "plot/gnuplot.hpp"

namespace crackle::study {
namespace fs = std::filesystem;
using plot::find_executable;
using plot::gnuplot_quote;
using plot::shell_quote;
namespace {

bool write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  return static_cast<bool>(out);
}

/// A file-name-safe form of a column or key: "tip.A2/A1 [-]" -> "tip.A2_A1".
std::string file_word(const std::string& text) {
  std::string word = text.substr(0, text.find(" ["));
  for (char& c : word)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  return word;
}

/// The numbers of a YAML value: one for a number, several for a list of numbers, none otherwise.
std::vector<double> numbers_of(const std::string& yaml) {
  std::vector<double> numbers;
  try {
    const YAML::Node node = YAML::Load(yaml);
    std::vector<YAML::Node> items;
    if (node.IsScalar()) items.push_back(node);
    if (node.IsSequence())
      for (const auto& item : node) items.push_back(item);
    for (const YAML::Node& item : items) {
      if (!item.IsScalar() || item.Tag() == "!") return {};
      char* end = nullptr;
      const double value = std::strtod(item.Scalar().c_str(), &end);
      if (item.Scalar().empty() || *end != '\0' || !std::isfinite(value)) return {};
      numbers.push_back(value);
    }
  } catch (const std::exception&) {
    return {};
  }
  return numbers;
}

}  // namespace

std::string plot_lines(const fs::path& png, const LinePlot& plot, const std::string& gnuplot) {
  const fs::path data = fs::path(png).replace_extension(".dat");
  const fs::path script = fs::path(png).replace_extension(".gp");
  std::string text = "# " + plot.x_label + "  " + plot.y_label + "\n";
  std::string commands;
  int block = 0;
  for (const Series& series : plot.series) {
    if (series.x.empty()) continue;
    if (block > 0) text += "\n\n";
    text += "# " + series.title + "\n";
    std::vector<std::size_t> order(series.x.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return series.x[a] < series.x[b]; });
    for (std::size_t i : order) text += number_text(series.x[i]) + " " + number_text(series.y[i]) + "\n";
    commands += std::string(block ? ", \\\n     ''" : "plot " + gnuplot_quote(data.filename().string())) +
                " index " + std::to_string(block) + " using 1:2 with linespoints pointtype 7 title " +
                gnuplot_quote(series.title);
    ++block;
  }
  if (block == 0) return png.filename().string() + ": no finite values to plot";
  const std::string body =
      "# gnuplot script written by crackle study; run: gnuplot " + script.filename().string() + "\n" +
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n  set terminal pngcairo size 900,600 noenhanced\n"
      "} else {\n  set terminal png size 900,600 noenhanced\n}\n"
      "set output " +
      gnuplot_quote(png.filename().string()) + "\nset title " + gnuplot_quote(plot.title) +
      "\nset grid\nset key outside right\nset xlabel " + gnuplot_quote(plot.x_label) + "\nset ylabel " +
      gnuplot_quote(plot.y_label) + "\n" + commands + "\n";
  if (!write_text(data, text) || !write_text(script, body))
    return png.filename().string() + ": cannot write its data";
  const fs::path program = find_executable(gnuplot);
  if (program.empty())
    return "gnuplot ('" + gnuplot + "') not found: plots not drawn; data and scripts written";
  std::error_code ignored;
  fs::remove(png, ignored);
  const fs::path folder = png.has_parent_path() ? png.parent_path() : fs::path(".");
  const std::string command = "cd " + shell_quote(folder.string()) + " && " + shell_quote(program.string()) +
                              " " + shell_quote(script.filename().string()) + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return png.filename().string() + ": could not start gnuplot";
  std::string output;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe))
    if (output.size() < 2000) output += buffer;
  const int status = ::pclose(pipe);
  std::error_code error;
  if (status != 0 || !fs::is_regular_file(png, error) || fs::file_size(png, error) == 0)
    return png.filename().string() + ": gnuplot failed: " + output;
  return "";
}

PlotReport plot_study(const StudyPlan& plan, const StudyTable& table, const fs::path& folder,
                      const std::string& gnuplot) {
  PlotReport report;
  std::vector<int> columns;
  for (std::size_t c = 0; c < table.headers.size(); ++c) {
    const std::string& header = table.headers[c];
    const bool first_mode = table.kinds[c] == "frequency" && header.find("_1 [") != std::string::npos;
    if (first_mode || table.kinds[c] == "index") columns.push_back(static_cast<int>(c));
  }
  const int status_column = table.column("status");
  const auto& vary = plan.spec.vary;
  bool gnuplot_missing = find_executable(gnuplot).empty();
  if (gnuplot_missing)
    report.notes.push_back("gnuplot ('" + gnuplot +
                           "') not found: plots not drawn; data and scripts written");
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) {
    report.notes.push_back(folder.string() + ": cannot create (" + error.message() + ")");
    return report;
  }

  for (std::size_t k = 0; k < vary.size(); ++k) {
    // x: the number, or the first entry of a list that varies over the cases.
    std::vector<std::vector<double>> values;
    for (const StudyCase& study_case : plan.cases)
      values.push_back(numbers_of(study_case.overrides[k].value));
    const std::size_t width = values.empty() ? 0 : values.front().size();
    bool numeric = width > 0;
    for (const auto& v : values) numeric = numeric && v.size() == width;
    if (!numeric) {
      report.notes.push_back(vary[k].path +
                             ": not plotted (values are not numbers or lists of numbers of one length)");
      continue;
    }
    std::size_t entry = width;
    for (std::size_t j = 0; j < width && entry == width; ++j)
      for (const auto& v : values)
        if (v[j] != values.front()[j]) entry = j;
    if (entry == width) {
      report.notes.push_back(vary[k].path + ": not plotted (a single value)");
      continue;
    }
    const std::string unit = key_unit(vary[k].path);
    const std::string x_label = (width == 1 ? vary[k].path : vary[k].path + "[" + std::to_string(entry) + "]") +
                                (unit.empty() ? "" : " [" + unit + "]");

    for (int column : columns) {
      LinePlot plot;
      plot.title = table.headers[column] + " against " + x_label;
      plot.x_label = x_label;
      plot.y_label = table.headers[column];
      std::map<std::string, std::size_t> series_of;
      for (std::size_t i = 0; i < plan.cases.size(); ++i) {
        const auto& row = table.rows[i];
        if (row[status_column].text != "ok" || !std::isfinite(row[column].number)) continue;
        std::string title;
        if (plan.spec.mode == StudyMode::grid) {
          for (std::size_t other = 0; other < vary.size(); ++other)
            if (other != k)
              title += (title.empty() ? "" : ", ") + vary[other].path + " = " +
                       plan.cases[i].overrides[other].value;
        }
        if (title.empty()) title = table.headers[column];
        const auto found = series_of.find(title);
        const std::size_t s = found != series_of.end() ? found->second : plot.series.size();
        if (found == series_of.end()) {
          series_of[title] = s;
          plot.series.push_back({title, {}, {}});
        }
        plot.series[s].x.push_back(values[i][entry]);
        plot.series[s].y.push_back(row[column].number);
      }
      const std::string name = file_word(table.headers[column]) + "_vs_" + file_word(vary[k].path) + ".png";
      if (plot.series.empty()) {
        report.notes.push_back(name + ": no ok case with a value");
        continue;
      }
      const std::string note = plot_lines(folder / name, plot, gnuplot_missing ? "" : gnuplot);
      if (note.empty())
        report.written.push_back(name);
      else if (!gnuplot_missing)
        report.notes.push_back(note);
    }
  }
  return report;
}

}  // namespace crackle::study
