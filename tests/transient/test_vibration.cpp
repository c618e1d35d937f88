#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "fem/assembly.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh.hpp"
#include "fem/elastic_operator.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"

namespace crackle::transient {
namespace {

const fem::Material kSteel = fem::isotropic(2e11, 0.3, 7800.0);

/// Index of the mode (among the first `count`) with the largest share of its mass-weighted
/// motion along `axis`.
int mode_along(const testing::DenseModes& modes, const VectorX& mass, int axis) {
  int best = 0;
  double best_share = -1.0;
  for (int k = 0; k < modes.shapes.cols(); ++k) {
    double along = 0.0, total = 0.0;
    for (Index d = 0; d < modes.shapes.rows(); ++d) {
      const double energy = mass[d] * modes.shapes(d, k) * modes.shapes(d, k);
      total += energy;
      if (d % 3 == axis) along += energy;
    }
    if (along / total > best_share) {
      best_share = along / total;
      best = k;
    }
  }
  return best;
}

/// Free vibration of an uncracked cantilever (clamped on node set `clamp`) after a pulse on the
/// faces `load`: the peak of the tip response spectrum sits at the lowest bending frequency of the
/// same mesh with the same lumped mass, and the (linear) run conserves its modified energy.
void expect_rings_at_modal_frequency(const mesh::Mesh& mesh, const std::string& clamp, const std::string& load,
                                     const Vec3& tip_point, const std::string& label) {
  const fem::Materials materials = {kSteel};
  TransientProblem problem;
  problem.materials = materials;
  problem.dirichlet.push_back({mesh.node_sets.at(clamp), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});

  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const fem::Constraints constraints = fem::make_constraints(dofs, problem.dirichlet);
  const VectorX mass = fem::assemble_lumped_mass(mesh, dofs, materials);
  const testing::DenseModes modes = testing::dense_modes(fem::assemble_stiffness(mesh, dofs, materials), mass, constraints, 1);
  const double f1 = modes.omega[0] / (2.0 * M_PI);

  ExternalLoad pulse;
  pulse.name = "tip";
  pulse.faces = mesh.face_sets.at(load);
  pulse.direction = Vec3::UnitZ();
  pulse.amplitude = 1000.0;
  pulse.signal.kind = SignalKind::pulse;
  pulse.signal.duration = 0.1 / f1;
  problem.loads.push_back(pulse);
  problem.probes.push_back({"tip", nearest_node(mesh, tip_point)});
  TransientOptions options;
  options.end_time = 30.0 / f1;
  options.progress = false;
  TransientSolver solver(mesh, problem, options);
  solver.run();

  const std::vector<double>& tip = solver.probes().values[2];  // u_z
  const double duration = solver.summary().time;
  const double peak = testing::dominant_frequency(tip, solver.dt(), 0.3 * f1, 2.0 * f1);
  std::printf("%s: modal f1 = %.4f Hz, transient peak %.4f Hz (resolution %.3f Hz), %lld steps, energy error %.1e\n",
              label.c_str(), f1, peak, 1.0 / duration, static_cast<long long>(solver.summary().steps),
              solver.summary().energy_error);
  EXPECT_LE(std::abs(peak - f1), 0.5 / duration) << label;
  EXPECT_LT(solver.summary().energy_error, 1e-9) << label;  // linear: the modified energy is exact
}

TEST(Vibration, CantileverRingsAtItsLumpedMassModalFrequency) {
  mesh::BoxSpec box;
  box.size = Vec3(0.5, 0.05, 0.05);
  box.cells = {8, 1, 1};
  box.order = 2;
  expect_rings_at_modal_frequency(mesh::build_box_mesh(box), "x-", "x+", Vec3(0.5, 0.025, 0.025), "cantilever");
}

/// The same on unstructured Gmsh tetrahedra (4- and 10-node, HRZ-lumped mass), which the elastic
/// operator applies as an assembled matrix (checked against K x first).
TEST(Vibration, TetrahedralCantileverRingsAtItsLumpedMassModalFrequency) {
  for (const char* file : {"box-tet4.msh", "box-tet10.msh"}) {
    const mesh::Mesh mesh = mesh::read_gmsh(std::string(CRACKLE_SOURCE_DIR) + "/data/meshes/" + file);
    const fem::Materials materials = {kSteel};
    const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    const SparseMatrix stiffness = fem::assemble_stiffness(mesh, dofs, materials);
    const fem::ElasticOperator elastic(mesh, dofs, materials);
    EXPECT_EQ(elastic.info().kernel, "assembled");
    const VectorX x = VectorX::LinSpaced(dofs.n_dofs(), -1.0, 1.0);
    VectorX y;
    elastic.apply(x, y);
    EXPECT_LT((y - stiffness * x).norm(), 1e-12 * (stiffness * x).norm()) << file;
    expect_rings_at_modal_frequency(mesh, "clamp", "load", Vec3(0.2, 0.025, 0.04), file);
  }
}

/// A bar clamped at x = 0, cut through at x = L/4, pressed by a constant end load so that the crack
/// stays closed; axial free vibration on top of that static state.
struct PreloadedBar {
  static constexpr double kLength = 0.4, kWidth = 0.04, kYoung = 2e11, kDensity = 7800.0, kPressure = 1e7;
  mesh::Mesh mesh;
  TransientProblem problem;
  TransientOptions options;

  explicit PreloadedBar(int cells, bool cracked) {
    mesh::BoxSpec box;
    box.size = Vec3(kLength, kWidth, kWidth);
    box.cells = {cells, 1, 1};
    box.order = 1;
    mesh::CrackSpec crack;
    crack.normal = kX;
    crack.at = 0.25 * kLength;
    crack.region = {{{0.0, 0.0}, {0.0, kWidth}, {0.0, kWidth}}};
    mesh = mesh::build_box_mesh(box, crack);
    problem.materials = {fem::isotropic(kYoung, 0.0, kDensity)};
    problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
    options.variant = cracked ? mesh::Variant::open : mesh::Variant::uncracked;
    options.progress = false;
  }
  double c0() const { return std::sqrt(kYoung / kDensity); }
};

TEST(Vibration, CrackHeldClosedByPreloadVibratesAtTheUncrackedFrequency) {
  PreloadedBar bar(40, true);
  const mesh::Mesh& mesh = bar.mesh;
  // Reference: the axial mode of the uncracked bar (crack faces tied), same lumped mass.
  const mesh::DofMap tied = mesh::make_dof_map(mesh, mesh::Variant::uncracked);
  const VectorX tied_mass = fem::assemble_lumped_mass(mesh, tied, bar.problem.materials);
  const testing::DenseModes modes = testing::dense_modes(fem::assemble_stiffness(mesh, tied, bar.problem.materials),
                                                         tied_mass, fem::make_constraints(tied, bar.problem.dirichlet), 10);
  const double f_uncracked = modes.omega[mode_along(modes, tied_mass, kX)] / (2.0 * M_PI);

  // Static state under the end pressure P (nu = 0: exactly uniaxial): u_x = -P x / E, and the
  // closed crack adds the penalty compression P / eps_N on the far side.
  contact::ContactOptions contact;  // automatic penalty
  const auto contact_term = testing::plug_contact(mesh, bar.problem, contact);
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const double penalty = contact::choose_penalty(mesh, bar.problem.materials, contact).normal_penalty;
  const double p = PreloadedBar::kPressure, E = PreloadedBar::kYoung, L = PreloadedBar::kLength;
  auto beyond = [&](Index node) { return node >= mesh.n_original_nodes || mesh.nodes[node].x() > 0.25 * L + 1e-9; };
  bar.problem.initial.displacement = nodal_field(mesh, dofs, [&](Index node, const Vec3& x) {
    return Vec3(-p * x.x() / E - (beyond(node) ? p / penalty : 0.0), 0.0, 0.0);
  });
  ExternalLoad load;
  load.faces = mesh.face_sets.at("x+");
  load.direction = -Vec3::UnitX();
  load.amplitude = p * PreloadedBar::kWidth * PreloadedBar::kWidth;
  load.signal.kind = SignalKind::step;
  bar.problem.loads.push_back(load);
  // Axial velocity in the shape of the first axial mode, 5% of the preload's particle velocity.
  const double velocity = 0.05 * p / (PreloadedBar::kDensity * bar.c0());
  bar.problem.initial.velocity = nodal_field(mesh, dofs, [&](Index, const Vec3& x) {
    return Vec3(velocity * std::sin(0.5 * M_PI * x.x() / L), 0.0, 0.0);
  });
  bar.problem.probes.push_back({"tip", nearest_node(mesh, Vec3(L, 0.0, 0.0))});
  bar.options.end_time = 40.0 / f_uncracked;
  TransientSolver solver(mesh, bar.problem, bar.options);
  solver.run();
  const double f_closed = testing::zero_crossing_frequency(solver.probes().values[0], solver.dt());
  std::printf("closed crack: f = %.4f Hz, uncracked %.4f Hz, ratio %.6f, penalty %.3g Pa/m (c = %g), closed fraction %.4f, "
              "%lld steps, dt %.3g s\n",
              f_closed, f_uncracked, f_closed / f_uncracked, penalty, contact_term->contact().penalty().factor,
              solver.summary().contact_fraction, static_cast<long long>(solver.summary().steps), solver.dt());
  EXPECT_EQ(solver.summary().contact_fraction, 1.0);
  EXPECT_GE(f_closed / f_uncracked, 0.999);
  EXPECT_LE(f_closed / f_uncracked, 1.0001);
}

/// A cantilever with a crack through the upper half of its section near the root, opened wide
/// (gap larger than any motion): it vibrates at the frequency of the open-crack body.
TEST(Vibration, WideOpenCrackVibratesAtTheOpenFrequency) {
  mesh::BoxSpec box;
  box.size = Vec3(0.5, 0.05, 0.05);
  box.cells = {10, 1, 2};
  box.order = 2;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.1;
  crack.region = {{{0.0, 0.0}, {0.0, 0.05}, {0.025, 0.05}}};
  crack.gap = 1e-3;
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  const fem::Materials materials = {kSteel};
  TransientProblem problem;
  problem.materials = materials;
  problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
  contact::ContactOptions contact;
  contact.initial_gap = crack.gap;
  testing::plug_contact(mesh, problem, contact);

  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const VectorX mass = fem::assemble_lumped_mass(mesh, dofs, materials);
  const fem::Constraints constraints = fem::make_constraints(dofs, problem.dirichlet);
  const testing::DenseModes open = testing::dense_modes(fem::assemble_stiffness(mesh, dofs, materials), mass, constraints, 4);
  const mesh::DofMap tied = mesh::make_dof_map(mesh, mesh::Variant::uncracked);
  const testing::DenseModes uncracked =
      testing::dense_modes(fem::assemble_stiffness(mesh, tied, materials), fem::assemble_lumped_mass(mesh, tied, materials),
                           fem::make_constraints(tied, problem.dirichlet), 4);
  // The z-bending mode: the lowest with tip motion mostly along z.
  const Index tip = nearest_node(mesh, Vec3(0.5, 0.025, 0.025));
  int k_open = 0;
  while (std::abs(open.shapes(dofs.dof(tip, 2), k_open)) < std::abs(open.shapes(dofs.dof(tip, 1), k_open))) ++k_open;
  const double f_open = open.omega[k_open] / (2.0 * M_PI);

  // Start from the open mode shape (20 micrometres at the tip): it never closes the 1 mm gap.
  const double scale = 2e-5 / std::abs(open.shapes(dofs.dof(tip, 2), k_open));
  problem.initial.displacement = scale * open.shapes.col(k_open);
  problem.probes.push_back({"tip", tip});
  TransientOptions options;
  options.end_time = 20.0 / f_open;
  options.progress = false;
  TransientSolver solver(mesh, problem, options);
  solver.run();
  const double duration = solver.summary().time;
  const double peak = testing::dominant_frequency(solver.probes().values[2], solver.dt(), 0.5 * f_open, 1.5 * f_open);
  std::printf("open crack: modal %.4f Hz (uncracked %.4f Hz), transient %.4f Hz (resolution %.3f Hz), zero crossings %.4f Hz\n",
              f_open, uncracked.omega[0] / (2.0 * M_PI), peak, 1.0 / duration,
              testing::zero_crossing_frequency(solver.probes().values[2], solver.dt()));
  EXPECT_EQ(solver.summary().contact_fraction, 0.0);
  EXPECT_LE(std::abs(peak - f_open), 0.5 / duration);
  EXPECT_LT(f_open, 0.99 * uncracked.omega[0] / (2.0 * M_PI));  // the crack matters
}

}  // namespace
}  // namespace crackle::transient
