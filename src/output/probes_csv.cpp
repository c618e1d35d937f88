#include "output/probes_csv.hpp"

#include <string>

#include "io/csv.hpp"

namespace crackle::output {

void write_probe_csv(const std::filesystem::path& path, const transient::ProbeHistory& probes) {
  io::CsvTable table;
  table.add("time [s]", probes.time);
  static const char* quantities[3] = {"u", "v", "a"};
  static const char* units[3] = {"m", "m/s", "m/s^2"};
  static const char* opening_names[3] = {"gap", "slip_1", "slip_2"};
  static const char* opening_suffixes[3] = {"", "_rate", "_acceleration"};
  for (std::size_t p = 0; p < probes.names.size(); ++p) {
    const bool opening = p < probes.opening.size() && probes.opening[p];
    for (int q = 0; q < 3; ++q) {
      for (int c = 0; c < 3; ++c) {
        const std::string quantity = opening ? std::string(opening_names[c]) + opening_suffixes[q]
                                             : std::string(quantities[q]) + "_" + axis_name(c);
        table.add(probes.names[p] + " " + quantity + " [" + units[q] + "]", probes.values[9 * p + 3 * q + c]);
      }
    }
    if (opening) table.add(probes.names[p] + " state [0 open 1 stick 2 slip]", probes.states[p]);
  }
  io::write_csv(path, table);
}

}  // namespace crackle::output
