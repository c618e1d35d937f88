#pragma once
/// \file A scene: the validated contents of a YAML scene file as plain structs (SI units).
///
/// Every parameter is declared once in the parameter table (schema.hpp): name, type, range,
/// default and doc. The loader validates the YAML against that table, rejects unknown keys, and
/// reports `file:line: key.path: expected ..., got ...` as an InputError. The same table generates
/// docs/scene-format.md.
#include <optional>
#include <string>
#include <vector>

#include "mesh/box.hpp"

namespace crackle::scene {

struct MaterialSection {
  double young = 0.0;    ///< E [Pa]
  double poisson = 0.0;  ///< nu
  double density = 0.0;  ///< rho [kg/m^3]
};

/// One entry of `boundary:`: fix components of every node of a face.
struct BoundarySection {
  std::string face;             ///< x-, x+, y-, y+, z-, z+
  std::vector<int> components;  ///< 0, 1, 2 for x, y, z
  std::vector<double> values;   ///< prescribed displacement [m] per component (default 0)
  int line = 0;                 ///< 1-based line in the scene file, for messages
};

/// The `modal:` section (issue 3).
struct ModalSection {
  int modes = 10;
  std::vector<std::string> variants;  ///< "uncracked" and/or "open"; defaulted by the loader
  std::string solver = "slepc";       ///< slepc | arpack
  std::string mass = "consistent";    ///< consistent | lumped
};

struct Scene {
  std::string file;  ///< path the scene was read from (or a name for in-memory scenes)
  mesh::BoxSpec box;
  MaterialSection material;
  std::vector<BoundarySection> boundary;
  std::optional<mesh::CrackSpec> crack;
  ModalSection modal;
  bool has_modal_section = false;
};

struct Param;

/// A parameter-study override: a YAML value for a dotted key path such as `crack.region.z`,
/// `modal.modes` or `boundary[0].value` (list entries by index). Applied before validation, so an
/// overridden value is checked like any other; messages about it name the path but no line.
struct Override {
  std::string path;
  std::string value;  ///< YAML text: "0.004", "[0.007, 0.01]", "lumped"
};

/// Loads and validates a scene file. Throws InputError (one line, see above) on any problem.
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {});

/// Same, from YAML text; `name` stands for the file name in messages.
Scene parse_scene(const std::string& text, const std::string& name, const std::vector<Override>& overrides = {});

/// The parameter table of a scene file: every key, declared once (schema.hpp). A new section is
/// one more entry here plus its conversion in scene.cpp.
const Param& scene_parameters();

/// Markdown reference of every scene key, generated from the parameter table.
std::string scene_format_markdown();

}  // namespace crackle::scene
