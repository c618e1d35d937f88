/// \file `crackle._crackle`: the pybind11 layer under the Python package `crackle` (python/crackle).
///
/// Each command runs the same library function the command line calls (pipeline::run_*_command,
/// study::run_study, identify::run_identify) into the output folder the package gives it; what the
/// pipeline hands back in memory (the modal result, the mesh) becomes NumPy arrays here. Around
/// every call: the GIL is released, std::cerr and the command's own streams go line by line to a
/// Python callable, and a pending KeyboardInterrupt stops the loops (core/interrupt.hpp).
#include <omp.h>
#include <petscsys.h>
#include <slepcsys.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11_json/pybind11_json.hpp>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <functional>
#include <iostream>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "identify/identify.hpp"
#include "planning/planning.hpp"
#include "mesh/mesh.hpp"
#include "modal/eigensolver.hpp"
#include "modal/modal.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/model.hpp"
#include "pipeline/sweep.hpp"
#include "scene/scene.hpp"
#include "scene/schema.hpp"
#include "study/study.hpp"

namespace py = pybind11;
using namespace crackle;

namespace {

// ---- streams: text lines to a Python callable ----------------------------------------------

/// The Python error that stops the call: a KeyboardInterrupt (or what a SIGINT handler raised)
/// found by the interrupt check or raised inside a progress callback.
std::unique_ptr<py::error_already_set> pending_error;

/// A streambuf that hands every line (ended by \n or \r, as progress lines are) to a Python
/// callable `sink(line)`, taking the GIL for it. Errors raised by the sink are reported as
/// unraisable and do not stop the run, but for a KeyboardInterrupt (Python runs its signal
/// handlers inside the sink too): it is kept, and the next interrupt poll stops the run.
class LineBuffer : public std::streambuf {
 public:
  explicit LineBuffer(py::object sink) : sink_(std::move(sink)) {}
  ~LineBuffer() override { emit(); }

  /// Hands over what is left without an end of line.
  void emit() {
    if (line_.empty()) return;
    std::string text;
    std::swap(text, line_);
    if (sink_.is_none()) return;
    py::gil_scoped_acquire gil;
    try {
      sink_(text);
    } catch (py::error_already_set& error) {
      if (error.matches(PyExc_KeyboardInterrupt)) {
        if (!pending_error) pending_error = std::make_unique<py::error_already_set>(std::move(error));
      } else {
        error.discard_as_unraisable("crackle progress callback");
      }
    }
  }

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    if (c == '\n' || c == '\r') {
      emit();
    } else {
      line_.push_back(static_cast<char>(c));
    }
    return c;
  }
  int sync() override { return 0; }

 private:
  py::object sink_;
  std::string line_;
};

/// std::cerr into `buffer` for its lifetime (the library's warnings and progress lines).
class CerrRedirect {
 public:
  explicit CerrRedirect(std::streambuf* buffer) : previous_(std::cerr.rdbuf(buffer)) {}
  ~CerrRedirect() { std::cerr.rdbuf(previous_); }
  CerrRedirect(const CerrRedirect&) = delete;
  CerrRedirect& operator=(const CerrRedirect&) = delete;

 private:
  std::streambuf* previous_;
};

// ---- KeyboardInterrupt ---------------------------------------------------------------------

/// The check installed during a call: runs Python's signal handlers every 50 ms (from the main
/// thread, which runs the loops; PyErr_CheckSignals does nothing on other threads).
bool python_signal_pending() {
  if (pending_error) return true;
  using Clock = std::chrono::steady_clock;
  static Clock::time_point last;
  const Clock::time_point now = Clock::now();
  if (now - last < std::chrono::milliseconds(50)) return false;
  last = now;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  pending_error = std::make_unique<py::error_already_set>();
  return true;
}

/// Installs the check for its lifetime.
class InterruptScope {
 public:
  InterruptScope() : previous_(set_interrupt_check(&python_signal_pending)) {}
  ~InterruptScope() { set_interrupt_check(previous_); }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  InterruptCheck previous_;
};

/// Runs `body(out)` without the GIL, with `out` and std::cerr going to `sink` line by line and
/// a KeyboardInterrupt stopping it; the Python error of an interruption is raised again here.
template <class Body>
auto call_library(const py::object& sink, Body&& body) {
  pending_error.reset();
  LineBuffer buffer(sink);
  std::ostream out(&buffer);
  const CerrRedirect redirect(&buffer);
  const InterruptScope scope;
  const auto raise_pending = [&]() {
    buffer.emit();
    if (!pending_error) return;
    py::error_already_set error = std::move(*pending_error);
    pending_error.reset();
    throw error;
  };
  try {
    auto value = [&]() {
      const py::gil_scoped_release release;
      return body(out);
    }();
    raise_pending();  // interrupted after the last poll (in a callback): the result is dropped
    return value;
  } catch (const Interrupted&) {
    raise_pending();
    throw;
  }
}

// ---- PETSc and SLEPc -----------------------------------------------------------------------

/// PETSc's argv: "crackle" and the options of set_petsc_options (never sys.argv).
std::vector<std::string> petsc_words = {"crackle"};
std::vector<char*> petsc_pointers;
int petsc_argc = 0;
char** petsc_argv = nullptr;
/// Started on the first SLEPc solve (only if nobody initialised SLEPc), finalised by shutdown().
std::unique_ptr<modal::SlepcSession> slepc_session;
bool session_ended = false;  ///< MPI cannot start again in this process

/// petsc_argc and petsc_argv (which the session reads when it starts) from petsc_words.
void refresh_petsc_argv() {
  petsc_pointers.clear();
  for (std::string& word : petsc_words) petsc_pointers.push_back(word.data());
  petsc_argc = static_cast<int>(petsc_words.size());
  petsc_pointers.push_back(nullptr);  // MPI expects argv[argc] == NULL
  petsc_argv = petsc_pointers.data();
}

void ensure_session() {
  if (session_ended) throw SolverError("crackle: SLEPc was finalised in this process (crackle._crackle.shutdown)");
  if (slepc_session) return;
  refresh_petsc_argv();
  slepc_session = std::make_unique<modal::SlepcSession>(&petsc_argc, &petsc_argv,
                                                        modal::SlepcSession::Start::on_first_use);
}

/// Options as `-name value` pairs (a value of None or "" gives the bare `-name`).
void set_petsc_options(const std::vector<std::pair<std::string, std::string>>& options) {
  PetscBool initialised = PETSC_FALSE;
  PetscInitialized(&initialised);
  for (const auto& [name, value] : options) {
    const std::string option = name.empty() || name[0] == '-' ? name : "-" + name;
    if (initialised) {
      if (PetscOptionsSetValue(nullptr, option.c_str(), value.empty() ? nullptr : value.c_str()) != 0)
        throw InputError("PETSc option " + option + ": PetscOptionsSetValue failed");
    } else {
      petsc_words.push_back(option);
      if (!value.empty()) petsc_words.push_back(value);
    }
  }
  if (!initialised) {
    // PETSc starts now, so that the options are in its database: modal.solver: auto reads SLEPc
    // options there and takes SLEPc for them.
    refresh_petsc_argv();
    if (!options.empty()) {
      ensure_session();
      modal::SlepcSession::start();
    }
  }
}

bool petsc_initialised() {
  PetscBool initialised = PETSC_FALSE;
  PetscInitialized(&initialised);
  return initialised == PETSC_TRUE;
}

/// Waits for a factorisation that an interruption left running (core/interrupt.hpp), then ends
/// crackle's SLEPc session (SlepcFinalize, and PetscFinalize only if SLEPc started PETSc).
void shutdown() {
  {
    const py::gil_scoped_release release;
    wait_for_abandoned_work();
  }
  if (slepc_session) session_ended = true;
  slepc_session.reset();
}

// ---- arrays --------------------------------------------------------------------------------

/// A NumPy array of `shape` that takes over `values` without a copy.
template <class T>
py::array_t<T> to_array(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free(owned, [](void* pointer) { delete static_cast<std::vector<T>*>(pointer); });
  return py::array_t<T>(shape, owned->data(), free);
}

/// Plain copies of a mesh, made without the GIL.
struct MeshArrays {
  std::vector<double> nodes;
  std::vector<std::int64_t> connectivity, regions, minus, plus;
  std::vector<double> normals, areas;
  py::ssize_t n_nodes = 0, n_elements = 0, nodes_per_element = 0, n_pairs = 0;
  Index n_original_nodes = 0;
  int order = 1;
  std::string shape;
  double crack_area = 0.0;

  explicit MeshArrays(const mesh::Mesh& mesh)
      : n_nodes(mesh.n_nodes()),
        n_elements(mesh.n_elements()),
        nodes_per_element(mesh.nodes_per_element()),
        n_pairs(static_cast<py::ssize_t>(mesh.crack_pairs.size())),
        n_original_nodes(mesh.n_original_nodes),
        order(mesh.order),
        shape(mesh.shape == mesh::ElementShape::tetrahedron ? "tetrahedron" : "hexahedron"),
        crack_area(mesh.crack_area) {
    for (const Vec3& node : mesh.nodes) nodes.insert(nodes.end(), {node[0], node[1], node[2]});
    connectivity.assign(mesh.connectivity.begin(), mesh.connectivity.end());
    regions.assign(mesh.element_region.begin(), mesh.element_region.end());
    for (const mesh::CrackPair& pair : mesh.crack_pairs) {
      minus.push_back(pair.minus);
      plus.push_back(pair.plus);
      normals.insert(normals.end(), {pair.normal[0], pair.normal[1], pair.normal[2]});
      areas.push_back(pair.area);
    }
  }

  py::dict to_python() {
    py::dict out;
    out["nodes"] = to_array(std::move(nodes), {n_nodes, 3});
    out["connectivity"] = to_array(std::move(connectivity), {n_elements, nodes_per_element});
    out["element_region"] = to_array(std::move(regions), {n_elements});
    py::dict pairs;
    pairs["minus"] = to_array(std::move(minus), {n_pairs});
    pairs["plus"] = to_array(std::move(plus), {n_pairs});
    pairs["normal"] = to_array(std::move(normals), {n_pairs, 3});
    pairs["area"] = to_array(std::move(areas), {n_pairs});
    out["crack_pairs"] = pairs;
    out["n_original_nodes"] = n_original_nodes;
    out["order"] = order;
    out["shape"] = shape;
    out["crack_area"] = crack_area;
    return out;
  }
};

/// Plain copies of a modal result (frequencies, nodal mode shapes, pairs, MAC).
struct ModalArrays {
  struct Variant {
    std::string name;
    std::vector<double> frequencies, shapes;
    py::ssize_t n_modes = 0;
  };
  std::vector<Variant> variants;
  std::vector<std::vector<double>> pair_columns;
  std::vector<double> mac;
  py::ssize_t mac_rows = 0, mac_columns = 0, n_nodes = 0;
  std::unique_ptr<MeshArrays> mesh;

  static constexpr const char* kPairColumns[8] = {"uncracked_mode", "open_mode", "f_uncracked_hz", "f_open_hz",
                                                   "ratio",          "mac",       "f_bilinear_hz",  "paired"};

  void take(const pipeline::Model& model, const modal::ModalResult& result) {
    mesh = std::make_unique<MeshArrays>(model.mesh);
    n_nodes = model.mesh.n_nodes();
    for (const modal::VariantResult& variant : result.variants) {
      Variant copy;
      copy.name = mesh::variant_name(variant.variant);
      copy.n_modes = variant.modes.n_modes();
      copy.frequencies.assign(variant.modes.frequencies_hz.data(),
                              variant.modes.frequencies_hz.data() + variant.modes.frequencies_hz.size());
      for (int mode = 0; mode < variant.modes.n_modes(); ++mode) {
        const std::vector<double> shape = modal::nodal_shape(model.mesh, variant, mode);
        copy.shapes.insert(copy.shapes.end(), shape.begin(), shape.end());
      }
      variants.push_back(std::move(copy));
    }
    pair_columns.assign(8, {});
    for (const modal::ModePair& pair : result.pairs) {
      const double row[8] = {double(pair.uncracked_mode + 1), double(pair.open_mode + 1), pair.f_uncracked_hz,
                             pair.f_open_hz, pair.ratio, pair.mac, pair.f_bilinear_hz, pair.paired ? 1.0 : 0.0};
      for (int c = 0; c < 8; ++c) pair_columns[c].push_back(row[c]);
    }
    mac_rows = result.mac.rows();
    mac_columns = result.mac.cols();
    for (py::ssize_t i = 0; i < mac_rows; ++i)
      for (py::ssize_t j = 0; j < mac_columns; ++j) mac.push_back(result.mac(i, j));
  }

  py::dict to_python() {
    py::dict out, frequencies, shapes, pairs;
    for (Variant& variant : variants) {
      const py::ssize_t n = static_cast<py::ssize_t>(variant.frequencies.size());
      frequencies[py::str(variant.name)] = to_array(std::move(variant.frequencies), {n});
      shapes[py::str(variant.name)] = to_array(std::move(variant.shapes), {variant.n_modes, n_nodes, 3});
    }
    for (int c = 0; c < 8; ++c) {
      const py::ssize_t n = static_cast<py::ssize_t>(pair_columns[c].size());
      pairs[kPairColumns[c]] = to_array(std::move(pair_columns[c]), {n});
    }
    out["frequencies_hz"] = frequencies;
    out["shapes"] = shapes;
    out["pairs"] = pairs;
    out["mac"] = to_array(std::move(mac), {mac_rows, mac_columns});
    out["mesh"] = mesh ? mesh->to_python() : py::dict();
    return out;
  }
};

// ---- the parameter table -------------------------------------------------------------------

const char* kind_name(scene::Kind kind) {
  switch (kind) {
    case scene::Kind::map: return "map";
    case scene::Kind::list: return "list";
    case scene::Kind::number: return "number";
    case scene::Kind::integer: return "integer";
    case scene::Kind::choice: return "choice";
    case scene::Kind::boolean: return "boolean";
    case scene::Kind::text: return "text";
  }
  return "";
}

/// One row per key of the table (and of its maps and lists, list entries as `[]`).
void parameter_rows(const scene::Param& param, const std::string& prefix, py::list& rows) {
  for (const scene::Param& child : param.children) {
    const std::string path = prefix + child.name;
    py::dict row;
    row["key"] = path;
    row["kind"] = kind_name(child.kind);
    row["expects"] = scene::describe(child);
    row["unit"] = child.unit;
    row["required"] = child.is_required;
    row["default"] = child.default_text;
    row["choices"] = child.choices;
    row["doc"] = child.doc;
    rows.append(row);
    if (child.kind == scene::Kind::map) parameter_rows(child, path + ".", rows);
    if (child.kind == scene::Kind::list) parameter_rows(child, path + "[].", rows);
  }
}

py::list parameters() {
  py::list rows;
  for (const scene::Param* table :
       {&scene::scene_parameters(), &scene::study_parameters(), &scene::identify_parameters(), &scene::plan_parameters()})
    parameter_rows(*table, "", rows);
  return rows;
}

// ---- errors --------------------------------------------------------------------------------

/// Raises the class `name` of crackle.errors with `message`.
void raise_crackle(const char* name, const char* message) {
  const py::object type = py::module_::import("crackle.errors").attr(name);
  PyErr_SetObject(type.ptr(), py::str(message).ptr());
}

void translate(std::exception_ptr error) {
  try {
    if (error) std::rethrow_exception(error);
  } catch (const Interrupted& interrupted) {
    PyErr_SetString(PyExc_KeyboardInterrupt, interrupted.what());
  } catch (const InputError& input) {
    raise_crackle("SceneError", input.what());
  } catch (const SolverError& solver) {
    raise_crackle("SolverError", solver.what());
  } catch (const IoError& io) {
    raise_crackle("IoError", io.what());
  } catch (const Error& other) {
    raise_crackle("CrackleError", other.what());
  }
}

std::vector<scene::Override> overrides_of(const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::vector<scene::Override> overrides;
  for (const auto& [path, value] : pairs) overrides.push_back({path, value});
  return overrides;
}

std::vector<std::string> assignments_of(const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::vector<std::string> assignments;
  for (const auto& [path, value] : pairs) assignments.push_back(path + "=" + value);
  return assignments;
}

using Pairs = std::vector<std::pair<std::string, std::string>>;

/// `crackle run` and `crackle sweep`, whose options share their fields: `name(path, overrides,
/// output, modal_cache, progress, sink, accuracy_start)`.
template <class Options, class Runner>
void define_stage_command(py::module_& module, const char* name, Runner runner) {
  module.def(
      name,
      [runner](const std::string& path, const Pairs& overrides, const std::string& output,
               const std::string& modal_cache, bool progress, const py::object& sink,
               const std::string& accuracy_start) {
        ensure_session();
        Options options;
        options.accuracy_start = accuracy_start;
        options.scene_path = path;
        options.overrides = assignments_of(overrides);
        options.output_directory = output;
        options.modal_cache = modal_cache;
        options.progress = progress;
        call_library(sink, [&](std::ostream& out) {
          runner(options, out);
          return 0;
        });
      },
      py::arg("path"), py::arg("overrides"), py::arg("output"), py::arg("modal_cache") = "",
      py::arg("progress") = true, py::arg("sink") = py::none(), py::arg("accuracy_start") = "");
}

}  // namespace

PYBIND11_MODULE(_crackle, module) {
  module.doc() = "crackle's library (see the package crackle for the documented interface)";
  py::register_exception_translator(&translate);

  module.def(
      "validate",
      [](const std::string& text, const std::string& name, const Pairs& overrides) {
        const scene::Scene scene = scene::parse_scene(text, name, overrides_of(overrides));
        py::dict sections;
        sections["transient"] = scene.transient.has_value();
        sections["spectrum"] = scene.spectrum.has_value();
        sections["sweep"] = scene.sweep.has_value();
        sections["modal"] = scene.has_modal_section;
        sections["crack"] = scene.has_crack();
        return sections;
      },
      py::arg("text"), py::arg("name"), py::arg("overrides"),
      "Validates a scene (YAML text; `name` stands for its file in messages) with overrides (key, "
      "YAML value) as `--set` does; InputError -> SceneError. Returns which sections it has.");
  module.def("read_scene_file", &scene::read_scene_file, py::arg("path"));
  module.def(
      "effective_text",
      [](const std::string& text, const std::string& name, const Pairs& overrides) {
        YAML::Node document = scene::parse_yaml(text, name);
        for (const auto& [path, value] : overrides) scene::apply_override(document, path, value, name);
        YAML::Emitter emitter;
        emitter << document;
        return std::string(emitter.c_str()) + "\n";
      },
      py::arg("text"), py::arg("name"), py::arg("overrides"),
      "The YAML text with the overrides applied (for the commands that take no --set: study, identify).");
  module.def("parameters", &parameters, "The parameter table: one dict per key.");
  module.def("scene_format_markdown", &scene::scene_format_markdown);
  module.def(
      "check_override",
      [](const std::string& assignment) { return pipeline::parse_overrides({assignment}).front().path; },
      py::arg("assignment"), "Parses `key.path=value` like --set; returns the key path.");

  module.def(
      "mesh",
      [](const std::string& path, const Pairs& overrides, bool for_modal) {
        std::unique_ptr<MeshArrays> arrays = call_library(py::none(), [&](std::ostream&) {
          const scene::Scene scene = scene::load_scene(path, pipeline::parse_overrides(assignments_of(overrides)));
          const pipeline::Model model =
              pipeline::build_model(scene, for_modal ? pipeline::MeshUse::modal : pipeline::MeshUse::transient);
          return std::make_unique<MeshArrays>(model.mesh);
        });
        return arrays->to_python();
      },
      py::arg("path"), py::arg("overrides"), py::arg("for_modal") = false);

  module.def(
      "modal",
      [](const std::string& path, const Pairs& overrides, const std::string& output, int modes,
         const std::string& solver, const std::string& modal_cache, const py::object& sink) {
        ensure_session();
        pipeline::ModalCommandOptions options;
        options.scene_path = path;
        options.overrides = assignments_of(overrides);
        options.output_directory = output;
        options.modes = modes;
        options.solver = solver;
        options.solver_option = "solver";
        options.modal_cache = modal_cache;
        ModalArrays arrays;
        call_library(sink, [&](std::ostream& out) {
          pipeline::run_modal_command(options, out, [&arrays](const pipeline::Model& model,
                                                              const modal::ModalResult& result) {
            arrays.take(model, result);
          });
          return 0;
        });
        return arrays.to_python();
      },
      py::arg("path"), py::arg("overrides"), py::arg("output"), py::arg("modes") = 0, py::arg("solver") = "",
      py::arg("modal_cache") = "", py::arg("sink") = py::none());

  define_stage_command<pipeline::RunCommandOptions>(
      module, "run", [](const pipeline::RunCommandOptions& options, std::ostream& out) {
        pipeline::run_run_command(options, out);
      });
  define_stage_command<pipeline::SweepCommandOptions>(
      module, "sweep", [](const pipeline::SweepCommandOptions& options, std::ostream& out) {
        pipeline::run_sweep_command(options, out, out);
      });

  module.def(
      "study",
      [](const std::string& path, const std::string& output, const std::string& executable, int jobs,
         bool modal_cache, bool retry_failed, double case_timeout_s, const py::object& sink) {
        study::StudyOptions options;
        options.scene_path = path;
        options.output_dir = output;
        options.executable = executable;
        options.jobs = jobs;
        options.modal_cache = modal_cache;
        options.retry_failed = retry_failed;
        options.case_timeout_s = case_timeout_s;
        return call_library(sink, [&](std::ostream& out) { return study::run_study(options, out); });
      },
      py::arg("path"), py::arg("output"), py::arg("executable"), py::arg("jobs") = 0, py::arg("modal_cache") = true,
      py::arg("retry_failed") = false, py::arg("case_timeout_s") = 0.0, py::arg("sink") = py::none(),
      "Runs the study; returns its exit code (0, 3 some cases failed, 130 interrupted).");

  module.def(
      "identify",
      [](const std::string& path, const std::string& output, const std::string& executable, int jobs,
         const std::string& map_cache, const py::object& sink) {
        identify::IdentifyOptions options;
        options.scene_path = path;
        options.output_dir = output;
        options.executable = executable;
        options.jobs = jobs;
        options.map_cache = map_cache;
        nlohmann::json document =
            call_library(sink, [&](std::ostream& out) { return identify::run_identify(options, out); });
        return document;
      },
      py::arg("path"), py::arg("output"), py::arg("executable"), py::arg("jobs") = 0, py::arg("map_cache") = "",
      py::arg("sink") = py::none());

  module.def(
      "plan",
      [](const std::string& path, const std::string& output, const std::string& executable, int jobs,
         const py::object& sink) {
        planning::PlanOptions options;
        options.scene_path = path;
        options.output_dir = output;
        options.executable = executable;
        options.jobs = jobs;
        nlohmann::json document = call_library(sink, [&](std::ostream& out) { return planning::run_plan(options, out); });
        return document;
      },
      py::arg("path"), py::arg("output"), py::arg("executable"), py::arg("jobs") = 0, py::arg("sink") = py::none());

  module.def(
      "set_threads", [](int threads) { omp_set_num_threads(threads); }, py::arg("threads"),
      "OpenMP threads of the element loops and Eigen (OMP_NUM_THREADS at start-up).");
  module.def("threads", []() { return omp_get_max_threads(); });
  module.def("set_petsc_options", &set_petsc_options, py::arg("options"));
  module.def("petsc_initialized", &petsc_initialised);
  module.def("slepc_initialized", []() {
    PetscBool initialised = PETSC_FALSE;
    SlepcInitialized(&initialised);
    return initialised == PETSC_TRUE;
  });
  module.def("background_work", &background_work,
             "Factorisations still running on workers that an interruption left behind (core/interrupt.hpp).");
  module.def("shutdown", &shutdown, "Waits for work an interruption left running, then ends crackle's SLEPc session, if it started one (atexit).");
  module.def("exit_code", [](const std::string& kind) {
    if (kind == "input") return exit_code_for(InputError(""));
    if (kind == "solver") return exit_code_for(SolverError(""));
    if (kind == "io") return exit_code_for(IoError(""));
    if (kind == "interrupted") return exit_code_for(Interrupted(""));
    return 1;
  });
}
