#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "fem/material.hpp"
#include "io/files.hpp"
#include "mesh/box.hpp"
#include "transient/damping.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"
#include "output/transient_json.hpp"

namespace crackle::transient {
namespace {

TEST(Signals, HarmonicRampPulseAndStep) {
  Signal harmonic;
  harmonic.frequency = 100.0;
  harmonic.ramp_periods = 3.0;
  EXPECT_EQ(harmonic.value(-1e-3), 0.0);
  EXPECT_EQ(harmonic.value(0.0), 0.0);
  EXPECT_NEAR(harmonic.value(0.015), 0.5 * std::sin(2.0 * M_PI * 1.5), 1e-12);  // half way up the ramp
  EXPECT_NEAR(harmonic.value(0.0425), std::sin(2.0 * M_PI * 4.25), 1e-12);        // after it
  EXPECT_NEAR(smooth_ramp(0.25, 1.0), std::pow(std::sin(M_PI / 8.0), 2), 1e-15);
  Signal pulse;
  pulse.kind = SignalKind::pulse;
  pulse.duration = 2e-3;
  pulse.start = 1e-3;
  EXPECT_EQ(pulse.value(0.5e-3), 0.0);
  EXPECT_NEAR(pulse.value(2e-3), 1.0, 1e-15);
  EXPECT_EQ(pulse.value(3.5e-3), 0.0);
  Signal step;
  step.kind = SignalKind::step;
  EXPECT_EQ(step.value(0.0), 1.0);
  step.duration = 1e-3;
  EXPECT_NEAR(step.value(0.5e-3), 0.5, 1e-15);
  EXPECT_EQ(step.value(2e-3), 1.0);
  Signal bad;
  EXPECT_THROW(check_signal(bad, "load"), InputError);  // harmonic with no frequency
}

TEST(Damping, RayleighHelpers) {
  const RayleighDamping mass = mass_proportional_damping(0.02, 1000.0);
  EXPECT_DOUBLE_EQ(mass.alpha, 40.0);
  EXPECT_EQ(mass.beta, 0.0);
  const RayleighDamping stiffness = stiffness_proportional_damping(0.02, 1000.0);
  EXPECT_DOUBLE_EQ(stiffness.beta, 4e-5);
  EXPECT_DOUBLE_EQ(damping_ratio(mass, 1000.0), 0.02);
  EXPECT_DOUBLE_EQ(damping_ratio(stiffness, 1000.0), 0.02);
  EXPECT_DOUBLE_EQ(damping_ratio(mass, 2000.0), 0.01);  // mass-proportional: falls as 1/omega
  EXPECT_THROW(mass_proportional_damping(-0.1, 1.0), InputError);
  // As a scene states it: a ratio at a frequency in Hz (mass or stiffness), else alpha and beta.
  const double at_hz = 1000.0 / (2.0 * M_PI);
  EXPECT_DOUBLE_EQ(stated_damping(0.02, false, at_hz, 7.0, 8.0).alpha, 40.0);
  EXPECT_DOUBLE_EQ(stated_damping(0.02, false, at_hz, 7.0, 8.0).beta, 0.0);
  EXPECT_DOUBLE_EQ(stated_damping(0.02, true, at_hz, 7.0, 8.0).beta, 4e-5);
  EXPECT_DOUBLE_EQ(stated_damping(std::nullopt, true, at_hz, 7.0, 8.0).alpha, 7.0);
  EXPECT_DOUBLE_EQ(stated_damping(std::nullopt, true, at_hz, 7.0, 8.0).beta, 8.0);
}

mesh::Mesh free_block() {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.1, 0.1);
  box.cells = {4, 2, 2};
  box.order = 2;
  return mesh::build_box_mesh(box);
}

/// A constant force on a free body: its momentum is the impulse, F (n - 1/2) dt after n steps
/// (the first velocity update is the half step).
TEST(Loads, FaceLoadTotalIsTheAmplitude) {
  const mesh::Mesh mesh = free_block();
  TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  ExternalLoad load;
  load.faces = mesh.face_sets.at("x+");
  load.direction = Vec3(2.0, 0.0, 1.0);  // normalised on use
  load.amplitude = 5e3;
  load.signal.kind = SignalKind::step;
  problem.loads.push_back(load);
  TransientOptions options;
  options.end_time = 1e-4;
  options.progress = false;
  TransientSolver solver(mesh, problem, options);
  solver.run();
  const VectorX& mass = solver.lumped_mass();
  Vec3 momentum = Vec3::Zero();
  for (Index k = 0; k < solver.dofs().n_dofs(); ++k) momentum[k % 3] += mass[k] * solver.velocity()[k];
  const double impulse = (static_cast<double>(solver.summary().steps) - 0.5) * solver.dt();
  EXPECT_TRUE(momentum.isApprox(5e3 * impulse * Vec3(2.0, 0.0, 1.0).normalized(), 1e-10));
  EXPECT_LT(solver.summary().energy_error, 1e-9);  // work of the load balances the energy
}

TEST(Outputs, CallbackStopsEarlyAndFilesCarryThePublicNames) {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.04, 0.04);
  box.cells = {6, 1, 1};
  box.order = 1;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.1;
  crack.region = {{{0.0, 0.0}, {0.0, 0.04}, {0.0, 0.02}}};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
  const auto contact_term = testing::plug_contact(mesh, problem, contact::ContactOptions{});
  ExternalLoad load;
  load.name = "shaker";
  load.nodes = mesh.node_sets.at("x+");
  load.direction = Vec3::UnitZ();
  load.amplitude = 100.0;
  load.signal.frequency = 2000.0;
  problem.loads.push_back(load);
  problem.probes.push_back({"tip", nearest_node(mesh, Vec3(0.2, 0.0, 0.0))});
  TransientOptions options;
  options.end_time = 5e-3;
  options.progress = false;
  options.probe_interval = 3;
  const std::filesystem::path directory = std::filesystem::temp_directory_path() / "crackle_test_outputs";
  std::filesystem::remove_all(directory);
  TransientSolver solver(mesh, problem, options);
  Index calls = 0;
  bool finished = false;
  TransientCallbacks callbacks;
  callbacks.on_step = [&](const StepView& view) {
    EXPECT_EQ(view.step, calls);
    EXPECT_EQ(view.probe_sample.size(), 9u);
    return ++calls == 500;  // "steady state reached"
  };
  callbacks.on_finish = [&](const TransientSummary&) {
    finished = true;
    output::write_transient_outputs(directory, solver, output::contact_json(contact_term->contact()));  // as the run pipeline does
  };
  const TransientSummary& summary = solver.run(callbacks);
  EXPECT_TRUE(finished);
  EXPECT_EQ(summary.status, "stopped");
  EXPECT_EQ(summary.steps, 500);
  EXPECT_LT(summary.steps, solver.n_steps());
  EXPECT_EQ(solver.probes().time.size(), 167u);  // every 3rd step

  const nlohmann::json json = nlohmann::json::parse(io::read_file(directory / "transient.json"));
  for (const char* key : {"steps", "dt", "dt_critical", "penalty", "energy_error", "contact_fraction", "wall_s"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["steps"], 500);
  EXPECT_DOUBLE_EQ(json["penalty"].get<double>(), contact_term->contact().penalty().normal_penalty);
  const std::string probes = io::read_file(directory / "probes.csv");
  EXPECT_EQ(probes.substr(0, probes.find('\n')),
            "time [s],tip u_x [m],tip u_y [m],tip u_z [m],tip v_x [m/s],tip v_y [m/s],tip v_z [m/s],"
            "tip a_x [m/s^2],tip a_y [m/s^2],tip a_z [m/s^2]");
  const std::string energy = io::read_file(directory / "energy.csv");
  EXPECT_EQ(energy.substr(0, energy.find('\n')),
            "time [s],kinetic [J],strain [J],contact [J],external_work [J],damping [J],friction [J],balance [J],"
            "relative_error [-]");
  std::filesystem::remove_all(directory);
}

TEST(Outputs, BadOptionsAreRefused) {
  const mesh::Mesh mesh = free_block();
  TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  TransientOptions options;
  options.progress = false;
  EXPECT_THROW(TransientSolver(mesh, problem, options), InputError);  // no end time
  options.end_time = 1e-3;
  options.damping.alpha = -1.0;
  EXPECT_THROW(TransientSolver(mesh, problem, options), InputError);
  options.damping.alpha = 0.0;
  EXPECT_THROW(testing::plug_contact(mesh, problem, contact::ContactOptions{}), InputError);  // contact without a crack
}

}  // namespace
}  // namespace crackle::transient
