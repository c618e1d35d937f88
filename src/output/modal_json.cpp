#include "output/modal_json.hpp"

#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/csv.hpp"
#include "io/files.hpp"
#include "io/vtu.hpp"

namespace crackle::output {
namespace {

using modal::ModalResult;
using modal::ModePair;
using modal::VariantResult;
using modal::ModeSet;
using modal::MacWeighting;
using modal::SolveReport;
using modal::Solver;

std::vector<double> to_std(const VectorX& values) { return {values.data(), values.data() + values.size()}; }

}  // namespace

nlohmann::json modal_json(const ModalResult& result) {
  using nlohmann::json;
  json document;
  Index largest = 0;
  double assembly = 0.0;
  double factorization = 0.0;
  double iterations = 0.0;
  double postprocess = 0.0;
  json variants = json::object();
  for (const VariantResult& variant : result.variants) {
    const ModeSet& modes = variant.modes;
    largest = std::max(largest, variant.constraints.n_free());
    assembly += variant.assembly_s;
    factorization += modes.report.factorization_s;
    iterations += modes.report.iterations_s;
    postprocess += modes.report.postprocess_s;
    variants[mesh::variant_name(variant.variant)] = {
        {"frequencies_hz", to_std(modes.frequencies_hz)},
        {"dofs", variant.dofs.n_dofs()},
        {"free_dofs", variant.constraints.n_free()},
        {"pieces", variant.n_pieces},
        {"rigid_body_modes", modes.n_rigid()},
        {"rigid_body_modes_expected", modes.n_rigid_expected},
        {"rigid_frequencies_hz", to_std(modes.rigid_frequencies_hz)},
        {"orthogonality_error", modes.orthogonality_error},
        {"backend_orthogonality_error", modes.backend_orthogonality_error},
        {"max_relative_residual", modes.max_residual},
        {"shift_rad2_s2", modes.report.shift},
        {"reference_eigenvalue_rad2_s2", modes.report.reference_eigenvalue},
        {"eigenpairs_computed", modes.report.n_eigenpairs},
        {"iterations", modes.report.iterations},
        {"attempts", modes.report.attempts},
        {"from_cache", modes.report.from_cache},
        {"timings_s",
         {{"assembly", variant.assembly_s},
          {"factorization", modes.report.factorization_s},
          {"iterations", modes.report.iterations_s},
          {"solve", modes.report.solve_s},
          {"postprocess", modes.report.postprocess_s}}},
    };
  }
  document["dofs"] = largest;  // free DOFs of the largest eigenproblem solved
  document["variants"] = variants;
  json pairs = json::array();
  for (const ModePair& pair : result.pairs) {
    pairs.push_back({{"uncracked_mode", pair.uncracked_mode + 1},
                     {"open_mode", pair.open_mode + 1},
                     {"f_uncracked_hz", pair.f_uncracked_hz},
                     {"f_open_hz", pair.f_open_hz},
                     {"ratio", pair.ratio},
                     {"mac", pair.mac},
                     {"f_bilinear_hz", pair.f_bilinear_hz},
                     {"paired", pair.paired}});
  }
  document["pairs"] = pairs;
  json mac = json::array();  // MAC[uncracked mode][open mode], for spotting mode mixing
  for (Index i = 0; i < result.mac.rows(); ++i) {
    std::vector<double> row(result.mac.cols());
    for (Index j = 0; j < result.mac.cols(); ++j) row[j] = result.mac(i, j);
    mac.push_back(row);
  }
  document["mac_matrix"] = mac;
  document["mac_weighting"] = result.options.mac == MacWeighting::mass ? "mass" : "plain";
  const SolveReport* report = result.variants.empty() ? nullptr : &result.variants.front().modes.report;
  document["solver"] = {
      {"backend", solver_name(result.options.solver)},
      {"method", result.options.solver == Solver::slepc ? "Krylov-Schur, shift-and-invert"
                                                        : "implicitly restarted Lanczos (dsaupd mode 3)"},
      {"factorization", report ? report->factorization : ""},
      {"ranks", report ? report->n_ranks : 1},
      {"tolerance", result.options.tolerance},
      {"mass", result.options.lumped_mass ? "lumped" : "consistent"},
      {"modes", result.options.modes},
  };
  document["timings_s"] = {{"assembly", assembly},
                           {"factorization", factorization},
                           {"iterations", iterations},
                           {"postprocess", postprocess},
                           {"total", result.total_s}};
  return document;
}

void write_modal_tables(const std::filesystem::path& directory, const ModalResult& result,
                        const nlohmann::json* accuracy_block) {
  io::ensure_directory(directory);
  const nlohmann::json accuracy = accuracy_block ? *accuracy_block : nlohmann::json();
  nlohmann::json document = modal_json(result);
  if (!accuracy.is_null()) document["accuracy"] = accuracy;
  io::write_json(directory / "modal.json", document);

  // The estimated relative error (the sum of its components) of one frequency, NaN where none.
  auto error_of = [&](const nlohmann::json& estimate) {
    return estimate.is_object() && estimate.value("error", nlohmann::json()).is_number()
               ? estimate["error"].get<double>()
               : std::numeric_limits<double>::quiet_NaN();
  };
  const bool estimated = accuracy.is_object() && accuracy.value("estimated", false);
  io::CsvTable table;
  if (!result.pairs.empty()) {
    std::vector<double> mode, f_u, open_mode, f_o, ratio, mac, f_b, paired;
    std::vector<double> f_u_error, f_o_error, f_b_error;
    for (std::size_t i = 0; i < result.pairs.size(); ++i) {
      const ModePair& pair = result.pairs[i];
      mode.push_back(pair.uncracked_mode + 1);
      f_u.push_back(pair.f_uncracked_hz);
      open_mode.push_back(pair.open_mode + 1);
      f_o.push_back(pair.f_open_hz);
      ratio.push_back(pair.ratio);
      mac.push_back(pair.mac);
      f_b.push_back(pair.f_bilinear_hz);
      paired.push_back(pair.paired ? 1.0 : 0.0);
      if (estimated) {
        const nlohmann::json& estimates = accuracy.at("pairs").at(i);
        f_u_error.push_back(error_of(estimates.value("f_uncracked_hz", nlohmann::json())));
        f_o_error.push_back(error_of(estimates.value("f_open_hz", nlohmann::json())));
        f_b_error.push_back(error_of(estimates.value("f_bilinear_hz", nlohmann::json())));
      }
    }
    table.add("mode [-]", mode);
    table.add("f_uncracked [Hz]", f_u);
    table.add("open_mode [-]", open_mode);
    table.add("f_open [Hz]", f_o);
    table.add("ratio [-]", ratio);
    table.add("mac [-]", mac);
    table.add("f_bilinear [Hz]", f_b);
    table.add("paired [-]", paired);
    if (estimated) {
      table.add("f_uncracked error [-]", f_u_error);
      table.add("f_open error [-]", f_o_error);
      table.add("f_bilinear error [-]", f_b_error);
    }
  } else if (!result.variants.empty()) {
    std::vector<double> mode;
    for (int i = 0; i < result.variants.front().modes.n_modes(); ++i) mode.push_back(i + 1);
    table.add("mode [-]", mode);
    for (const VariantResult& variant : result.variants) {
      table.add(std::string("f_") + mesh::variant_name(variant.variant) + " [Hz]",
                to_std(variant.modes.frequencies_hz));
    }
    for (const VariantResult& variant : result.variants) {
      if (!estimated) break;
      const nlohmann::json& estimates = accuracy.at("variants").at(mesh::variant_name(variant.variant)).at("frequencies_hz");
      std::vector<double> errors;
      for (int i = 0; i < variant.modes.n_modes(); ++i) errors.push_back(error_of(estimates.at(i)));
      table.add(std::string("f_") + mesh::variant_name(variant.variant) + " error [-]", errors);
    }
  }
  io::write_csv(directory / "modes.csv", table);
}

void write_modal_outputs(const std::filesystem::path& directory, const mesh::Mesh& mesh,
                         const ModalResult& result, const nlohmann::json* accuracy_block) {
  write_modal_tables(directory, result, accuracy_block);

  for (const VariantResult& variant : result.variants) {
    std::vector<io::PointField> fields;
    for (int mode = 0; mode < variant.modes.n_modes(); ++mode) {
      char name[32];
      std::snprintf(name, sizeof name, "mode_%02d", mode + 1);
      fields.push_back({name, 3, modal::nodal_shape(mesh, variant, mode)});
    }
    io::write_vtu(directory / (std::string("modes_") + mesh::variant_name(variant.variant) + ".vtu"), mesh,
                  fields);
  }
}

}  // namespace crackle::output
