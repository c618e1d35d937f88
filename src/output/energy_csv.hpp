#pragma once
/// \file energy.csv: the energy balance of a transient over time (the output layer).
#include <filesystem>

#include "transient/solver.hpp"

namespace crackle::output {

/// energy.csv: time and the EnergyHistory columns with units.
void write_energy_csv(const std::filesystem::path& path, const transient::EnergyHistory& energy);

}  // namespace crackle::output
