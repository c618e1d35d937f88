#include "output/energy_csv.hpp"

#include "io/csv.hpp"

namespace crackle::output {

void write_energy_csv(const std::filesystem::path& path, const transient::EnergyHistory& energy) {
  io::CsvTable table;
  table.add("time [s]", energy.time);
  table.add("kinetic [J]", energy.kinetic);
  table.add("strain [J]", energy.strain);
  table.add("contact [J]", energy.contact);
  table.add("external_work [J]", energy.external_work);
  table.add("damping [J]", energy.damping);
  table.add("friction [J]", energy.friction);
  table.add("balance [J]", energy.balance);
  table.add("relative_error [-]", energy.relative_error);
  io::write_csv(path, table);
}

}  // namespace crackle::output
