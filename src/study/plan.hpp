#pragma once
/// \file The plan of a parameter study: the `study:` section of a scene file (which keys vary and
/// how), and the cases it expands to, each a full scene validated by the scene loader.
///
/// ```yaml
/// study:
///   vary:
///     crack.region.z: {from: [0.009, 0.01], to: [0.005, 0.01], steps: 5}  # a range
///     modal.mass: [consistent, lumped]                                      # a list of values
///   mode: grid                  # grid (cartesian product, first key slowest) | zip
///   outputs: [modal, spectrum]  # what each case runs: modal -> `crackle modal`, spectrum -> `crackle run`,
///                               # sweep -> `crackle sweep`
///                               # (both: `run` alone when the scene has modal:, it writes modal.json)
/// ```
/// The scene loader does not know `study:`; the section is parsed here, with the same
/// `file:line: key.path: expected ..., got ...` messages, and blanked out of the text (lines kept)
/// before the rest goes to scene::parse_scene.
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace crackle::study {

using scene::StudyMode;  // grid | zip (its words: scene::kStudyModeWords)

/// One varied scene key and its values.
struct VariedKey {
  std::string path;                 ///< scene key path: crack.region.z, boundary[0].value
  std::vector<std::string> values;  ///< YAML text of each value, in order
  int line = -1;                    ///< line of the key in the scene file
};

/// The `study:` section.
struct StudySpec {
  std::vector<VariedKey> vary;
  StudyMode mode = StudyMode::grid;
  std::vector<std::string> outputs = {"modal"};  ///< subset of "modal", "spectrum", "sweep", in this order
  int line = -1;                                 ///< line of `study:`; -1 when absent
};

/// Whether the command of a study output (modal: crackle modal, spectrum: crackle run, sweep: crackle
/// sweep) can read the scene key `path`: crackle modal reads no key of transient:, spectrum: or
/// sweep:, crackle run none of sweep:, and no command reads study:, identify: or plan:. A study
/// that varies a key none of its outputs reads is refused (every case would be the same run).
bool output_reads(const std::string& output, const std::string& path);

/// One case: the base scene with overrides applied.
struct StudyCase {
  int index = 0;
  std::vector<scene::Override> overrides;  ///< the varied keys, then any the study adds (mesh lines)
  std::string scene_text;                  ///< the full case scene as written to cases/NNNN/scene.yaml
  std::string hash;                        ///< of the scene (without its comment header) and the outputs
  std::string modal_key;    ///< hash of what the uncracked modal solve depends on: the modal cache key
  std::string primer_text;  ///< scene that solves just the uncracked modes of this key (may be empty)
  bool has_modal_section = false;  ///< the scene has modal:, so `crackle run` writes modal.json too
  /// Hash of what the accuracy tolerance's refinements depend on: the case scene without the drive,
  /// the damping, the spectrum and the sweep's range (the mesh, the crack, the material and the model
  /// settings). The cases with one key share a mesh: the first refines, the others start their
  /// tolerance loops where it ended (`--accuracy-start`). Empty where the case's run or sweep has no
  /// tolerance (accuracy.estimate off, or neither accuracy.tolerance nor transient.model auto).
  std::string accuracy_key;
};

struct StudyPlan {
  std::string file;  ///< scene file name, for messages
  StudySpec spec;
  std::string base_text;  ///< the scene text without the study section (line numbers kept)
  std::vector<StudyCase> cases;
  /// The study added the union of crack edges as mesh.box.lines (and of crack fronts as
  /// mesh.box.grading.fronts): the cases share one mesh.
  bool shares_grid_lines = false;
};

/// Parses and checks the `study:` section of a scene file. InputError (file:line: path: ...) on any
/// problem, including a varied key the scene format does not declare; a missing section gives a
/// spec with no varied keys and line -1.
StudySpec parse_study_section(const std::string& text, const std::string& file);

/// The scene text without its top-level `study:` section. Block-style sections are blanked line by
/// line, so that messages about the rest keep their line numbers.
std::string strip_study_section(const std::string& text, const std::string& file);

/// Empty when `path` names a key of the scene format (scene::scene_parameters()), else why not,
/// as "expected ..., got ..." text.
std::string check_key_path(const std::string& path);

/// The unit of a scene key as the parameter table declares it ("m" for crack.region.z), "-" for a
/// number or integer declared without one (dimensionless), "" for other keys (choices, texts,
/// maps) and for paths the table does not declare.
std::string key_unit(const std::string& path);

/// `path [unit]` as study.csv heads a column of that key (no brackets when the unit is "").
std::string key_header(const std::string& path);

/// Every scalar key path of the scene format, list entries as `[0]`: mesh.box.size, boundary[0].face.
std::vector<std::string> leaf_key_paths();

/// Expands the study into cases and validates every case scene. Throws InputError, before
/// anything runs, for a bad base scene, a bad study section, or a case whose overrides the scene
/// loader rejects (the message names the case, its values and the offending key path).
StudyPlan plan_study(const std::string& text, const std::string& file);

/// Sorted, distinct grid-line coordinates per axis that make every case's crack edges grid lines
/// of one shared mesh; empty per axis where the cases' cracks agree.
std::vector<std::vector<double>> shared_crack_lines(const std::vector<scene::Scene>& scenes);

/// When the cases grade their box meshes (mesh.box.grading not none) towards crack fronts that
/// differ, the mesh.box.grading value (a YAML flow map) that grades every case towards the fronts of
/// all cases, with the same mode, ratio and layers (the most any case resolves); empty otherwise.
std::string shared_grading(const std::vector<scene::Scene>& scenes);

/// 64-bit FNV-1a of the text, as 16 hex digits.
std::string hash_text(const std::string& text);

/// Folder of case `index` inside the study directory: "cases/0007".
std::string case_folder(int index);

}  // namespace crackle::study
