#pragma once
/// \file `crackle sweep` with its accuracy: the routed scene's sweep and, when it is estimated
/// (accuracy: section, DETECTION.md sec. 1), one refinement sweep per error component (mesh: the
/// two lower element orders; modes: twice the band; harmonics: H + 2), silent, in temporary
/// folders, sharing the modal and reduction caches. The estimated quantities are the sweep's
/// summary: each probe's peaks (value and frequency), the fold and bifurcation frequencies (the
/// turning points) and the bilinear frequency. With a tolerance, the component with the largest
/// error per unit cost is refined until the estimate meets it or the budget is spent.
#include <iosfwd>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/route.hpp"
#include "pipeline/sweep.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// One sweep: its sweep.json document (without route and accuracy), wall time and points (the
/// caller may release them).
struct SweepOutcome {
  nlohmann::json document;
  double wall_s = 0.0;
  SweepResult result;
};

/// One sweep of `scene` into options.output_directory: sweep.csv and the plots written, the summary
/// printed to `out`; sweep.json is the caller's to write.
SweepOutcome sweep_scene(const scene::Scene& scene, const SweepCommandOptions& options, std::ostream& out,
                         std::ostream& progress);

/// Sweeps `scene` (the user's scene with `overrides`, the route's included) into
/// options.output_directory, estimates its summary when the scene asks for it, and writes
/// sweep.json with `route` and `accuracy`.
void sweep_with_accuracy(const scene::Scene& scene, const RunRoute& route, const std::vector<scene::Override>& overrides,
                         const SweepCommandOptions& options, std::ostream& out, std::ostream& progress);

}  // namespace crackle::pipeline
