// The study section and its cases: ranges and lists, grid and zip, exact messages with file:line and
// key path, every key of the scene format can be varied, bad overrides fail before anything runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "scene/schema.hpp"
#include "study/plan.hpp"
#include "study/results.hpp"

namespace crackle::study {
namespace {

/// A cantilever with an edge crack normal to `normal` (x or y); lines 1-14.
std::string base_scene(const std::string& normal = "x") {
  const std::string crack =
      normal == "x" ? "  plane: {normal: x, at: 0.05}\n  region: {y: [0.0, 0.02], z: [0.007, 0.01]}\n"
                    : "  plane: {normal: y, at: 0.01}\n  region: {x: [0.04, 0.06], z: [0.007, 0.01]}\n";
  return "mesh:\n"
         "  box:\n"
         "    origin: [0, 0, 0]\n"
         "    size: [0.2, 0.02, 0.01]\n"
         "    cells: [20, 2, 2]\n"
         "    order: 1\n"
         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
         "boundary:\n"
         "  - {face: x-, fix: [x, y, z], value: [0, 0, 0]}\n"
         "crack:\n" +
         crack +
         "  gap: 0.0\n"
         "modal: {modes: 4, variants: [uncracked, open], solver: slepc, mass: consistent}\n";
}

std::string error_of(const std::string& text) {
  try {
    plan_study(text, "beam.yaml");
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(StudyPlan, GridOfARangeAndAList) {
  const std::string text = base_scene() +
                           "study:\n"
                           "  vary:\n"
                           "    crack.region.z: {from: [0.009, 0.01], to: [0.005, 0.01], steps: 5}\n"
                           "    modal.mass: [consistent, lumped]\n"
                           "  outputs: [spectrum, modal]\n";
  const StudyPlan plan = plan_study(text, "beam.yaml");
  ASSERT_EQ(plan.cases.size(), 10u);
  EXPECT_EQ(plan.spec.outputs, (std::vector<std::string>{"modal", "spectrum"}));
  EXPECT_EQ(plan.spec.vary[0].values,
            (std::vector<std::string>{"[0.009, 0.01]", "[0.008, 0.01]", "[0.007, 0.01]", "[0.006, 0.01]",
                                      "[0.005, 0.01]"}));
  // First key slowest.
  EXPECT_EQ(plan.cases[1].overrides[0].value, "[0.009, 0.01]");
  EXPECT_EQ(plan.cases[1].overrides[1].value, "lumped");
  EXPECT_EQ(plan.cases[9].overrides[0].value, "[0.005, 0.01]");
  // The case scene is the base scene with the overrides, and reads back as such.
  const scene::Scene case_scene = scene::parse_scene(plan.cases[7].scene_text, "case.yaml");
  EXPECT_EQ(case_scene.crack->region[2][0], 0.006);
  EXPECT_EQ(case_scene.modal.mass, scene::MassMatrix::lumped);
  EXPECT_EQ(case_scene.material.young, 210e9);
  EXPECT_EQ(
      plan.cases[7].scene_text.rfind("# case 7 (crack.region.z = [0.006, 0.01], modal.mass = lumped)", 0),
      0u);
  std::set<std::string> hashes;
  for (const StudyCase& c : plan.cases) hashes.insert(c.hash);
  EXPECT_EQ(hashes.size(), plan.cases.size());
}

TEST(StudyPlan, ZipPairsTheValues) {
  const std::string text = base_scene() +
                           "study:\n"
                           "  mode: zip\n"
                           "  vary:\n"
                           "    material.E: {from: 200e9, to: 220e9, steps: 3}\n"
                           "    modal.modes: [3, 4, 5]\n";
  const StudyPlan plan = plan_study(text, "beam.yaml");
  ASSERT_EQ(plan.cases.size(), 3u);
  EXPECT_EQ(plan.cases[1].overrides[0].value, "2.1e11");
  EXPECT_EQ(plan.cases[1].overrides[1].value, "4");
  EXPECT_EQ(plan.spec.outputs, std::vector<std::string>{"modal"});
}

TEST(StudyPlan, StudySectionIsBlankedKeepingLines) {
  const std::string text = "study:\n  vary: {material.nu: [0.2, 0.25]}\n\n" + base_scene();
  const std::string stripped = strip_study_section(text, "beam.yaml");
  EXPECT_EQ(stripped, "\n\n\n" + base_scene());
  // A problem of the base scene keeps its line (material is on line 3 + 7).
  std::string broken = text;
  broken.replace(broken.find("E: 210.0e9"), 10, "E: -1");
  EXPECT_EQ(error_of(broken), "beam.yaml:10: material.E: expected a positive number, got -1");
  // A flow-style document loses its lines but not its content.
  const std::string flow = "{study: {vary: {material.nu: [0.2]}}, material: {E: 1}}";
  EXPECT_EQ(strip_study_section(flow, "f.yaml"), "material:\n  E: 1\n");
}

TEST(StudyPlan, MessagesNameFileLineAndPath) {
  const std::string base = base_scene();  // 14 lines: the study starts on line 15
  const auto study = [&](const std::string& body) { return error_of(base + "study:\n" + body); };
  EXPECT_EQ(
      error_of(base),
      "beam.yaml: study: expected a section study: {vary: {key.path: [values]}, mode, outputs}, got nothing");
  EXPECT_EQ(study("  vary: {material.nu: [0.2]}\n  mdoe: zip\n"),
            "beam.yaml:17: study.mdoe: expected one of vary, mode, outputs, got unknown key 'mdoe' (did you "
            "mean 'mode'?)");
  EXPECT_EQ(study("  vary: {material.nu: [0.2]}\n  mode: cartesian\n"),
            "beam.yaml:17: study.mode: expected one of grid, zip, got 'cartesian'");
  EXPECT_EQ(study("  vary: {material.nu: [0.2]}\n  outputs: [modal, spectra]\n"),
            "beam.yaml:17: study.outputs[1]: expected one of modal, spectrum, sweep, got 'spectra' (did you mean "
            "'spectrum'?)");
  EXPECT_EQ(study("  mode: zip\n"),
            "beam.yaml:15: study.vary: expected a map from scene key paths (e.g. crack.region.z) to lists of "
            "values or ranges, got nothing");
  EXPECT_EQ(study("  vary:\n    material.nu: 0.2\n"),
            "beam.yaml:17: study.vary.material.nu: expected a list of values [a, b, ...] or a range {from, "
            "to, steps}, got 0.2");
  // The keys listed are the table's (names() below), which grows with the scene format.
  const auto names = [](const scene::Param& param) {
    std::string text;
    for (const scene::Param& child : param.children) text += (text.empty() ? "" : ", ") + child.name;
    return text;
  };
  const scene::Param& root = scene::scene_parameters();
  EXPECT_EQ(study("  vary:\n    crack.regoin.z: [[0.005, 0.01]]\n"),
            "beam.yaml:17: study.vary.crack.regoin.z: expected a scene key (keys of crack: " +
                names(*root.child("crack")) + "), got 'crack.regoin.z' (did you mean 'crack.region'?)");
  EXPECT_EQ(study("  vary:\n    materail.E: [1e9]\n"),
            "beam.yaml:17: study.vary.materail.E: expected a scene key (sections: " + names(root) +
                "), got 'materail.E' (did you mean 'material'?)");
  EXPECT_EQ(
      study("  vary:\n    boundary.face: [x+]\n"),
      "beam.yaml:17: study.vary.boundary.face: expected an index after boundary, as in boundary[0].face, got "
      "'boundary.face'");
  EXPECT_EQ(study("  vary:\n    crack.gap.x: [1]\n"),
            "beam.yaml:17: study.vary.crack.gap.x: expected a scene key, got 'crack.gap.x' (crack.gap has no "
            "keys below it)");
  EXPECT_EQ(study("  vary:\n    crack.region.z: {from: [0.009, 0.01], to: 0.005, steps: 3}\n"),
            "beam.yaml:17: study.vary.crack.region.z.to: expected a list of 2 numbers, like from, got 0.005");
  EXPECT_EQ(study("  vary:\n    material.E: {from: 1e9, to: 2e9, steps: 1}\n"),
            "beam.yaml:17: study.vary.material.E.steps: expected an integer in 2..100000 (a study has at most "
            "100000 cases), got 1");
  EXPECT_EQ(study("  vary:\n    material.E: {from: 1e9, to: 2e9, step: 3}\n"),
            "beam.yaml:17: study.vary.material.E.step: expected one of from, to, steps, got unknown key "
            "'step' (did you "
            "mean 'steps'?)");
  EXPECT_EQ(
      study("  vary:\n    crack.region: [{y: [0, 0.02], z: [0.006, 0.01]}]\n    crack.region.z: [[0.005, "
            "0.01]]\n"),
      "beam.yaml:18: study.vary.crack.region.z: expected keys that do not overlap, got 'crack.region.z' and "
      "'crack.region'");
  EXPECT_EQ(
      study("  mode: zip\n  vary:\n    material.E: [1e9, 2e9]\n    material.nu: [0.2]\n"),
      "beam.yaml:19: study.vary.material.nu: expected as many values as material.E (2) in mode zip, got 1");
}

TEST(StudyPlan, AKeyThatNoOutputReadsIsRefused) {
  const std::string base = base_scene();  // 14 lines: the study starts on line 15
  const auto study = [&](const std::string& body) { return error_of(base + "study:\n" + body); };
  const std::string advice =
      " reads (every case would be the same run); add the output that uses it to study.outputs (spectrum: crackle "
      "run, sweep: crackle sweep) or vary another key";
  // The default output is modal: crackle modal never steps in time.
  EXPECT_EQ(study("  vary:\n    transient.time_step: [1.0e-7, 2.0e-7]\n"),
            "beam.yaml:17: study.vary.transient.time_step: expected a key that an output of study.outputs (modal) "
            "reads, got 'transient.time_step', which crackle modal never" + advice);
  EXPECT_EQ(study("  vary:\n    spectrum.harmonics: [3, 5]\n  outputs: [modal]\n"),
            "beam.yaml:17: study.vary.spectrum.harmonics: expected a key that an output of study.outputs (modal) "
            "reads, got 'spectrum.harmonics', which crackle modal never" + advice);
  EXPECT_EQ(study("  vary:\n    sweep.points: [10, 20]\n  outputs: [spectrum]\n"),
            "beam.yaml:17: study.vary.sweep.points: expected a key that an output of study.outputs (spectrum) "
            "reads, got 'sweep.points', which crackle run never" + advice);
  EXPECT_EQ(study("  vary:\n    sweep.points: [10, 20]\n  outputs: [modal, spectrum]\n"),
            "beam.yaml:17: study.vary.sweep.points: expected a key that an output of study.outputs (modal, "
            "spectrum) reads, got 'sweep.points', which none of their commands" + advice);
  // What an output reads is not refused, and one output that reads the key is enough.
  EXPECT_EQ(output_reads("modal", "crack.region.z"), true);
  EXPECT_EQ(output_reads("modal", "mesh.box.cells[0]"), true);
  EXPECT_EQ(output_reads("modal", "transient.damping.ratio"), false);
  EXPECT_EQ(output_reads("spectrum", "transient.damping.ratio"), true);
  EXPECT_EQ(output_reads("spectrum", "sweep.points"), false);
  EXPECT_EQ(output_reads("sweep", "transient.damping.ratio"), true);
  EXPECT_EQ(output_reads("sweep", "identify.unknowns"), false);
  EXPECT_EQ(error_of(base + "transient:\n  duration: 0.01\nstudy:\n  vary:\n    transient.duration: [0.01, 0.02]\n"
                            "  outputs: [modal, spectrum]\n"),
            "(no error)");
}

TEST(StudyPlan, BadOverrideNamesTheCaseAndPath) {
  const auto study = [&](const std::string& body) { return error_of(base_scene() + "study:\n" + body); };
  EXPECT_EQ(study("  vary:\n    material.nu: [0.2, 0.7]\n"),
            "beam.yaml:17: study.vary.material.nu: case 1 (material.nu = 0.7): material.nu: expected a "
            "number in (-1, "
            "0.5), got 0.7");
  // The message of mesh::check_crack, after the case and the key path.
  EXPECT_EQ(study("  vary:\n    modal.mass: [lumped]\n    crack.region.z: [[0.007, 0.01], [0.007, 0.011]]\n")
                .rfind("beam.yaml:18: study.vary.crack.region.z: case 1 (modal.mass = lumped, crack.region.z "
                       "= [0.007, "
                       "0.011]): crack.region.z",
                       0),
            0u);
  EXPECT_NE(study("  vary:\n    boundary[3].face: [x+]\n")
                .find("study.vary: case 0 (boundary[3].face = x+): boundary: "),
            std::string::npos);
  EXPECT_NE(
      study("  vary:\n    modal.modes: ['4']\n").find("modal.modes: expected a positive integer, got '4'"),
      std::string::npos);
}

/// The declared parameter of a leaf path such as boundary[0].value.
const scene::Param* param_at(const std::string& path) {
  std::string clean;
  bool in_index = false;
  for (char c : path) {
    if (c == '[') in_index = true;
    if (!in_index) clean += c;
    if (c == ']') in_index = false;
  }
  const scene::Param* param = &scene::scene_parameters();
  std::size_t start = 0;
  while (param && start <= clean.size()) {
    const std::size_t dot = std::min(clean.find('.', start), clean.size());
    param = param->child(clean.substr(start, dot - start));
    start = dot + 1;
  }
  return param;
}

/// The current value at a leaf path as YAML text, or "" if the validated scene lacks it.
std::string value_text(const scene::Values& values, const std::string& path) {
  const scene::Param* param = param_at(path);
  if (!param || !values.has(path)) return "";
  std::vector<std::string> parts;
  for (double n : values.numbers(path))
    parts.push_back(param->kind == scene::Kind::boolean ? (n != 0 ? "true" : "false") : format_number(n));
  for (const std::string& w : values.words(path)) parts.push_back(w);
  if (!param->is_list_of_scalars()) return parts.at(0);
  std::string text = "[";
  for (std::size_t i = 0; i < parts.size(); ++i) text += (i ? ", " : "") + parts[i];
  return text + "]";
}

/// Layered materials on a box mesh (the materials list instead of material).
const std::string kPlies =
    "mesh: {box: {size: [0.2, 0.02, 0.01], cells: [20, 2, 2], order: 1}}\n"
    "materials:\n"
    "  - {name: steel, isotropic: {E: 210e9, nu: 0.3}, rho: 7850, region: {x: [0, 0.2], y: [0, 0.02], z: [0, "
    "0.005]}}\n"
    "  - name: ply\n"
    "    orthotropic: {E1: 140e9, E2: 10e9, E3: 10e9, G12: 5e9, G13: 5e9, G23: 3.5e9, nu12: 0.3, nu13: 0.3, "
    "nu23: 0.4}\n"
    "    rho: 1600\n"
    "    angle: 30\n"
    "    region: {z: [0.005, 0.01]}\n";

/// A Gmsh mesh with physical groups (the file is read only when the model is built).
const std::string kGmsh =
    "mesh: {gmsh: beam.msh}\n"
    "materials:\n"
    "  - {name: steel, isotropic: {E: 210e9, nu: 0.3}, rho: 7850, region: {group: body}}\n"
    "boundary:\n"
    "  - {group: clamp, fix: [x, y, z]}\n"
    "crack: {group: crack}\n";

TEST(StudyPlan, EveryKeyOfTheSceneFormatCanBeVaried) {
  std::vector<std::string> bases;
  for (const std::string& base : {base_scene("x"), base_scene("y"), kPlies, kGmsh}) {
    try {
      scene::parse_scene(base, "base.yaml");
      bases.push_back(base);
    } catch (const InputError& error) {  // the scene format changed under this test
      std::cout << "note: a base scene of this test no longer reads: " << error.what() << "\n";
    }
  }
  std::set<std::string> checked;
  std::vector<std::string> unchecked;
  for (const std::string& path : leaf_key_paths()) {
    EXPECT_EQ(check_key_path(path), "") << path;
    bool done = false;
    for (std::size_t b = 0; b < bases.size() && !done; ++b) {
      const scene::Values values =
          scene::validate(scene::scene_parameters(), scene::parse_yaml(bases[b], "base.yaml"), "base.yaml");
      // The first list entry that has the key: materials[1].orthotropic.E1.
      for (int entry = 0; entry < 4 && !done; ++entry) {
        std::string instance = path;
        const std::size_t index = instance.find("[0]");
        if (index != std::string::npos) instance.replace(index, 3, "[" + std::to_string(entry) + "]");
        const std::string value = value_text(values, instance);
        if (value.empty()) continue;
        // The current value, twice, so that the study has two cases.
        // With an output whose command reads the key (a study varying a key none reads is refused).
        const std::string output = output_reads("modal", instance)      ? "modal"
                                   : output_reads("spectrum", instance) ? "spectrum"
                                                                        : "sweep";
        const std::string text = bases[b] + "study:\n  vary:\n    " + instance + ": [" + value + ", " + value +
                                 "]\n  outputs: [" + output + "]\n";
        try {
          const StudyPlan plan = plan_study(text, "base.yaml");
          EXPECT_EQ(plan.cases.size(), 2u) << instance;
          EXPECT_EQ(plan.cases[0].overrides[0].value, value) << instance;
          EXPECT_EQ(plan.cases[1].scene_text.substr(plan.cases[1].scene_text.find('\n')),
                    plan.cases[0].scene_text.substr(plan.cases[0].scene_text.find('\n')))
              << instance;
        } catch (const InputError& error) {
          ADD_FAILURE() << instance << " = " << value << ": " << error.what();
        }
        done = true;
      }
    }
    if (done)
      checked.insert(path);
    else
      unchecked.push_back(path);
  }
  // The keys known when this test was written must all be covered by the base scenes above.
  for (const std::string& path :
       {"mesh.box.origin",    "mesh.box.size",  "mesh.box.cells",   "mesh.box.order",  "material.E",
        "material.nu",        "material.rho",   "boundary[0].face", "boundary[0].fix", "boundary[0].value",
        "crack.plane.normal", "crack.plane.at", "crack.region.x",   "crack.region.y",  "crack.region.z",
        "crack.gap",          "modal.modes",    "modal.variants",   "modal.solver",    "modal.mass"})
    EXPECT_TRUE(checked.count(path)) << path;
  for (const std::string& path : unchecked)
    std::cout << "note: " << path << " is absent from the test scenes: add it to one to check it\n";
  // List entries can be addressed too.
  EXPECT_EQ(check_key_path("mesh.box.cells[1]"), "");
  EXPECT_EQ(
      plan_study(base_scene() + "study:\n  vary:\n    mesh.box.cells[0]: [20, 40]\n", "b.yaml").cases.size(),
      2u);
  EXPECT_NE(check_key_path("mesh.box.cells[1].x"), "");
  EXPECT_NE(check_key_path("study.vary"), "");
}

TEST(StudyPlan, SharedCrackLinesAreTheUnionOfVaryingEdges) {
  std::vector<scene::Scene> scenes;
  for (const char* z : {"[0.007, 0.01]", "[0.005, 0.01]", "[0.006, 0.01]"})
    scenes.push_back(scene::parse_scene(base_scene(), "b.yaml", {{"crack.region.z", z}}));
  const auto lines = shared_crack_lines(scenes);
  EXPECT_TRUE(lines[0].empty());
  EXPECT_TRUE(lines[1].empty());  // every case has the same y extent
  EXPECT_EQ(lines[2], (std::vector<double>{0.005, 0.006, 0.007, 0.01}));
}

TEST(StudyPlan, ModalCacheKeyIgnoresWhatTheUncrackedModesDoNotDependOn) {
  const StudyPlan gaps =
      plan_study(base_scene() + "study:\n  vary:\n    crack.gap: [0, 1e-6, 2e-6]\n", "b.yaml");
  EXPECT_EQ(gaps.cases[0].modal_key, gaps.cases[1].modal_key);
  EXPECT_EQ(gaps.cases[0].modal_key, gaps.cases[2].modal_key);
  EXPECT_NE(gaps.cases[0].hash, gaps.cases[1].hash);
  const StudyPlan stiffness =
      plan_study(base_scene() + "study:\n  vary:\n    material.E: [1e11, 2e11]\n", "b.yaml");
  EXPECT_NE(stiffness.cases[0].modal_key, stiffness.cases[1].modal_key);
  // Crack depths mesh differently unless the cases share grid lines (mesh.box.lines).
  const StudyPlan depths = plan_study(
      base_scene() + "study:\n  vary:\n    crack.region.z: [[0.007, 0.01], [0.006, 0.01]]\n", "b.yaml");
  EXPECT_EQ(depths.cases[0].modal_key == depths.cases[1].modal_key, depths.shares_grid_lines);
  // The primer solves the uncracked modes only.
  const scene::Scene primer = scene::parse_scene(gaps.cases[0].primer_text, "primer.yaml");
  EXPECT_EQ(primer.modal.variants, std::vector<mesh::Variant>{mesh::Variant::uncracked});
  // A scene with a run and its spectrum on the scene's mesh (transient.model: full) still has a
  // primer (the spectrum needs the transient).
  const std::string run_scene = base_scene() +
                                "transient:\n  model: full\n  excitation: {face: x+, direction: z, amplitude: 1.0, frequency: 100}\n"
                                "  periods: 2\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\n"
                                "spectrum: {harmonics: 3}\n";
  const StudyPlan runs = plan_study(run_scene + "study:\n  vary:\n    crack.gap: [0, 1e-6]\n  outputs: [spectrum]\n",
                                    "b.yaml");
  ASSERT_FALSE(runs.cases[0].primer_text.empty());
  EXPECT_EQ(scene::parse_scene(runs.cases[0].primer_text, "primer.yaml").modal.variants,
            std::vector<mesh::Variant>{mesh::Variant::uncracked});
  // Its modes are those of the run's mesh: mesh.box.grading auto meshes a run uniformly, crackle modal
  // graded, so the primer says none. With an accuracy section (which needs the transient) too.
  const StudyPlan accurate = plan_study(run_scene + "accuracy: {estimate: off}\nstudy:\n  vary:\n    crack.gap: [0, 1e-6]\n"
                                                    "  outputs: [spectrum]\n", "b.yaml");
  ASSERT_FALSE(accurate.cases[0].primer_text.empty());
  EXPECT_EQ(scene::parse_scene(accurate.cases[0].primer_text, "primer.yaml").grading.mode, scene::GradingMode::none);
  EXPECT_EQ(accurate.cases[0].modal_key, runs.cases[0].modal_key);
  const StudyPlan both = plan_study(run_scene + "study:\n  vary:\n    crack.gap: [0, 1e-6]\n  outputs: [modal, spectrum]\n",
                                    "b.yaml");
  EXPECT_EQ(scene::parse_scene(both.cases[0].primer_text, "primer.yaml").grading.mode, scene::GradingMode::automatic);
  // The spectrum and the sweep (the primer drops both) do not split the cache either: the sweeps of one
  // crack at several drive frequencies share the modes and the reduction.
  const StudyPlan windows = plan_study(run_scene + "study:\n  vary:\n    spectrum.harmonics: [3, 5]\n  outputs: [spectrum]\n",
                                       "b.yaml");
  EXPECT_EQ(windows.cases[0].modal_key, windows.cases[1].modal_key);
  EXPECT_NE(windows.cases[0].hash, windows.cases[1].hash);
  const StudyPlan sweeps = plan_study(run_scene + "sweep: {frequency: {from: 90, to: 110}, points: 10}\n"
                                                  "study:\n  vary:\n    sweep.frequency.from: [80, 90]\n  outputs: [sweep]\n",
                                      "b.yaml");
  EXPECT_EQ(sweeps.cases[0].modal_key, sweeps.cases[1].modal_key);
  EXPECT_NE(sweeps.cases[0].hash, sweeps.cases[1].hash);
  EXPECT_EQ(sweeps.cases[0].modal_key, windows.cases[0].modal_key);
}

// Cases whose run takes the automatic route's own graded mesh (transient.model: auto, a harmonic
// drive, a spectrum, a breathing crack) mesh themselves: no shared crack lines or fronts (a mesh
// with every case's fronts would make the route lower its order) and no primer on the scene's mesh.
// The same cases run on the scene's mesh (transient.model: full) share one.
TEST(StudyPlan, CasesOnTheRoutesOwnMeshMeshThemselves) {
  const std::string transient =
      "  excitation: {face: x+, direction: z, amplitude: 1.0, frequency: 100}\n"
      "  periods: 2\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\nspectrum: {harmonics: 3}\n"
      "study:\n  vary:\n    crack.region.z: [[0.007, 0.01], [0.006, 0.01]]\n  outputs: [spectrum]\n";
  const StudyPlan routed = plan_study(base_scene() + "transient:\n" + transient, "b.yaml");
  EXPECT_FALSE(routed.shares_grid_lines);
  for (const StudyCase& study_case : routed.cases) {
    EXPECT_TRUE(study_case.primer_text.empty());
    for (const scene::Override& override : study_case.overrides) {
      EXPECT_NE(override.path.rfind("mesh.box", 0), 0u) << override.path << " = " << override.value;
    }
  }
  const StudyPlan written = plan_study(base_scene() + "transient:\n  model: full\n" + transient, "b.yaml");
  EXPECT_TRUE(written.shares_grid_lines);
}

// The cases that share a mesh (they differ in the drive, the damping, the spectrum or the sweep)
// share an accuracy key: the first refines to the tolerance, the others start where it ended. Another
// crack is another mesh; a case without a tolerance to reach has no key, so it never waits.
TEST(StudyPlan, TheAccuracyKeyGroupsTheCasesOfOneMeshThatHaveATolerance) {
  const auto transient = [](const std::string& model) {
    return "transient:\n  model: " + model +
           "\n  excitation: {face: x+, direction: z, amplitude: 1.0, frequency: 100}\n"
           "  damping: {ratio: 0.01, at: 100}\n  periods: 2\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\n"
           "spectrum: {harmonics: 3}\n";
  };
  const std::string vary = "study:\n  vary:\n    transient.excitation.amplitude: [1, 2]\n"
                           "    transient.damping.ratio: [0.01, 0.02]\n"
                           "    crack.region.z: [[0.007, 0.01], [0.006, 0.01]]\n  outputs: [spectrum]\n";
  const StudyPlan toleranced =
      plan_study(base_scene() + transient("reduced") + "accuracy: {tolerance: 0.01}\n" + vary, "b.yaml");
  ASSERT_EQ(toleranced.cases.size(), 8u);
  std::map<std::string, std::set<std::string>> keys_by_crack;
  for (const StudyCase& study_case : toleranced.cases) {
    EXPECT_FALSE(study_case.accuracy_key.empty());
    for (const scene::Override& change : study_case.overrides)
      if (change.path == "crack.region.z") keys_by_crack[change.value].insert(study_case.accuracy_key);
  }
  ASSERT_EQ(keys_by_crack.size(), 2u);
  for (const auto& [crack, keys] : keys_by_crack) EXPECT_EQ(keys.size(), 1u) << crack;
  EXPECT_NE(*keys_by_crack.begin()->second.begin(), *keys_by_crack.rbegin()->second.begin());
  // transient.model: auto has the route's tolerance (0.01) without an accuracy section.
  const StudyPlan automatic = plan_study(base_scene() + transient("auto") + vary, "b.yaml");
  EXPECT_FALSE(automatic.cases[0].accuracy_key.empty());
  // No tolerance to reach: an explicit reduced model without one, or the estimate off.
  const StudyPlan reduced = plan_study(base_scene() + transient("reduced") + vary, "b.yaml");
  const StudyPlan off = plan_study(base_scene() + transient("auto") + "accuracy: {estimate: off}\n" + vary, "b.yaml");
  for (const StudyPlan* plan : {&reduced, &off})
    for (const StudyCase& study_case : plan->cases) EXPECT_TRUE(study_case.accuracy_key.empty());
}

TEST(StudyPlan, YamlValuesAsJson) {
  EXPECT_EQ(yaml_text_to_json("[0.005, 0.01]"), nlohmann::json::parse("[0.005, 0.01]"));
  EXPECT_EQ(yaml_text_to_json("lumped"), "lumped");
  EXPECT_EQ(yaml_text_to_json("true"), true);
  EXPECT_EQ(yaml_text_to_json("\"4\""), "4");
}

}  // namespace
}  // namespace crackle::study
