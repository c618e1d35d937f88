#pragma once
/// \file A scene: the validated contents of a YAML scene file as plain structs (SI units).
///
/// Every parameter is declared once in the parameter table (schema.hpp): name, type, range,
/// default and doc. The loader validates the YAML against that table, rejects unknown keys, and
/// reports `file:line: key.path: expected ..., got ...` as an InputError. The same table generates
/// docs/scene-format.md.
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/choices.hpp"
#include "core/defaults.hpp"
#include "core/types.hpp"
#include "mesh/box.hpp"

namespace crackle::scene {

struct MaterialSection {
  double young = 0.0;    ///< E [Pa]
  double poisson = 0.0;  ///< nu
  double density = 0.0;  ///< rho [kg/m^3]
};

/// Orthotropic engineering constants of `materials[].orthotropic` (axes 1, 2, 3) [Pa].
struct OrthotropicSection {
  double e1 = 0.0, e2 = 0.0, e3 = 0.0, g12 = 0.0, g13 = 0.0, g23 = 0.0;
  double nu12 = 0.0, nu13 = 0.0, nu23 = 0.0;
};

/// Where a material of `materials:` is: element centroids inside every given range and, for a Gmsh
/// mesh, elements of the volume group. Nothing given: everywhere.
struct RegionSection {
  std::array<std::optional<std::array<double, 2>>, 3> range;  ///< per axis [m]
  std::string group;                                           ///< physical volume group, or empty
};

/// One entry of `materials:` (layered composites).
struct MaterialEntrySection {
  std::string name;
  std::optional<MaterialSection> isotropic;      ///< E, nu (and rho = density)
  std::optional<OrthotropicSection> orthotropic;
  double density = 0.0;  ///< rho [kg/m^3]
  double angle = 0.0;    ///< ply angle about z [deg]
  RegionSection region;
  int line = 0;  ///< 1-based line of the entry, for messages
};

/// `crack: {group: ...}`: a physical surface group of a Gmsh mesh.
struct GroupCrackSection {
  std::string group;
  double gap = 0.0;  ///< initial normal gap g0 [m] (MODEL.md eq. 9)
  int line = 0;
};

/// One entry of `boundary:`: fix components of every node of a face or a mesh group.
struct BoundarySection {
  std::string face;             ///< x-, x+, y-, y+, z-, z+; empty when `group` is given
  std::string group;            ///< a named node set of the mesh (Gmsh physical group), or empty
  std::vector<int> components;  ///< 0, 1, 2 for x, y, z
  std::vector<double> values;   ///< prescribed displacement [m] per component (default 0)
  int line = 0;                 ///< 1-based line in the scene file, for messages
};

/// The axes x, y, z as the indices 0, 1, 2 (directions, components, crack normals).
inline constexpr Words<int, 3> kAxisWords{{{"x", 0}, {"y", 1}, {"z", 2}}};

/// `modal.solver`: ARPACK on one process and SLEPc under mpirun or with SLEPc options (auto), or
/// the one named (pipeline/modal_command.cpp resolves auto).
enum class ModalSolver { automatic, slepc, arpack };
inline constexpr Words<ModalSolver, 3> kModalSolverWords{
    {{"auto", ModalSolver::automatic}, {"slepc", ModalSolver::slepc}, {"arpack", ModalSolver::arpack}}};

/// `modal.mass`: the consistent or the lumped mass matrix.
enum class MassMatrix { consistent, lumped };
inline constexpr Words<MassMatrix, 2> kMassMatrixWords{
    {{"consistent", MassMatrix::consistent}, {"lumped", MassMatrix::lumped}}};

/// The `modal:` section (issue 3).
struct ModalSection {
  int modes = defaults::kModes;
  std::vector<mesh::Variant> variants;  ///< uncracked and/or open; defaulted by the loader
  ModalSolver solver = ModalSolver::automatic;
  MassMatrix mass = MassMatrix::consistent;
};

/// `crack.contact.model`: penalty (the faces touch: a breathing crack) or none (the faces pass
/// through each other: the open body, a linear run).
enum class ContactModel { penalty, none };
inline constexpr Words<ContactModel, 2> kContactModelWords{
    {{"penalty", ContactModel::penalty}, {"none", ContactModel::none}}};

/// `crack.contact`: penalty contact options of transient runs.
struct ContactSection {
  std::optional<double> penalty;  ///< eps_N [Pa/m]; empty: auto
  double friction = 0.0;          ///< Coulomb mu
  ContactIntegration integration = ContactIntegration::implicit;  ///< core/choices.hpp
  ContactModel model = ContactModel::penalty;
};

/// `transient.excitation`.
/// Whose mode a frequency `{mode: n, ratio: r}` is relative to (`of`): the bilinear frequency of a
/// paired mode, the uncracked body's or the open body's.
enum class ModeOf { bilinear, uncracked, open };
inline constexpr Words<ModeOf, 3> kModeOfWords{
    {{"bilinear", ModeOf::bilinear}, {"uncracked", ModeOf::uncracked}, {"open", ModeOf::open}}};
inline std::string mode_of_name(ModeOf of) { return text_of(kModeOfWords, of); }

/// `transient.excitation.kind`: harmonic (sin(2 pi f t) ramped in) or pulse (an impact-hammer blow).
enum class ExcitationKind { harmonic, pulse };
inline constexpr Words<ExcitationKind, 2> kExcitationKindWords{
    {{"harmonic", ExcitationKind::harmonic}, {"pulse", ExcitationKind::pulse}}};
inline std::string excitation_kind_name(ExcitationKind kind) { return text_of(kExcitationKindWords, kind); }

struct ExcitationSection {
  std::string face;           ///< box face, or empty
  std::string group;          ///< mesh group, or empty
  std::optional<Vec3> point;  ///< nearest node, or empty
  int direction = 2;          ///< 0, 1, 2 for x, y, z
  double amplitude = 0.0;     ///< total force [N]
  ExcitationKind kind = ExcitationKind::harmonic;
  std::optional<double> frequency_hz;  ///< given in Hz
  int mode = 0;                      ///< > 0: frequency = ratio * f(mode) of `of`
  double ratio = 1.0;
  ModeOf of = ModeOf::uncracked;
  double ramp_periods = 3.0;
  double duration = 0.0;             ///< pulse [s]
};

/// `transient.damping`: either a ratio at a frequency (or mode) or alpha/beta directly.
/// `transient.damping.type` of a stated ratio: mass- or stiffness-proportional Rayleigh damping.
enum class DampingType { mass, stiffness };
inline constexpr Words<DampingType, 2> kDampingTypeWords{
    {{"mass", DampingType::mass}, {"stiffness", DampingType::stiffness}}};

struct DampingSection {
  std::optional<double> ratio;
  std::optional<double> at_hz;
  int at_mode = 0;
  DampingType type = DampingType::mass;
  double alpha = 0.0, beta = 0.0;
};

/// `transient.probes[].side`: which copy of a split crack node a probe records, the lower (the
/// plus face of MODEL.md eq. 9) or the upper (the minus face).
enum class FaceSide { lower, upper };
inline constexpr Words<FaceSide, 2> kFaceSideWords{{{"lower", FaceSide::lower}, {"upper", FaceSide::upper}}};

struct ProbeSection {
  std::string name;
  Vec3 point = Vec3::Zero();
  int component = -1;  ///< -1: the excitation direction
  bool crack_opening = false;  ///< the crack pair nearest `point` (gap, slip, state), not a node
  std::optional<FaceSide> side;  ///< which copy of a split crack node; empty: the nearest node
};

/// One entry of `transient.initial`.
struct InitialSection {
  Vec3 velocity = Vec3::Zero();
  Vec3 displacement = Vec3::Zero();
  std::array<std::optional<std::array<double, 2>>, 3> range;  ///< per axis [m]; none: everywhere
};

/// Which of `transient.release`'s keys is given: static (a static deflection) or mode (a mode shape).
enum class ReleaseKind { static_deflection, mode };
inline constexpr Words<ReleaseKind, 2> kReleaseKindWords{
    {{"static", ReleaseKind::static_deflection}, {"mode", ReleaseKind::mode}}};

/// `transient.release`: the run starts at rest from a static deflection or a mode shape.
struct ReleaseSection {
  ReleaseKind kind = ReleaseKind::static_deflection;
  std::string face;           ///< static: box face, or empty
  std::string group;          ///< static: mesh group, or empty
  std::optional<Vec3> point;  ///< static: nearest node, or empty
  int direction = 2;          ///< static: 0, 1, 2 for x, y, z
  double amplitude = 0.0;     ///< static: total force [N]; mode: largest nodal displacement [m]
  int mode = 0;               ///< mode: elastic mode number (1-based)
  mesh::Variant variant = mesh::Variant::uncracked;  ///< mode: of the uncracked or the open body
};

/// `transient:` (issue 4).
/// `transient.reduced:` (the reduced model, HYBRID.md sec. 2-3).
struct ReducedSection {
  int modes = 0;                 ///< 0: auto (every mode up to max_frequency)
  double max_frequency_hz = 0.0; ///< 0: auto
  int steps_per_period = 40;
  bool residual_flexibility = true;
};

/// transient.model: the full explicit model, the reduced model, or auto (the route chooses).
enum class TransientModel { full, reduced, automatic };
inline constexpr Words<TransientModel, 3> kTransientModelWords{
    {{"full", TransientModel::full}, {"reduced", TransientModel::reduced}, {"auto", TransientModel::automatic}}};
/// The scene's word for it: "full", "reduced", "auto".
inline std::string model_name(TransientModel model) { return text_of(kTransientModelWords, model); }

struct TransientSection {
  std::optional<ExcitationSection> excitation;
  DampingSection damping;
  std::optional<double> periods;   ///< run length in excitation periods
  std::optional<double> duration;  ///< run length [s]
  std::optional<double> time_step;  ///< [s]; empty: auto
  double safety_factor = defaults::kSafetyFactor;
  bool force_time_step = false;
  mesh::Variant variant = mesh::Variant::open;  ///< transient.variant (uncracked where the scene has no crack)
  TransientModel model = TransientModel::automatic;  ///< transient.model (pipeline/route.hpp chooses auto's)
  ReducedSection reduced;
  std::vector<ProbeSection> probes;
  std::vector<InitialSection> initial;
  std::optional<ReleaseSection> release;
  int snapshots = 0;
  /// Probe rows written to probes.csv per excitation period (per pulse duration for a pulse);
  /// 0: every step. The harmonic analysis takes every step regardless.
  int history_samples_per_period = 64;
  bool progress = true;
};

/// `spectrum:` (issue 5).
struct SpectrumSection {
  int harmonics = 5;
  bool subharmonics = true;
  double tolerance = 1e-3;
  int min_periods = 20;
  int window_periods = 10;
  Window window = Window::automatic;  ///< of the amplitude spectrum (core/choices.hpp)
  bool plots = true;
  std::optional<double> ringdown_start;  ///< [s]; empty: auto (0, or the end of a pulse)
  int ringdown_window_periods = 4;
};

/// One end of `sweep.frequency`: a value in Hz, or a ratio of a mode's frequency.
struct SweepFrequencySection {
  std::optional<double> hz;        ///< given in Hz
  int mode = 0;                    ///< > 0: ratio * f(mode) of `of`
  double ratio = 1.0;
  ModeOf of = ModeOf::uncracked;
};

/// `sweep:` (frequency sweeps by harmonic balance, HYBRID.md §4-5), run by `crackle sweep`.
/// `sweep.method`: harmonic_balance (continuation of periodic solutions) or stepped_sine (the
/// reduced transient to steady state at each frequency).
enum class SweepMethod { harmonic_balance, stepped_sine };
inline constexpr Words<SweepMethod, 2> kSweepMethodWords{
    {{"harmonic_balance", SweepMethod::harmonic_balance}, {"stepped_sine", SweepMethod::stepped_sine}}};
inline std::string method_name(SweepMethod method) { return text_of(kSweepMethodWords, method); }

struct SweepSection {
  SweepFrequencySection from, to;
  int harmonics = 15;              ///< H: orders 0..H of the base frequency
  int subharmonic = 1;             ///< nu: 1, or 2 for period-doubled branches
  SweepMethod method = SweepMethod::harmonic_balance;
  bool stability = true;           ///< Floquet multipliers at every point, Hill around changes (harmonic_balance)
  int points = 200;                ///< at least this many points (harmonic_balance), or frequencies each way (stepped_sine)
  double tolerance = 1e-6;         ///< stepped_sine: steady when no harmonic changes more than this x A1 over a period
  int max_periods = 2000;          ///< stepped_sine: periods per frequency at most
  LinearSolver solver = LinearSolver::automatic;  ///< harmonic_balance's linear solves (sweep.solver)
  bool plots = true;               ///< sweep_<probe>.png (gnuplot)
  std::vector<double> solve_at_hz; ///< harmonic_balance: frequencies where every branch is solved exactly [Hz]
};

/// `mesh.box.grading`: where (mode) and how (layers, ratio; auto resolved from the order) the box
/// mesh is graded towards the crack front. Which commands grade is decided in pipeline::build_model.
/// `mesh.box.grading.mode`: auto (modal and check graded, run uniform), always, none.
enum class GradingMode { automatic, always, none };
inline constexpr Words<GradingMode, 3> kGradingModeWords{
    {{"auto", GradingMode::automatic}, {"always", GradingMode::always}, {"none", GradingMode::none}}};
inline std::string grading_mode_name(GradingMode mode) { return text_of(kGradingModeWords, mode); }

struct GradingSection {
  GradingMode mode = GradingMode::automatic;
  mesh::Grading grading;
};

/// `accuracy:`: error estimates of the signatures and a tolerance to reach (DETECTION.md sec. 1).
/// `accuracy.estimate`: auto (where the route is automatic or a tolerance is asked), on, off.
enum class EstimateChoice { automatic, on, off };
inline constexpr Words<EstimateChoice, 3> kEstimateChoiceWords{
    {{"auto", EstimateChoice::automatic}, {"on", EstimateChoice::on}, {"off", EstimateChoice::off}}};

struct AccuracySection {
  EstimateChoice estimate = EstimateChoice::automatic;
  std::optional<double> tolerance;      ///< relative; empty: auto (0.01 with transient.model: auto)
  double budget_s = 600.0;              ///< wall time of all runs together [s]
  std::vector<std::string> quantities = {"A1", "A2/A1"};  ///< what the tolerance applies to
};

struct Scene {
  std::string file;  ///< path the scene was read from (or a name for in-memory scenes)
  mesh::BoxSpec box;  ///< box.grading stays none: build_model sets it per command from `grading`
  GradingSection grading;
  /// `mesh.gmsh` resolved against the scene file's folder; empty for a box mesh.
  std::string gmsh_file;
  MaterialSection material;
  /// `materials:` (regions with their own, possibly orthotropic, materials); empty: `material`.
  std::vector<MaterialEntrySection> materials;
  std::vector<BoundarySection> boundary;
  std::optional<mesh::CrackSpec> crack;
  /// `crack.reference`: the crack the box grid is made for, moved onto `crack` (mesh::morph_lines).
  std::optional<mesh::CrackSpec> crack_reference;
  std::optional<GroupCrackSection> crack_group;  ///< `crack: {group: ...}` of a Gmsh mesh
  bool has_crack() const { return crack || crack_group; }
  ContactSection contact;
  ModalSection modal;
  bool has_modal_section = false;
  std::optional<TransientSection> transient;
  std::optional<SpectrumSection> spectrum;
  std::optional<SweepSection> sweep;
  AccuracySection accuracy;
  bool has_accuracy_section = false;
  /// 1-based line of some keys (those the pipeline may have to name after loading: mesh size,
  /// run length, snapshots, probe and load points); absent or <= 0 when not from the file.
  std::map<std::string, int> key_lines;
  /// "file:line: key.path" (the line left out when unknown), the start of a message about a key.
  std::string where(const std::string& key_path) const;
};

/// `study.mode` (read by src/study): every combination of the values, or the i-th values together.
enum class StudyMode { grid, zip };
inline constexpr Words<StudyMode, 2> kStudyModeWords{{{"grid", StudyMode::grid}, {"zip", StudyMode::zip}}};

/// `identify.sigma` (read by src/identify): scaled (s^2 = chi^2/(n - k), Student's t) is true,
/// trusted (the stated sigmas, the normal quantile) false.
inline constexpr Words<bool, 2> kScaledSigmaWords{{{"scaled", true}, {"trusted", false}}};

/// Why the reduced model does not serve `crackle run` of this scene on `ranks` processes under
/// `transient.model: auto` (empty: it does; the route then takes it, HYBRID.md sec. 1): no harmonic
/// drive, no spectrum, no breathing crack, mpirun, an explicit time step, initial fields, a release.
std::string reduced_route_refusal(const Scene& scene, int ranks);

/// Whether `crackle run` (`command` "run") or `crackle sweep` ("sweep") of this scene on one process
/// takes the automatic route's own graded box mesh (pipeline/route.hpp) instead of the scene's cells.
bool takes_route_mesh(const Scene& scene, const std::string& command);

struct Param;

/// A parameter-study override: a YAML value for a dotted key path such as `crack.region.z`,
/// `modal.modes` or `boundary[0].value` (list entries by index). Applied before validation, so an
/// overridden value is checked like any other; messages about it name the path but no line.
struct Override {
  std::string path;
  std::string value;  ///< YAML text: "0.004", "[0.007, 0.01]", "lumped"
};

/// The text of a scene file. InputError naming the path and the reason (missing, unreadable, a
/// directory) when it cannot be read.
std::string read_scene_file(const std::string& path);

/// Loads and validates a scene file. Throws InputError (one line, see above) on any problem.
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {});

/// Same, from YAML text; `name` stands for the file name in messages.
Scene parse_scene(const std::string& text, const std::string& name, const std::vector<Override>& overrides = {});

/// The parameter table of a scene file: every key, declared once (schema.hpp). A new plain key is
/// its declaration bound to its struct field (`.to(&Section::field)`) plus the field; a key that
/// needs a check across keys or a conversion is also read in scene.cpp.
const Param& scene_parameters();
/// A table whose one child is the `study:` section (read by the study plan, src/study/plan.cpp,
/// not by load_scene): declared here so that docs/scene-format.md lists its keys and the plan
/// takes its keys and choices from it.
const Param& study_parameters();
/// The `identify:` section (read by src/identify, not by load_scene), declared for docs/scene-format.md.
const Param& identify_parameters();
/// The `plan:` section (read by src/planning, which takes its key lists from here), for docs/scene-format.md.
const Param& plan_parameters();

/// Markdown reference of every scene key, generated from the parameter table.
std::string scene_format_markdown();

}  // namespace crackle::scene
