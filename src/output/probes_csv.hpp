#pragma once
/// \file probes.csv: the probe histories of a transient (the output layer).
#include <filesystem>

#include "transient/solver.hpp"

namespace crackle::output {

/// probes.csv: "time [s]", then per probe "<name> u_x [m]" ... "<name> a_z [m/s^2]"; an opening probe
/// "<name> gap [m]", "<name> slip_1 [m]", "<name> slip_2 [m]", "<name> gap_rate [m/s]" ...,
/// "<name> gap_acceleration [m/s^2]" ..., "<name> state [0 open 1 stick 2 slip]".
void write_probe_csv(const std::filesystem::path& path, const transient::ProbeHistory& probes);

}  // namespace crackle::output
