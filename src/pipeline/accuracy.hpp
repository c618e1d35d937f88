#pragma once
/// \file `crackle run` with its accuracy: the routed scene's run and, when its signatures are
/// estimated (accuracy: section, DETECTION.md sec. 1), one refinement run per error component
/// (mesh: the two lower element orders; modes: twice the band; steps: twice per period; penalty:
/// four times), silent, in temporary folders, sharing the modal and reduction caches. With a
/// tolerance, the component with the largest error per unit cost is refined until the estimate meets
/// it or the budget is spent. The numbers are combined by accuracy/estimate.hpp; this file wires.
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/commands.hpp"
#include "pipeline/route.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// run.json and sweep.json `route`: model, automatic, reason, and the own mesh beside the scene's.
nlohmann::json route_json(const RunRoute& route);

/// Runs `scene` (the user's scene with `overrides`, the route's included) into
/// options.output_directory, estimates its signatures when the scene asks for it, and writes
/// spectrum.json (with `accuracy`) and run.json (with `route` and `accuracy`).
void run_with_accuracy(const scene::Scene& scene, const RunRoute& route, const std::vector<scene::Override>& overrides,
                       const RunCommandOptions& options, std::ostream& out);

}  // namespace crackle::pipeline
