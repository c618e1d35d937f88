#include "pipeline/model.hpp"

#include "pipeline/commands.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh.hpp"
#include "modal/stiffness_factors.hpp"
#include "pipeline/limits.hpp"

namespace crackle::pipeline {
namespace {

/// Relative tolerance of region ranges (and of the grid lines they add) against the body size.
constexpr double kRegionTolerance = 1e-9;

}  // namespace

mesh::Grading box_grading(const scene::Scene& scene, MeshUse use) {
  const scene::GradingMode mode = scene.grading.mode;
  if (mode == scene::GradingMode::none || (mode == scene::GradingMode::automatic && use == MeshUse::transient))
    return mesh::Grading{};
  return scene.grading.grading;
}

/// Box grid lines: the generator's, plus the ends of the material regions inside the body, so that
/// every layer is a whole number of elements.
std::array<std::vector<double>, 3> box_lines(const scene::Scene& scene, MeshUse use) {
  mesh::BoxSpec box = scene.box;
  box.grading = box_grading(scene, use);
  // With crack.reference the lines are made for the reference crack, then moved onto the crack.
  const std::optional<mesh::CrackSpec>& made_for = scene.crack_reference ? scene.crack_reference : scene.crack;
  std::array<std::vector<double>, 3> lines = mesh::grid_lines(box, made_for);
  std::array<std::vector<double>, 3> fixed = box.extra_lines;
  for (int axis = 0; axis < 3; ++axis) {
    const double low = scene.box.origin[axis], high = low + scene.box.size[axis];
    const double tolerance = kRegionTolerance * scene.box.size[axis];
    for (const scene::MaterialEntrySection& material : scene.materials) {
      if (!material.region.range[axis]) continue;
      for (double end : *material.region.range[axis]) {
        if (end <= low + tolerance || end >= high - tolerance) continue;
        fixed[axis].push_back(end);
        std::vector<double>& line = lines[axis];
        const auto next = std::lower_bound(line.begin(), line.end(), end);
        if (next != line.end() && *next - end <= tolerance) continue;
        if (next != line.begin() && end - *(next - 1) <= tolerance) continue;
        line.insert(next, end);
      }
    }
  }
  if (scene.crack_reference) lines = mesh::morph_lines(box, lines, *scene.crack_reference, *scene.crack, fixed);
  return lines;
}

namespace {

std::string where(const scene::Scene& scene, int line) {
  return scene.file + (line > 0 ? ":" + std::to_string(line) : "") + ": ";
}

std::string point_text(const Vec3& x) {
  return "(" + format_number(x[0]) + ", " + format_number(x[1]) + ", " + format_number(x[2]) + ")";
}

/// The materials of `materials:` and the region (material index) of every element.
void assign_materials(const scene::Scene& scene, Model& model) {
  const mesh::Mesh& mesh = model.mesh;
  std::vector<std::vector<char>> in_group(scene.materials.size());
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    const scene::MaterialEntrySection& entry = scene.materials[m];
    const std::string name = "materials[" + std::to_string(m) + "] (" + entry.name + ")";
    fem::Material material;
    try {
      if (entry.isotropic) {
        material = fem::isotropic(entry.isotropic->young, entry.isotropic->poisson, entry.density, entry.name);
      } else {
        const scene::OrthotropicSection& o = *entry.orthotropic;
        material = fem::orthotropic({o.e1, o.e2, o.e3, o.g12, o.g13, o.g23, o.nu12, o.nu13, o.nu23}, entry.density,
                                    entry.name);
      }
      if (entry.angle != 0.0) material = fem::rotated_about_z(material, entry.angle);
      fem::check_positive_definite(material);
    } catch (const InputError& error) {
      throw InputError(where(scene, entry.line) + name + ": " + error.what());
    }
    model.materials.push_back(material);
    if (!entry.region.group.empty()) {
      const auto found = mesh.element_sets.find(entry.region.group);
      if (found == mesh.element_sets.end()) {
        std::string names;
        for (const auto& [group, elements] : mesh.element_sets) names += (names.empty() ? "" : ", ") + group;
        throw InputError(where(scene, entry.line) + "materials[" + std::to_string(m) +
                         "].region.group: expected a volume group of the mesh (" +
                         (names.empty() ? "it has none" : names) + "), got '" + entry.region.group + "'");
      }
      in_group[m].assign(mesh.n_elements(), 0);
      for (Index e : found->second) in_group[m][e] = 1;
    }
  }
  // Each element takes the one material whose region holds its centroid.
  Vec3 size = Vec3::Ones();
  if (mesh.n_nodes() > 0) {
    Vec3 low = mesh.nodes[0], high = mesh.nodes[0];
    for (const Vec3& x : mesh.nodes) {
      low = low.cwiseMin(x);
      high = high.cwiseMax(x);
    }
    size = (high - low).cwiseMax(1e-300);
  }
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    Vec3 centroid = Vec3::Zero();
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 0; a < mesh.nodes_per_element(); ++a) centroid += mesh.nodes[nodes[a]];
    centroid /= mesh.nodes_per_element();
    int chosen = -1;
    for (std::size_t m = 0; m < scene.materials.size(); ++m) {
      const scene::RegionSection& region = scene.materials[m].region;
      bool inside = in_group[m].empty() || in_group[m][e];
      for (int axis = 0; axis < 3 && inside; ++axis) {
        if (!region.range[axis]) continue;
        const double tolerance = kRegionTolerance * size[axis];
        inside = centroid[axis] >= (*region.range[axis])[0] - tolerance &&
                 centroid[axis] <= (*region.range[axis])[1] + tolerance;
      }
      if (!inside) continue;
      if (chosen >= 0) {
        throw InputError(where(scene, scene.materials[m].line) + "materials: element " + std::to_string(e) +
                         " (centroid " + point_text(centroid) + ") lies in the regions of materials[" +
                         std::to_string(chosen) + "] (" + scene.materials[chosen].name + ") and materials[" +
                         std::to_string(m) + "] (" + scene.materials[m].name + "); regions must not overlap");
      }
      chosen = static_cast<int>(m);
    }
    if (chosen < 0) {
      throw InputError(where(scene, scene.materials.front().line) + "materials: element " + std::to_string(e) +
                       " (centroid " + point_text(centroid) + ") lies in no material's region");
    }
    model.mesh.element_region[e] = chosen;
  }
}

}  // namespace

std::vector<scene::Override> parse_overrides(const std::vector<std::string>& assignments) {
  std::vector<scene::Override> overrides;
  for (const std::string& assignment : assignments) {
    const std::size_t equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0) {
      throw InputError("--set: expected key.path=value, got '" + assignment + "'");
    }
    overrides.push_back({assignment.substr(0, equals), assignment.substr(equals + 1)});
  }
  return overrides;
}

contact::ContactOptions scene_contact_options(const scene::Scene& scene) {
  contact::ContactOptions contact;
  contact.initial_gap = scene.crack ? scene.crack->gap : (scene.crack_group ? scene.crack_group->gap : 0.0);
  contact.normal_penalty = scene.contact.penalty.value_or(0.0);
  contact.friction_coefficient = scene.contact.friction;
  contact.integration = scene.contact.integration;
  return contact;
}

modal::StiffnessFactors& Model::factors() const {
  if (!factors_) factors_ = std::make_shared<modal::StiffnessFactors>();
  return *factors_;
}

mesh::Variant transient_variant(const scene::Scene& scene, const Model& model) {
  const bool open = scene.transient && scene.transient->variant == mesh::Variant::open && model.mesh.has_crack();
  return open ? mesh::Variant::open : mesh::Variant::uncracked;
}

Model build_model(const scene::Scene& scene, MeshUse use) {
  check_memory(scene, matrices::none, use);
  Model model;
  if (!scene.gmsh_file.empty()) {
    mesh::GmshOptions options;
    if (scene.crack_group) options.crack_group = scene.crack_group->group;
    try {
      model.mesh = mesh::read_gmsh(scene.gmsh_file, options);
    } catch (const InputError& error) {
      throw InputError(where(scene, 0) + "mesh.gmsh: " + error.what());
    }
  } else {
    model.mesh = mesh::build_box_mesh(scene.box, box_lines(scene, use), scene.crack);
  }
  if (model.mesh.n_elements() == 0) {
    throw InputError(scene.file + ": mesh: a body left with no elements");
  }
  if (scene.materials.empty()) {
    model.materials.push_back(
        fem::isotropic(scene.material.young, scene.material.poisson, scene.material.density, "material"));
  } else {
    assign_materials(scene, model);
  }
  for (std::size_t b = 0; b < scene.boundary.size(); ++b) {
    const scene::BoundarySection& section = scene.boundary[b];
    const std::string entry = "boundary[" + std::to_string(b) + "]";
    const std::string set = section.face.empty() ? section.group : section.face;
    const auto found = model.mesh.node_sets.find(set);
    if (found == model.mesh.node_sets.end() || found->second.empty()) {
      throw InputError(where(scene, section.line) + entry + ".group: expected a group of the mesh (" +
                       mesh::group_names(model.mesh) + "), got '" + set + "'");
    }
    fem::DirichletCondition condition;
    condition.nodes = found->second;
    condition.components = section.components;
    condition.values = section.values;
    condition.source = scene.file + ":" + std::to_string(section.line) + ": " + entry + " (" +
                       (section.face.empty() ? "group " : "face ") + set + ")";
    model.dirichlet.push_back(std::move(condition));
  }
  if (scene.transient && scene.transient->excitation && !scene.transient->excitation->group.empty()) {
    const std::string& group = scene.transient->excitation->group;
    const auto found = model.mesh.node_sets.find(group);
    if (found == model.mesh.node_sets.end() || found->second.empty()) {
      throw InputError(where(scene, 0) + "transient.excitation.group: expected a group of the mesh (" +
                       mesh::group_names(model.mesh) + "), got '" + group + "'");
    }
  }
  return model;
}

}  // namespace crackle::pipeline
