#include "scene/scene.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"
#include "scene/schema.hpp"

namespace crackle::scene {
namespace {

const std::vector<std::string> kAxes = {"x", "y", "z"};

int axis_index(const std::string& axis) {
  return static_cast<int>(std::find(kAxes.begin(), kAxes.end(), axis) - kAxes.begin());
}

/// Default of `boundary[i].value`: a zero for each fixed component.
std::string zeros_per_fix(const Values& values, const std::string& entry) {
  const std::size_t n = values.words(entry + ".fix").size();
  std::string text = "[";
  for (std::size_t i = 0; i < n; ++i) text += i ? ", 0" : "0";
  return text + "]";
}

/// Default of `modal.variants`: both limits when the scene has a crack.
std::string default_variants(const Values& values, const std::string&) {
  return values.has("crack") ? "[uncracked, open]" : "[uncracked]";
}

Param build_parameters() {
  const auto& faces = mesh::box_face_names();
  // clang-format off
  return map_of("", "A scene file.", {
    one_of("mesh", "How the body is meshed: exactly one of the keys below.", {
      map_of("box", "Structured mesh of the box [origin, origin + size].", {
        number("origin", "Corner of the box with the smallest coordinates.").with_unit("m").list(3)
            .defaults_to("[0, 0, 0]"),
        number("size", "Edge lengths along x, y, z.").with_unit("m").above(0).list(3).required(),
        integer("cells", "Elements per direction; grid lines are added where crack edges need them.")
            .at_least(1).list(3).required(),
        integer("order", "Element order p (Lagrange elements on GLL nodes).").at_least(1).at_most(4).required(),
      }),
    }).required(),
    map_of("material", "Isotropic linear elastic material (MODEL.md eq. 2).", {
      number("E", "Young's modulus.").with_unit("Pa").above(0).required(),
      number("nu", "Poisson's ratio.").above(-1).below(0.5).required(),
      number("rho", "Mass density.").with_unit("kg/m^3").above(0).required(),
    }).required(),
    list_of("boundary", "Prescribed displacements on box faces; none: a free body.", {
      choice("face", "Face of the box.", {faces.begin(), faces.end()}).required(),
      choice("fix", "Displacement components fixed on every node of the face.", kAxes).list(1, 3).distinct()
          .required(),
      number("value", "Prescribed displacement of each fixed component.").with_unit("m").list(1, 3)
          .same_length_as("fix").defaults_to("zeros", zeros_per_fix),
    }).defaults_to("[]"),
    map_of("crack", "An axis-aligned rectangular crack on a grid plane of the mesh; none: no crack.", {
      map_of("plane", "The plane of the crack.", {
        choice("normal", "Axis normal to the crack.", kAxes).required(),
        number("at", "Position of the plane along the normal; must be a grid plane origin + k size/cells "
                     "strictly inside the body.").with_unit("m").required(),
      }).required(),
      map_of("region", "Rectangle on the plane: [low, high] along each of the two in-plane axes, which "
                       "are exactly its keys.", {
        number("x", "Extent along x.").with_unit("m").list(2),
        number("y", "Extent along y.").with_unit("m").list(2),
        number("z", "Extent along z.").with_unit("m").list(2),
      }).required(),
      number("gap", "Initial normal gap g0 (MODEL.md eq. 9): > 0 open, < 0 pre-compressed.").with_unit("m")
          .defaults_to("0"),
    }),
    map_of("modal", "Modal analysis of the linear limits of the cracked body; optional.", {
      integer("modes", "Number of lowest modes per variant.").at_least(1).defaults_to("10"),
      choice("variants", "Linear limits to analyse: faces tied (uncracked) or free (open); open needs a crack.",
             {"uncracked", "open"}).list(1, 2).distinct()
          .defaults_to("[uncracked, open] with a crack, else [uncracked]", default_variants),
      choice("solver", "Eigen-solver.", {"slepc", "arpack"}).defaults_to("slepc"),
      choice("mass", "Mass matrix.", {"consistent", "lumped"}).defaults_to("consistent"),
    }),
  });
  // clang-format on
}

Vec3 vec3(const std::vector<double>& numbers) { return Vec3(numbers[0], numbers[1], numbers[2]); }

/// Two faces share nodes when they are the same face or meet at a box edge.
bool faces_touch(const std::string& a, const std::string& b) { return a == b || a[0] != b[0]; }

/// The same component of a shared node must not be fixed to two different values.
void check_boundary(const Values& values, const std::vector<BoundarySection>& boundary) {
  for (std::size_t j = 0; j < boundary.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      if (!faces_touch(boundary[i].face, boundary[j].face)) continue;
      for (std::size_t k = 0; k < boundary[j].components.size(); ++k) {
        const int component = boundary[j].components[k];
        const auto& earlier = boundary[i].components;
        const auto found = std::find(earlier.begin(), earlier.end(), component);
        if (found == earlier.end()) continue;
        const double fixed = boundary[i].values[found - earlier.begin()];
        if (fixed == boundary[j].values[k]) continue;
        const std::string axis = kAxes[component];
        const std::string where =
            boundary[i].face == boundary[j].face
                ? "on the same face"
                : "on face " + boundary[i].face + ", which shares an edge with " + boundary[j].face;
        values.fail(
            "boundary[" + std::to_string(j) + "].value[" + std::to_string(k) + "]",
            axis + " = " + format_number(fixed) + " as fixed by boundary[" + std::to_string(i) + "] " + where,
            axis + " = " + format_number(boundary[j].values[k]));
      }
    }
  }
}

mesh::CrackSpec crack_from(const Values& values, const mesh::BoxSpec& box) {
  mesh::CrackSpec crack;
  crack.normal = axis_index(values.word("crack.plane.normal"));
  crack.at = values.number("crack.plane.at");
  crack.gap = values.number("crack.gap");

  std::vector<std::string> in_plane, given;
  for (int axis = 0; axis < 3; ++axis) {
    if (axis != crack.normal) in_plane.push_back(kAxes[axis]);
    if (values.has("crack.region." + kAxes[axis])) given.push_back(kAxes[axis]);
  }
  if (given != in_plane) {
    values.fail("crack.region",
                "keys " + in_plane[0] + " and " + in_plane[1] + " (the in-plane axes of a crack normal to " +
                    kAxes[crack.normal] + ")",
                given.empty()       ? "none"
                : given.size() == 1 ? given[0]
                                    : given[0] + " and " + given[1]);
  }
  for (const std::string& axis : in_plane) {
    const auto& range = values.numbers("crack.region." + axis);
    crack.region[axis_index(axis)] = {range[0], range[1]};
  }
  const std::string problem = mesh::check_crack(box, crack);
  if (!problem.empty()) values.fail("crack." + problem.substr(0, problem.find(':')), "crack." + problem);
  return crack;
}

Scene scene_from(const Values& values) {
  Scene scene;
  scene.file = values.file();
  scene.box.origin = vec3(values.numbers("mesh.box.origin"));
  scene.box.size = vec3(values.numbers("mesh.box.size"));
  const auto& cells = values.numbers("mesh.box.cells");
  scene.box.cells = {static_cast<int>(cells[0]), static_cast<int>(cells[1]), static_cast<int>(cells[2])};
  scene.box.order = values.integer("mesh.box.order");

  scene.material.young = values.number("material.E");
  scene.material.poisson = values.number("material.nu");
  scene.material.density = values.number("material.rho");

  for (int i = 0; i < values.count("boundary"); ++i) {
    const std::string entry = "boundary[" + std::to_string(i) + "]";
    BoundarySection section;
    section.face = values.word(entry + ".face");
    for (const std::string& axis : values.words(entry + ".fix"))
      section.components.push_back(axis_index(axis));
    section.values = values.numbers(entry + ".value");
    section.line = std::max(values.line(entry), 0);
    scene.boundary.push_back(section);
  }
  check_boundary(values, scene.boundary);

  if (values.has("crack")) scene.crack = crack_from(values, scene.box);

  scene.has_modal_section = values.has("modal");
  scene.modal.modes = values.integer("modal.modes");
  scene.modal.variants = values.words("modal.variants");
  scene.modal.solver = values.word("modal.solver");
  scene.modal.mass = values.word("modal.mass");
  for (std::size_t i = 0; i < scene.modal.variants.size(); ++i) {
    if (scene.modal.variants[i] == "open" && !scene.crack) {
      values.fail("modal.variants[" + std::to_string(i) + "]", "uncracked (the scene has no crack)",
                  "'open'");
    }
  }
  return scene;
}

}  // namespace

const Param& scene_parameters() {
  static const Param root = build_parameters();
  return root;
}

Scene parse_scene(const std::string& text, const std::string& name, const std::vector<Override>& overrides) {
  YAML::Node document = parse_yaml(text, name);
  for (const Override& change : overrides) apply_override(document, change.path, change.value, name);
  return scene_from(validate(scene_parameters(), document, name));
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
  std::ifstream file(path);
  if (!file) throw InputError(path + ": expected a readable scene file, got " + std::strerror(errno));
  std::ostringstream text;
  text << file.rdbuf();
  return parse_scene(text.str(), path, overrides);
}

std::string scene_format_markdown() {
  return "# Scene format\n\n"
         "<!-- Generated from the parameter table in src/scene/scene.cpp by scene_format_markdown(); do not "
         "edit.\n"
         "     Regenerate: CRACKLE_UPDATE_DOCS=1 build/tests/scene/test_scene -->\n\n"
         "A scene is a YAML file in SI units. Unknown keys are errors. Keys marked required must be given "
         "when\n"
         "their section is; an optional section without required keys that is left out takes its defaults.\n"
         "Lists are written `[a, b, c]`; entries of `boundary` are addressed as `boundary[0]`, and a "
         "parameter\n"
         "study overrides any key by its path, e.g. `crack.region.z`. Every problem is reported on one line "
         "as\n"
         "`file:line: key.path: expected ..., got ...`.\n\n" +
         markdown_table(scene_parameters());
}

}  // namespace crackle::scene
