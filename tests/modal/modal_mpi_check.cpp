// Runs the same modal analysis on however many MPI ranks it is started with (SLEPc backend,
// automatic factorisation: CHOLMOD on 1 rank, MUMPS on several) and either writes the result
// (--write FILE) or compares it with one written before (--compare FILE): frequencies to 1e-8
// relative and MAC values to 1e-6. Exit code 0 when they agree, on every rank.
#include <petscsys.h>  // brings mpi.h without OpenMPI's C++ bindings (OMPI_SKIP_MPICXX)

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "modal/modal.hpp"
#include "modal_meshes.hpp"
#include "output/modal_json.hpp"

using namespace crackle;

namespace {

nlohmann::json analyse() {
  const mesh::Mesh mesh = modal::testing::box_mesh(Vec3(1.0, 0.1, 0.2), {10, 1, 4}, 3, modal::testing::edge_crack());
  modal::ModalOptions options;
  options.modes = 8;
  const modal::ModalResult result =
      modal::run_modal(mesh, modal::testing::steel(0.3), {modal::testing::fix(mesh, "x-", {0, 1, 2})}, options);
  nlohmann::json document = output::modal_json(result);
  std::printf("rank %d of %d: %s, %d free DOFs, f1 = %.15g Hz (uncracked), %.15g Hz (open)\n", modal::mpi_rank(),
              modal::mpi_size(), document["solver"]["factorization"].get<std::string>().c_str(),
              document["dofs"].get<int>(), result.variants[0].modes.frequencies_hz[0],
              result.variants[1].modes.frequencies_hz[0]);
  return document;
}

bool compare(const nlohmann::json& reference, const nlohmann::json& document) {
  bool agree = true;
  for (const char* variant : {"uncracked", "open"}) {
    const auto& expected = reference["variants"][variant]["frequencies_hz"];
    const auto& actual = document["variants"][variant]["frequencies_hz"];
    if (expected.size() != actual.size()) return false;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      const double e = expected[i].get<double>(), a = actual[i].get<double>();
      if (!(std::abs(a - e) <= 1e-8 * std::abs(e))) {
        std::printf("rank %d: %s mode %zu: %.15g Hz, reference %.15g Hz\n", modal::mpi_rank(), variant, i + 1, a, e);
        agree = false;
      }
    }
  }
  for (std::size_t i = 0; i < reference["pairs"].size(); ++i) {
    const double e = reference["pairs"][i]["mac"].get<double>(), a = document["pairs"][i]["mac"].get<double>();
    if (!(std::abs(a - e) <= 1e-6)) {
      std::printf("rank %d: pair %zu: MAC %.12g, reference %.12g\n", modal::mpi_rank(), i + 1, a, e);
      agree = false;
    }
  }
  return agree;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    modal::SlepcSession session(&argc, &argv);
    if (argc != 3 || (std::string(argv[1]) != "--write" && std::string(argv[1]) != "--compare")) {
      std::fprintf(stderr, "usage: modal_mpi_check --write|--compare FILE\n");
      return 2;
    }
    const nlohmann::json document = analyse();
    int ok = 1;
    if (std::string(argv[1]) == "--write") {
      if (modal::is_output_rank()) std::ofstream(argv[2]) << document.dump(1);
    } else {
      std::ifstream file(argv[2]);
      if (!file) throw IoError(std::string("cannot read ") + argv[2]);
      ok = compare(nlohmann::json::parse(file), document) ? 1 : 0;
    }
    int all_ok = 0;
    MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (modal::is_output_rank()) std::printf("%s\n", all_ok ? "agree" : "DIFFER");
    return all_ok ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "modal_mpi_check: %s\n", error.what());
    return 1;
  }
}
