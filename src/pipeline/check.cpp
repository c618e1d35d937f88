#include <iomanip>
#include <ostream>
#include <sstream>

#include "pipeline/commands.hpp"
#include "core/resources.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "pipeline/limits.hpp"
#include "mesh/box.hpp"
#include "pipeline/model.hpp"
#include "pipeline/placement.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

void run_check(const CheckOptions& options, std::ostream& out) {
  Stopwatch clock;
  const scene::Scene scene = scene::load_scene(options.scene_path, parse_overrides(options.overrides));
  check_memory(scene, options.assemble ? matrices::stiffness : matrices::none, MeshUse::modal);
  const Model model = build_model(scene, MeshUse::modal);
  check_points(scene, model);  // every refusal crackle run makes for a probe or a load point
  const double mesh_seconds = clock.seconds();
  const mesh::Mesh& mesh = model.mesh;

  const fem::System& system = *model.system(mesh::Variant::open);
  const mesh::DofMap& open = system.dofs();
  const mesh::DofMap tied = mesh::make_dof_map(mesh, mesh::Variant::uncracked);
  const fem::Constraints& constraints = system.constraints();
  Index front = 0;
  for (const mesh::CrackPair& pair : mesh.crack_pairs) front += pair.on_front();

  out << "scene        " << scene.file << "\n";
  if (scene.gmsh_file.empty()) {
    out << "mesh         box " << scene.box.cells[0] << " x " << scene.box.cells[1] << " x " << scene.box.cells[2]
        << " cells requested, order p = " << mesh.order << "\n";
  } else {
    out << "mesh         " << scene.gmsh_file << ": " << mesh::shape_name(mesh.shape) << " elements of order " << mesh.order
        << "\n";
  }
  if (scene.gmsh_file.empty()) {
    // The modal mesh is what check builds; crackle run (full or reduced) and crackle sweep mesh
    // without grading under mode auto.
    const mesh::Grading modal_grading = box_grading(scene, MeshUse::modal);
    const mesh::Grading run_grading = box_grading(scene, MeshUse::transient);
    auto grading_text = [&](mesh::Grading grading) {
      if (grading.layers == 0 || !scene.crack) return std::string("none");
      mesh::BoxSpec box = scene.box;
      box.grading = grading;
      grading = mesh::resolve_grading(box, *scene.crack);
      std::ostringstream text;
      text << grading.layers << " layers of ratio " << grading.ratio;
      return text.str();
    };
    out << "grading      " << grading_text(modal_grading) << " (crackle modal, check), " << grading_text(run_grading)
        << " (crackle run, sweep)\n";
    out << "aspect ratio " << std::setprecision(4) << mesh::max_aspect_ratio(box_lines(scene, MeshUse::modal))
        << " max (crackle modal, check), " << mesh::max_aspect_ratio(box_lines(scene, MeshUse::transient))
        << " max (crackle run, sweep)\n";
  } else {
    out << "aspect ratio " << std::setprecision(4) << mesh::max_aspect_ratio(mesh) << " max\n";
  }
  out << "elements     " << mesh.n_elements() << "\n";
  out << "nodes        " << mesh.n_nodes() << " (" << mesh.n_original_nodes << " + "
      << mesh.n_nodes() - mesh.n_original_nodes << " crack-face copies)\n";
  out << "dofs         " << open.n_dofs() << " open, " << tied.n_dofs() << " uncracked, "
      << open.n_dofs() - constraints.n_free() << " constrained (open)\n";
  if (mesh.has_crack()) {
    double pair_area = 0.0;
    for (const mesh::CrackPair& pair : mesh.crack_pairs) pair_area += pair.area;
    out << "crack pairs  " << mesh.crack_pairs.size() << " (" << mesh.crack_pairs.size() - front << " split, "
        << front << " on the front)\n";
    out << "crack area   " << std::setprecision(6) << mesh.crack_area << " m^2 (pairs sum to " << pair_area
        << " m^2)\n";
  } else {
    out << "crack pairs  0 (no crack)\n";
  }
  out << "volume       " << std::setprecision(6) << mesh.volume() << " m^3\n";
  out << "mesh time    " << std::setprecision(3) << mesh_seconds << " s\n";
  if (!options.assemble) return;

  clock.restart();
  const SparseMatrix stiffness = system.assemble_stiffness();
  const double stiffness_seconds = clock.seconds();
  clock.restart();
  const VectorX& lumped = system.lumped_mass();
  const double mass_seconds = clock.seconds();
  out << "total mass   " << std::setprecision(6) << lumped.sum() / 3.0 << " kg\n";
  out << "K            " << stiffness.nonZeros() << " nonzeros, assembled in " << std::setprecision(3)
      << stiffness_seconds << " s\n";
  out << "lumped M     assembled in " << std::setprecision(3) << mass_seconds << " s\n";
  out << "peak memory  " << peak_rss_bytes() / (1024 * 1024) << " MiB\n";
}

}  // namespace crackle::pipeline
