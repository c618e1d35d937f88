#include "scene/scene.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "scene/schema.hpp"

namespace crackle::scene {
namespace {

const std::vector<std::string> kAxes = texts_of(kAxisWords);

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

/// `sweep.frequency.from` / `.to`: like transient.excitation.frequency.
Param sweep_end(const std::string& name, const std::string& doc) {
  return map_of(name, doc, {
      number("hz", "Frequency in Hz.").with_unit("Hz").above(0).to(&SweepFrequencySection::hz),
      integer("mode", "Elastic mode number (1 = lowest) the frequency refers to; needs a modal solve.").at_least(1)
          .to(&SweepFrequencySection::mode),
      number("ratio", "Multiple of the mode's frequency.").above(0).defaults_to("1").to(&SweepFrequencySection::ratio),
      choice("of", "Which frequency of the mode: bilinear (default with a crack), uncracked (default without) or "
                   "open.", kModeOfWords)
          .defaults_to("bilinear with a crack, else uncracked", [](const Values& values, const std::string&) {
            return std::string(values.has("crack") ? "bilinear" : "uncracked");
          }).to(&SweepFrequencySection::of),
  }).or_scalar_for("hz").exactly_one_of({"hz", "mode"}).required();
}

/// An optional map of position lists along x, y and z [m], at most `most` per axis, each bound to
/// its axis's entry of `field`.
template <class S>
Param axis_positions(const std::string& name, const std::string& doc, int most,
                     std::array<std::vector<double>, 3> S::*field) {
  return map_of(name, doc, {
    number("x", "Positions along x.").with_unit("m").list(1, most).to(field, kX),
    number("y", "Positions along y.").with_unit("m").list(1, most).to(field, kY),
    number("z", "Positions along z.").with_unit("m").list(1, most).to(field, kZ),
  }).optional_section();
}

/// A crack's rectangle: [low, high] along each in-plane axis [m], bound to `field`'s entry of the axis.
template <class S>
Param crack_extent(const std::string& name, const std::string& doc, std::array<std::array<double, 2>, 3> S::*field) {
  return map_of(name, doc, {
    number("x", "Extent along x.").with_unit("m").list(2).to(field, kX),
    number("y", "Extent along y.").with_unit("m").list(2).to(field, kY),
    number("z", "Extent along z.").with_unit("m").list(2).to(field, kZ),
  }).optional_section();
}

/// `crack.reference`'s keys, bound apart from mesh::CrackSpec so that reading the crack's own
/// section (which walks the whole `crack` map) never lands a reference value in the crack: the
/// fields start at the crack's own, and the keys given replace them.
struct CrackReferenceSection {
  double at = 0.0;
  std::array<std::array<double, 2>, 3> region{};
};

Param build_parameters() {
  const auto& faces = mesh::box_face_names();
  // clang-format off
  return map_of("", "A scene file.", {
    one_of("mesh", "How the body is meshed: exactly one of the keys below.", {
      map_of("box", "Structured mesh of the box [origin, origin + size].", {
        number("origin", "Corner of the box with the smallest coordinates.").with_unit("m").list(3)
            .defaults_to("[0, 0, 0]").to(&mesh::BoxSpec::origin),
        number("size", "Edge lengths along x, y, z.").with_unit("m").above(0).list(3).required()
            .to(&mesh::BoxSpec::size),
        integer("cells", "Elements per direction; grid lines are added where crack edges need them.")
            .at_least(1).list(3).required().to(&mesh::BoxSpec::cells),
        integer("order", "Element order p (Lagrange elements on GLL nodes).").at_least(1).at_most(4).required()
            .to(&mesh::BoxSpec::order),
        axis_positions("lines", "Extra grid lines along each axis, added to the uniform ones (a study puts the "
                                "crack edges of all its cases here so that they share one mesh); lines on or "
                                "outside the boundary and repeated lines are ignored.", 100000,
                       &mesh::BoxSpec::extra_lines),
        map_of("grading", "Grid lines graded geometrically towards the crack front (the crack-tip singularity "
                          "otherwise limits every order p to first-order convergence): on each side of the "
                          "front, lines at h ratio^k, k = 1..layers, h the distance to the next grid line. "
                          "Also given as a plain mode (`grading: none`).", {
          choice("mode", "auto: graded for crackle modal and crackle check, uniform for crackle run and "
                         "crackle sweep (the full explicit transient would pay the smallest cell in its stable "
                         "step; the reduced model and the sweep keep its mesh, so that switching "
                         "transient.model changes the cost, not the answer; the modal stage uses the same "
                         "mesh, so the excitation is that mesh's own resonance), graded for the forward sweeps of "
                         "crackle identify and crackle plan (their ratios on a uniform grid: docs/benchmarks.md "
                         "section 13.7); always: graded for every "
                         "command (with the reduced model the way to an accurate A2/A1, docs/benchmarks.md "
                         "section 5.1); none: no grading.", kGradingModeWords).defaults_to("auto")
              .to(&GradingSection::mode),
          integer("layers", "Geometric layers on each side of the front; auto: p - 1 + round(log2(D/h)) "
                              "in 1..4, h the uniform cell size across the front, D the body's thinnest side.").at_least(1)
              .at_most(8).or_word("auto").defaults_to("auto").to(&mesh::Grading::layers),
          number("ratio", "Ratio of successive layers; auto: 0.2.").above(0).below(1).or_word("auto")
              .defaults_to("auto").to(&mesh::Grading::ratio),
          axis_positions("fronts", "Further positions to grade towards along each axis, besides the crack's "
                                   "own front (a study puts the fronts of all its cases here, so that they "
                                   "share one mesh); positions on or outside the boundary are ignored.", 10000,
                         &mesh::Grading::fronts),
        }).or_scalar_for("mode"),
      }),
      text("gmsh", "Gmsh MSH 4.1 file (ASCII or binary), relative to the scene file's folder: 8- or 27-node "
                   "hexahedra or 4- or 10-node tetrahedra. Its physical groups name faces, cracks and "
                   "material regions."),
    }).required(),
    map_of("material", "Isotropic linear elastic material of the whole body (MODEL.md eq. 2); or give "
                       "materials.", {
      number("E", "Young's modulus.").with_unit("Pa").above(0).required().to(&MaterialSection::young),
      number("nu", "Poisson's ratio.").above(-1).below(0.5).required().to(&MaterialSection::poisson),
      number("rho", "Mass density.").with_unit("kg/m^3").above(0).required().to(&MaterialSection::density),
    }),
    list_of("materials", "Materials by region (layered composites), instead of material: each element takes the "
                         "one material whose region holds its centroid.", {
      text("name", "Name of the material, for messages and outputs.").required().to(&MaterialEntrySection::name),
      map_of("isotropic", "Isotropic elastic constants (give isotropic or orthotropic).", {
        number("E", "Young's modulus.").with_unit("Pa").above(0).required().to(&MaterialSection::young),
        number("nu", "Poisson's ratio.").above(-1).below(0.5).required().to(&MaterialSection::poisson),
      }),
      map_of("orthotropic", "Orthotropic elastic constants in the material axes 1, 2, 3 (axis 3 = z); "
                            "nu_ij is the contraction along j under stress along i.", {
        number("E1", "Young's modulus along axis 1.").with_unit("Pa").above(0).required().to(&OrthotropicSection::e1),
        number("E2", "Young's modulus along axis 2.").with_unit("Pa").above(0).required().to(&OrthotropicSection::e2),
        number("E3", "Young's modulus along axis 3.").with_unit("Pa").above(0).required().to(&OrthotropicSection::e3),
        number("G12", "Shear modulus in the 12 plane.").with_unit("Pa").above(0).required().to(&OrthotropicSection::g12),
        number("G13", "Shear modulus in the 13 plane.").with_unit("Pa").above(0).required().to(&OrthotropicSection::g13),
        number("G23", "Shear modulus in the 23 plane.").with_unit("Pa").above(0).required().to(&OrthotropicSection::g23),
        number("nu12", "Poisson's ratio nu12.").required().to(&OrthotropicSection::nu12),
        number("nu13", "Poisson's ratio nu13.").required().to(&OrthotropicSection::nu13),
        number("nu23", "Poisson's ratio nu23.").required().to(&OrthotropicSection::nu23),
      }),
      number("rho", "Mass density.").with_unit("kg/m^3").above(0).required().to(&MaterialEntrySection::density),
      number("angle", "Ply angle: material axis 1 turned about z from x towards y.").with_unit("deg")
          .defaults_to("0").to(&MaterialEntrySection::angle),
      map_of("region", "Where the material is: coordinate ranges (box meshes get grid lines at their ends) "
                       "and/or a physical volume group of a Gmsh mesh; none: everywhere.", {
        number("x", "Range of the element centroids along x.").with_unit("m").list(2).increasing()
            .to(&RegionSection::range, kX),
        number("y", "Range of the element centroids along y.").with_unit("m").list(2).increasing()
            .to(&RegionSection::range, kY),
        number("z", "Range of the element centroids along z (a ply).").with_unit("m").list(2).increasing()
            .to(&RegionSection::range, kZ),
        text("group", "Physical volume group of a Gmsh mesh.").to(&RegionSection::group),
      }).optional_section(),
    }),
    list_of("boundary", "Prescribed displacements on box faces or mesh groups; none: a free body.", {
      choice("face", "Face of the box (give face or group).", {faces.begin(), faces.end()}).to(&BoundarySection::face),
      text("group", "Physical group of a Gmsh mesh (any named node set of the mesh).").to(&BoundarySection::group),
      choice("fix", "Displacement components fixed on every node of the face.", kAxisWords).list(1, 3).distinct()
          .required().to(&BoundarySection::components),
      number("value", "Prescribed displacement of each fixed component.").with_unit("m").list(1, 3)
          .same_length_as("fix").defaults_to("zeros", zeros_per_fix).to(&BoundarySection::values),
    }).defaults_to("[]"),
    map_of("crack", "An axis-aligned rectangular crack on a grid plane of a box mesh (plane and region), or a "
                    "physical surface group of a Gmsh mesh (group); none: no crack.", {
      map_of("plane", "The plane of the crack.", {
        choice("normal", "Axis normal to the crack.", kAxisWords).required().to(&mesh::CrackSpec::normal),
        number("at", "Position of the plane along the normal; must be a grid plane origin + k size/cells "
                     "strictly inside the body.").with_unit("m").required().to(&mesh::CrackSpec::at),
      }),
      crack_extent("region", "Rectangle on the plane: [low, high] along each of the two in-plane axes, which "
                             "are exactly its keys.", &mesh::CrackSpec::region),
      map_of("reference", "The crack the box grid is made for, when it differs from the crack itself: the grid lines "
                          "(crack edges, grading) are placed for this crack, then moved piecewise linearly along each "
                          "axis so that they land on the crack's own plane and edges. The topology then does not "
                          "depend on where the crack is, and results change smoothly with its position and size "
                          "(`crackle identify` sets it to the middle of its bounds). The crack's own plane may then "
                          "lie anywhere inside the body.", {
        number("at", "Plane position of the reference crack; default: the crack's own (must be a grid plane).")
            .with_unit("m").to(&CrackReferenceSection::at),
        crack_extent("region", "Extent of the reference crack; each axis defaults to the crack's own.",
                     &CrackReferenceSection::region),
      }).optional_section(),
      text("group", "Physical surface group of a Gmsh mesh: its nodes are split except on the crack front."),
      number("gap", "Initial normal gap g0 (MODEL.md eq. 9): > 0 open, < 0 pre-compressed.").with_unit("m")
          .defaults_to("0").to(&mesh::CrackSpec::gap),
      map_of("contact", "Penalty contact between the crack faces in transient runs (MODEL.md eq. 25d, 15).", {
        choice("model", "penalty: the crack faces touch (penalty springs, a breathing crack); none: no contact, "
                        "the faces pass through each other (the open body, a linear run at the open "
                        "frequencies).", kContactModelWords).defaults_to("penalty").to(&ContactSection::model),
        number("penalty", "Normal penalty eps_N (force per unit area per unit penetration); auto: from E and "
                          "the element size normal to the crack.").with_unit("Pa/m").above(0).or_word("auto")
            .defaults_to("auto").to(&ContactSection::penalty),
        number("friction", "Coulomb friction coefficient mu (tangential penalty with a return mapping).")
            .at_least(0).defaults_to("0").to(&ContactSection::friction),
        choice("integration", "implicit: the penalty law at U(i+1), solved per pair in closed form, so the "
                              "springs do not limit the time step (auto penalty " +
                                  format_number(defaults::kImplicitPenaltyFactor) + " E/h); explicit: the force "
                              "at U(i) as in MODEL.md eq. 27, the springs enter omega_max at 4 times their own "
                              "frequency so that contact events are resolved (stable at any penalty; steps grow as "
                              "sqrt(penalty); auto penalty " +
                                  format_number(defaults::kExplicitPenaltyFactor) + " E/h).", kContactIntegrationWords).defaults_to("implicit")
            .to(&ContactSection::integration),
      }),
    }).optional_section(),
    map_of("modal", "Modal analysis of the linear limits of the cracked body; optional.", {
      integer("modes", "Number of lowest modes per variant.").at_least(1).defaults_to(std::to_string(defaults::kModes))
          .to(&ModalSection::modes),
      choice("variants", "Linear limits to analyse: faces tied (uncracked) or free (open); open needs a crack.",
             mesh::kVariantWords).list(1, 2).distinct()
          .defaults_to("[uncracked, open] with a crack, else [uncracked]", default_variants)
          .to(&ModalSection::variants),
      choice("solver", "Eigen-solver: slepc (Krylov-Schur; the one that runs under MPI), arpack (Lanczos with "
                       "CHOLMOD; the fastest on one process, docs/benchmarks.md section 3) or auto (arpack on one "
                       "process; slepc under mpirun or given SLEPc options such as -eps_tol).",
             kModalSolverWords).defaults_to("auto").to(&ModalSection::solver),
      choice("mass", "Mass matrix.", kMassMatrixWords).defaults_to("consistent").to(&ModalSection::mass),
    }),
    map_of("transient", "Explicit dynamics (MODEL.md eqs. 24-28) run by `crackle run`; optional.", {
      map_of("excitation", "Force on a face, mesh group or the node nearest a point (give one of them).", {
        choice("face", "Loaded face of the box (uniform traction of the given total).", {faces.begin(), faces.end()})
            .to(&ExcitationSection::face),
        text("group", "Loaded node set of a Gmsh mesh.").to(&ExcitationSection::group),
        number("point", "Loaded point: the force acts on the nearest node.").with_unit("m").list(3)
            .to(&ExcitationSection::point),
        choice("direction", "Direction of the force.", kAxisWords).defaults_to("z").to(&ExcitationSection::direction),
        number("amplitude", "Total force amplitude (the peak force of a pulse).").with_unit("N").above(0).required()
            .to(&ExcitationSection::amplitude),
        choice("kind", "harmonic: sin(2 pi f t) ramped in; pulse: an impact-hammer blow, one half-sine of the "
                       "given duration and peak `amplitude` from t = 0 (its spectrum falls to a third of its "
                       "static value at 1/duration; the spectrum stage writes the FRF H = X/F up to there).",
               kExcitationKindWords).defaults_to("harmonic").to(&ExcitationSection::kind),
        map_of("frequency", "Excitation frequency: a value in Hz, or relative to a mode.", {
          number("hz", "Frequency in Hz.").with_unit("Hz").above(0).to(&ExcitationSection::frequency_hz),
          integer("mode", "Elastic mode number (1 = lowest) the frequency refers to; needs a modal solve.")
              .at_least(1).to(&ExcitationSection::mode),
          number("ratio", "Multiple of the mode's frequency.").above(0).defaults_to("1").to(&ExcitationSection::ratio),
          choice("of", "Which frequency of the mode: bilinear (default with a crack), uncracked (default "
                       "without) or open.", kModeOfWords)
              .defaults_to("bilinear with a crack, else uncracked", [](const Values& values, const std::string&) {
                return std::string(values.has("crack") ? "bilinear" : "uncracked");
              }).to(&ExcitationSection::of),
        }).or_scalar_for("hz").exactly_one_of({"hz", "mode"}).optional_section(),
        number("ramp_periods", "Harmonic excitation: periods of the smooth ramp-in.").at_least(0).defaults_to("3")
            .to(&ExcitationSection::ramp_periods),
        number("duration", "Pulse: duration of the half-sine.").with_unit("s").above(0).to(&ExcitationSection::duration),
      }).exactly_one_of({"face", "group", "point"}).optional_section(),
      map_of("damping", "Rayleigh damping C = alpha M + beta K: a ratio at a frequency, or alpha and beta.", {
        number("ratio", "Damping ratio xi at the frequency `at`.").at_least(0).below(1).to(&DampingSection::ratio),
        map_of("at", "Frequency of the damping ratio: a value in Hz or a mode.", {
          number("hz", "Frequency in Hz.").with_unit("Hz").above(0).to(&DampingSection::at_hz),
          integer("mode", "Elastic mode number (uncracked variant).").at_least(1).to(&DampingSection::at_mode),
        }).or_scalar_for("hz").exactly_one_of({"hz", "mode"}).optional_section(),
        choice("type", "mass: alpha = 2 xi omega (free per step, no time-step penalty); stiffness: "
                       "beta = 2 xi / omega (shrinks the stable step).", kDampingTypeWords).defaults_to("mass")
            .to(&DampingSection::type),
        number("alpha", "Mass-proportional coefficient.").with_unit("1/s").at_least(0).to(&DampingSection::alpha),
        number("beta", "Stiffness-proportional coefficient.").with_unit("s").at_least(0).to(&DampingSection::beta),
      }).optional_section(),
      number("periods", "Length of the run in excitation periods (the limit when steady-state detection "
                        "is on).").above(0).to(&TransientSection::periods),
      number("duration", "Length of the run.").with_unit("s").above(0).to(&TransientSection::duration),
      number("time_step", "Time step; auto: safety_factor x the critical step (adjusted down so that an "
                          "excitation period is a whole number of steps).").with_unit("s").above(0)
          .or_word("auto").defaults_to("auto").to(&TransientSection::time_step),
      number("safety_factor", "Fraction of the critical time step used by time_step: auto.").above(0).at_most(1)
          .defaults_to(format_number(defaults::kSafetyFactor)).to(&TransientSection::safety_factor),
      boolean("force_time_step", "Run a time step above the critical one anyway (the health checks stop a "
                                 "diverging run).").defaults_to("false").to(&TransientSection::force_time_step),
      choice("variant", "Run the body with its crack (open faces with contact) or with the faces tied.",
             mesh::kVariantWords).defaults_to("open").to(&TransientSection::variant),
      choice("model", "full: the explicit finite-element model (MODEL.md eqs. 24-28); reduced: modes of the "
                      "variant + residual flexibility at the crack pairs (HYBRID.md sec. 2-3), implicit steps set "
                      "by accuracy (rigid-body modes of a free body or piece are kept as modes of frequency 0); "
                      "auto: the reduced model on its own graded mesh of a box for a harmonic-drive signature run "
                      "(a crack, a spectrum: section, one process, no transient.time_step, no initial fields or "
                      "release), raising the element order until accuracy.tolerance is met, else the full model; "
                      "run.json route says which and why.", kTransientModelWords)
          .defaults_to("auto").to(&TransientSection::model),
      map_of("reduced", "The reduced model (transient.model: reduced).", {
        integer("modes", "Modes kept; auto: every mode of the variant up to max_frequency.").at_least(1)
            .or_word("auto").defaults_to("auto").to(&ReducedSection::modes),
        number("max_frequency", "Highest frequency resolved: modes up to it (modes: auto) and the time step; "
                                "auto: 4 x spectrum.harmonics (5 without spectrum:) x the excitation frequency.")
            .with_unit("Hz").above(0).or_word("auto").defaults_to("auto").to(&ReducedSection::max_frequency_hz),
        integer("steps_per_period", "Time steps per period of the highest retained mode or of max_frequency, "
                                    "whichever is higher (average-acceleration Newmark: frequency error "
                                    "(2 pi / n)^2 / 12).").at_least(4).defaults_to("40").to(&ReducedSection::steps_per_period),
        boolean("residual_flexibility", "Keep the static correction of the truncated modes (HYBRID.md sec. 2); "
                                        "false only to measure what it brings.").defaults_to("true")
            .to(&ReducedSection::residual_flexibility),
      }),
      list_of("probes", "Points whose displacement, velocity and acceleration are recorded (nearest node).", {
        text("name", "Name of the probe: letters, digits, _ . - (column prefix, file names, spectrum.json key).")
            .required().to(&ProbeSection::name),
        number("point", "Position: the displacement of the nearest node (give point or crack_opening).")
            .with_unit("m").list(3).to(&ProbeSection::point),
        choice("side", "For a point on a crack face: which copy of the split node to record, lower (coordinate "
                       "below the crack plane: the plus face of MODEL.md eq. 9, the default nearest node) or "
                       "upper (the minus face).", kFaceSideWords).to(&ProbeSection::side),
        number("crack_opening", "Position: the crack pair nearest it (give point or crack_opening); records "
                                "the normal gap g_N = g0 + (u- - u+) . n+ (eq. 9), the tangential slip along "
                                "two tangents (eq. 10), their rates, and the contact state (0 open, 1 stick, 2 "
                                "slip) as probes.csv columns; the spectrum analyses the gap.").with_unit("m").list(3)
            .to(&ProbeSection::point),
        choice("component", "Component of the displacement analysed by the spectrum (default: the excitation "
                            "direction); its unit is that of the harmonic amplitudes. Not with crack_opening "
                            "(its gap is analysed).", kAxisWords).with_unit("m").to(&ProbeSection::component),
      }).exactly_one_of({"point", "crack_opening"}).defaults_to("[]"),
      map_of("release", "Free vibration: the run starts at rest from a deflected state (MODEL.md eq. 6), given "
                        "by exactly one of static and mode; added to `initial`.", {
        map_of("static", "The static deflection under a load, with the crack's contact active (the nonlinear "
                         "static problem: a crack pressed shut or pulled open starts from its true state); the "
                         "load is removed at t = 0.", {
          choice("face", "Loaded face of the box (uniform traction of the given total).", {faces.begin(), faces.end()})
              .to(&ReleaseSection::face),
          text("group", "Loaded node set of a Gmsh mesh.").to(&ReleaseSection::group),
          number("point", "Loaded point: the force acts on the nearest node.").with_unit("m").list(3)
              .to(&ReleaseSection::point),
          choice("direction", "Direction of the force.", kAxisWords).defaults_to("z").to(&ReleaseSection::direction),
          number("amplitude", "Total static force.").with_unit("N").above(0).required().to(&ReleaseSection::amplitude),
        }).exactly_one_of({"face", "group", "point"}).optional_section(),
        map_of("mode", "A mode shape of one linear limit (the modal stage runs for that variant).", {
          integer("number", "Elastic mode number (1 = lowest).").at_least(1).required().to(&ReleaseSection::mode),
          choice("variant", "Which linear limit's mode: faces tied (uncracked) or free (open).",
                 mesh::kVariantWords).defaults_to("uncracked").to(&ReleaseSection::variant),
          number("amplitude", "Largest nodal displacement of the scaled mode shape.").with_unit("m").above(0)
              .required().to(&ReleaseSection::amplitude),
        }).optional_section(),
      }).exactly_one_of({"static", "mode"}).optional_section(),
      list_of("initial", "Initial velocity and displacement (MODEL.md eq. 6), uniform over the nodes in a "
                         "coordinate range (all nodes when no range is given). With transient.model: reduced the fields "
                         "(and a release) are projected on the retained modes (transient.json initial_state: the "
                         "share left out).", {
        number("velocity", "Initial velocity.").with_unit("m/s").list(3).defaults_to("[0, 0, 0]")
            .to(&InitialSection::velocity),
        number("displacement", "Initial displacement.").with_unit("m").list(3).defaults_to("[0, 0, 0]")
            .to(&InitialSection::displacement),
        number("x", "Range along x.").with_unit("m").list(2).increasing().to(&InitialSection::range, kX),
        number("y", "Range along y.").with_unit("m").list(2).increasing().to(&InitialSection::range, kY),
        number("z", "Range along z.").with_unit("m").list(2).increasing().to(&InitialSection::range, kZ),
      }).defaults_to("[]"),
      map_of("snapshots", "Displacement fields written as VTU files. With transient.model: reduced the field is "
                          "u = Phi q + the static correction G_res (B^T p + f a) (HYBRID.md sec. 2), recovered only "
                          "at the snapshots (one factor of K, made at the first).", {
        integer("count", "Number of snapshots spread evenly over the run (0: none), at most one per step; "
                         "snapshots.pvd lists them with their times (a time series in ParaView).")
            .at_least(0).defaults_to("0").to(&TransientSection::snapshots),
      }),
      map_of("history", "Probe histories written to probes.csv; the harmonic analysis and the spectra take "
                        "every step regardless.", {
        integer("samples_per_period", "Rows of probes.csv per excitation period (per pulse duration for a "
                                      "pulse; without an excitation every step is written); all: every step.")
            .at_least(2).or_word("all", 0).defaults_to("64").to(&TransientSection::history_samples_per_period),
      }),
      boolean("progress", "Progress line with ETA on the terminal.").defaults_to("true").to(&TransientSection::progress),
    }).exactly_one_of({"periods", "duration"}).optional_section(),
    map_of("spectrum", "Harmonics of the probe responses and damage indices (needs transient).", {
      integer("harmonics", "Highest harmonic order analysed (orders 1..harmonics of the excitation).")
          .at_least(1).at_most(50).defaults_to("5").to(&SpectrumSection::harmonics),
      boolean("subharmonics", "Also orders 1/2, 3/2, 5/2, ...").defaults_to("true").to(&SpectrumSection::subharmonics),
      map_of("steady_state", "Stop when the harmonic table has settled.", {
        number("tolerance", "Largest change of any harmonic (relative to A1) between the last two windows; "
                            "0: never stop early.").at_least(0).defaults_to("1e-3").to(&SpectrumSection::tolerance),
        integer("min_periods", "Periods run before the check starts.").at_least(1).defaults_to("20")
            .to(&SpectrumSection::min_periods),
        integer("window_periods", "Periods per analysis window (made even for sub-harmonics).").at_least(1)
            .defaults_to("10").to(&SpectrumSection::window_periods),
      }),
      map_of("ringdown", "Ring-down analysis, run instead of the harmonic table when the excitation is not "
                         "harmonic (free vibration, a pulse, or none): dominant frequency, damping ratio and "
                         "orders of it.", {
        number("start", "Analysis start time; auto: 0, or the end of a pulse.").with_unit("s").at_least(0)
            .or_word("auto").defaults_to("auto").to(&SpectrumSection::ringdown_start),
        integer("window_periods", "Periods of the dominant frequency per envelope window (made even for "
                                  "sub-harmonics).").at_least(1).defaults_to("4").to(&SpectrumSection::ringdown_window_periods),
      }),
      choice("window", "Window of the amplitude spectra (spectrum_<probe>.csv and their plots, over the analysed "
                       "periods): auto: rectangular when a period is a whole number of time steps (every "
                       "harmonic on a bin, no leakage), else flat-top (peaks within ~0.1 % between bins); "
                       "rectangular, hann, flattop: as named (spectrum.json amplitude_spectrum.window says "
                       "which). The harmonic amplitudes (A1, the ratios, spectrum.json's tables) are always "
                       "taken over whole periods without a window.", kWindowWords).defaults_to("auto")
          .to(&SpectrumSection::window),
      boolean("plots", "PNG plots of each probe's history and spectrum (gnuplot; skipped with a note when "
                       "absent).").defaults_to("true").to(&SpectrumSection::plots),
    }).optional_section(),
    map_of("accuracy", "Error estimates of the signatures (DETECTION.md sec. 1) and a tolerance to reach: each "
                       "numerical error estimated by one refinement at a time from the setting that was run (mesh: "
                       "three element orders on the same graded grid, Richardson with the observed rate; modes: "
                       "twice the retained band, four times where that change is above a tenth of the tolerance (three "
                       "levels, the observed order); time step: twice the steps; penalty: four times it; the "
                       "steady-state window change), reported in spectrum.json accuracy and on the terminal. crackle sweep "
                       "estimates each probe's peaks, the fold and period-doubling frequencies and the bilinear "
                       "frequency (mesh: the two lower orders; modes: twice the band; harmonics: H + 2) in sweep.json "
                       "accuracy. crackle modal estimates every frequency of modal.json (mesh: the lower element orders from 2 on a "
                       "box, at order 4 checked by order 2 on the cells doubled) in modal.json accuracy.", {
      choice("estimate", "auto: crackle run: on for the reduced model (its refinements cost a fraction of the run), "
                         "off for the full model (they would cost more than the run); crackle sweep: on with "
                         "transient.model: auto (the route's own mesh), off for a mesh swept as written; crackle "
                         "modal: on at element order 3 or more on a box (the lower orders cost about a quarter of "
                         "the solve), off below; on (crackle modal below order 3: the orders above, up to 4); off.",
             kEstimateChoiceWords)
          .defaults_to("auto").to(&AccuracySection::estimate),
      number("tolerance", "Relative error to reach on accuracy.quantities at every probe: the run refines the "
                          "component with the largest error per unit cost until the estimate (the "
                          "components combined with their signs and margins) is below it or accuracy.budget is spent (the mesh: one order up, at order 4 "
                          "one more front layer, up to 3; the window: the steady-state tolerance / 10 and "
                          "transient.periods x 4, twice at most); auto: 0.01 with transient.model: auto, else none "
                          "(the estimate only).").above(0).below(1).or_word("auto").defaults_to("auto")
          .to(&AccuracySection::tolerance),
      number("budget", "Wall time the tolerance may spend, all runs together.").with_unit("s").above(0)
          .defaults_to("600").to(&AccuracySection::budget_s),
      choice("quantities", "Signatures the tolerance applies to (every signature gets its estimate).",
             {"A1", "A2/A1", "A3/A1", "A1/2/A1", "f_b"}).list(1, 5).distinct().defaults_to("[A1, A2/A1]")
          .to(&AccuracySection::quantities),
    }).optional_section(),
    map_of("sweep", "Frequency sweep run by `crackle sweep` (HYBRID.md sections 4-5): the periodic response of the "
                    "reduced model to transient.excitation (its load shape and amplitude; its frequency is swept) "
                    "at transient.probes, with transient.damping and crack.contact.", {
      map_of("frequency", "The range of excitation frequencies swept.", {
        sweep_end("from", "Start of the range: a value in Hz, or relative to a mode."),
        sweep_end("to", "End of the range: a value in Hz, or relative to a mode."),
      }).required(),
      integer("harmonics", "H: harmonic orders 0..H of the base frequency (excitation / subharmonic).")
          .at_least(1).at_most(200).defaults_to("15").to(&SweepSection::harmonics),
      integer("subharmonic", "1, or 2 for period-doubled branches (base frequency = excitation / 2): the "
                             "period-one branch, then the period-two branch from its first period doubling "
                             "(harmonic_balance needs stability for it).")
          .at_least(1).at_most(2).defaults_to("1").to(&SweepSection::subharmonic),
      choice("method", "harmonic_balance: pseudo-arclength continuation of the periodic solutions (through "
                       "folds); stepped_sine: the reduced transient run to steady state at each frequency, up "
                       "then down, as a lab does.", kSweepMethodWords)
          .defaults_to("harmonic_balance").to(&SweepSection::method),
      boolean("stability", "Floquet multipliers at every point (monodromy matrix), Hill's method around each "
                           "stability change (harmonic_balance; frictionless contact only).")
          .defaults_to("true without friction, else false", [](const Values& values, const std::string&) {
            const bool friction = values.has("crack.contact.friction") && values.number("crack.contact.friction") > 0;
            return std::string(friction ? "false" : "true");
          }).to(&SweepSection::stability),
      integer("points", "harmonic_balance: at least this many points (the continuation step is at most the range "
                        "/ points); stepped_sine: this many frequencies each way.").at_least(2).at_most(100000)
          .defaults_to("200").to(&SweepSection::points),
      number("tolerance", "stepped_sine: steady when no harmonic changes by more than this times A1 from one "
                          "period to the next.").above(0).defaults_to("1e-6").to(&SweepSection::tolerance),
      integer("max_periods", "stepped_sine: periods run at most per frequency (a warning names the frequencies "
                             "that did not settle).").at_least(2).defaults_to("2000").to(&SweepSection::max_periods),
      choice("solver", "harmonic_balance's linear solves: dense (the Jacobian of pairs x (2H+1) unknowns "
                       "formed and LU-factorised, cost ~ unknowns^3), krylov (matrix-free GMRES preconditioned "
                       "by the mean contact stiffness and each breathing pair's harmonic block, no square "
                       "matrix), auto (dense up to 1500 unknowns).",
             kLinearSolverWords).defaults_to("auto").to(&SweepSection::solver),
      boolean("plots", "sweep_<probe>.png: each probe's amplitudes against frequency (gnuplot; skipped with a "
                       "note when absent).").defaults_to("true").to(&SweepSection::plots),
      number("solve_at", "harmonic_balance: frequencies where every branch is also solved exactly (Newton at "
                         "that frequency from the two points around it): rows of sweep.csv there, to read a "
                         "response at a measured drive frequency instead of between two points.")
          .with_unit("Hz").above(0).list(1, 100).to(&SweepSection::solve_at_hz),
    }).optional_section(),
  });
  // clang-format on
}

/// Two faces share nodes when they are the same face or meet at a box edge.
bool faces_touch(const std::string& a, const std::string& b) { return a == b || a[0] != b[0]; }

/// The same component of a shared node must not be fixed to two different values.
void check_boundary(const Values& values, const std::vector<BoundarySection>& boundary) {
  for (std::size_t j = 0; j < boundary.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      // Groups of a mesh file are checked once meshed (fem::make_constraints).
      if (boundary[i].face.empty() || boundary[j].face.empty()) continue;
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

/// The table's declaration of the map (or list of maps) at a dotted key path (`transient.reduced`).
const Param& declared(const std::string& path) {
  const Param* param = &scene_parameters();
  for (std::size_t start = 0; start <= path.size();) {
    const std::size_t dot = std::min(path.find('.', start), path.size());
    param = param->child(path.substr(start, dot - start));
    if (!param) throw std::logic_error("no declared map " + path);
    start = dot + 1;
  }
  return *param;
}

/// Fills the fields of `section` that the table binds below `path`, a dotted path of maps
/// (`transient.reduced`): each key with `.to(&Section::field)` is read here, nowhere else.
template <class S>
void read_section(const Values& values, const std::string& path, S& section) {
  read_bound(declared(path), values, path, section);
}

/// Fills the fields of `section` bound in entry `index` of the list of maps at `path`
/// (`transient.probes`).
template <class S>
void read_entry(const Values& values, const std::string& path, int index, S& section) {
  read_bound(declared(path), values, path + "[" + std::to_string(index) + "]", section);
}

mesh::CrackSpec crack_from(const Values& values, const mesh::BoxSpec& box) {
  // plane.normal, plane.at, region and gap (crack.reference's keys are bound to
  // CrackReferenceSection, read by reference_crack_from).
  mesh::CrackSpec crack;
  read_section(values, "crack", crack);

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
  const bool has_reference = values.has("crack.reference");
  const std::string problem = mesh::check_crack(box, crack, !has_reference);
  if (!problem.empty()) values.fail("crack." + problem.substr(0, problem.find(':')), "crack." + problem);
  return crack;
}

/// `crack.reference`: the crack the grid is made for (its keys default to the crack's own).
std::optional<mesh::CrackSpec> reference_crack_from(const Values& values, const mesh::BoxSpec& box,
                                                    const mesh::CrackSpec& crack) {
  if (!values.has("crack.reference")) return std::nullopt;
  const std::string along_normal = "crack.reference.region." + kAxes[crack.normal];
  if (values.has(along_normal)) {
    values.fail(along_normal, "the in-plane axes of the crack's region", kAxes[crack.normal] + " (the crack's normal)");
  }
  CrackReferenceSection section{crack.at, crack.region};
  read_section(values, "crack.reference", section);
  mesh::CrackSpec reference = crack;
  reference.at = section.at;
  reference.region = section.region;
  const std::string problem = mesh::check_crack(box, reference);
  if (!problem.empty()) values.fail("crack.reference." + problem.substr(0, problem.find(':')), "crack.reference." + problem);
  return reference;
}

/// A mesh file named in a scene, relative to the scene file's folder unless absolute.
std::string mesh_file_path(const std::string& scene_file, const std::string& mesh_file) {
  const std::filesystem::path path(mesh_file);
  if (path.is_absolute()) return mesh_file;
  return (std::filesystem::path(scene_file).parent_path() / path).string();
}

std::vector<MaterialEntrySection> materials_from(const Values& values, bool gmsh_mesh) {
  std::vector<MaterialEntrySection> materials;
  for (int i = 0; i < values.count("materials"); ++i) {
    const std::string entry = "materials[" + std::to_string(i) + "]";
    MaterialEntrySection material;
    read_entry(values, "materials", i, material);
    material.line = std::max(values.line(entry), 0);
    if (values.has(entry + ".isotropic") == values.has(entry + ".orthotropic")) {
      values.fail(entry, "isotropic or orthotropic constants",
                  values.has(entry + ".isotropic") ? "both" : "neither");
    }
    const Param& declared_entry = declared("materials");
    if (values.has(entry + ".isotropic")) {
      MaterialSection isotropic;
      read_bound(*declared_entry.child("isotropic"), values, entry + ".isotropic", isotropic);
      isotropic.density = material.density;
      material.isotropic = isotropic;
    } else {
      OrthotropicSection orthotropic;
      read_bound(*declared_entry.child("orthotropic"), values, entry + ".orthotropic", orthotropic);
      material.orthotropic = orthotropic;
    }
    if (values.has(entry + ".region")) {
      read_bound(*declared_entry.child("region"), values, entry + ".region", material.region);
    }
    if (values.has(entry + ".region.group")) {
      if (!gmsh_mesh) {
        values.fail(entry + ".region.group", "coordinate ranges x, y, z (a box mesh has no groups)",
                    "'" + material.region.group + "'");
      }
    }
    materials.push_back(material);
  }
  return materials;
}

/// The given keys among `keys` below `parent`, e.g. "face and point".
std::vector<std::string> given_keys(const Values& values, const std::string& parent,
                                    const std::vector<std::string>& keys) {
  std::vector<std::string> given;
  for (const std::string& key : keys) {
    if (values.has(parent + "." + key)) given.push_back(key);
  }
  return given;
}

std::string and_list(const std::vector<std::string>& words) {
  if (words.empty()) return "none";
  std::string text = words[0];
  for (std::size_t i = 1; i < words.size(); ++i) text += (i + 1 == words.size() ? " and " : ", ") + words[i];
  return text;
}

/// A name that becomes part of file names and CSV headers (probes): letters, digits, _ . - only.
void check_file_safe_name(const Values& values, const std::string& path, const std::string& name) {
  const bool safe = std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '.' || c == '-';
  });
  if (safe && name != "." && name != "..") return;
  std::string shown;  // the name as a message can show it on one line
  for (const char c : name) {
    if (c == '\n')
      shown += "\\n";
    else if (c == '\r')
      shown += "\\r";
    else if (c == '\t')
      shown += "\\t";
    else
      shown += c;
  }
  values.fail(path, "a name of letters, digits, _ . - (it names output files and CSV columns)",
              "'" + shown + "'");
}

/// `transient.excitation`: a frequency for a harmonic drive, a duration for a pulse, nothing else.
ExcitationSection excitation_from(const Values& values, const Scene& scene) {
  ExcitationSection excitation;
  read_section(values, "transient.excitation", excitation);
  const bool harmonic = excitation.kind == ExcitationKind::harmonic;
  const bool has_frequency = values.has("transient.excitation.frequency");
  if (harmonic && !has_frequency) {
    values.fail("transient.excitation.frequency", "a frequency (in Hz, or {mode: n, ratio: r}) for a harmonic "
                "excitation", "nothing");
  }
  if (!harmonic && has_frequency) {
    values.fail("transient.excitation.frequency", "no frequency with kind: pulse (duration sets its band)",
                "a frequency");
  }
  if (harmonic && excitation.of != ModeOf::uncracked && !scene.has_crack()) {
    values.fail("transient.excitation.frequency.of", "uncracked (the scene has no crack)", mode_of_name(excitation.of));
  }
  if (harmonic && values.has("transient.excitation.duration")) {
    values.fail("transient.excitation.duration", "no duration with kind: harmonic (the run's length is "
                "transient.periods or transient.duration)", format_number(excitation.duration));
  }
  if (!harmonic && !values.has("transient.excitation.duration")) {
    values.fail("transient.excitation.duration", "the duration of the pulse", "nothing");
  }
  return excitation;
}

/// `transient.damping`: a ratio at a frequency, or alpha and/or beta.
DampingSection damping_from(const Values& values) {
  const std::vector<std::string> coefficients = given_keys(values, "transient.damping", {"alpha", "beta"});
  if (values.has("transient.damping.ratio") == !coefficients.empty()) {
    values.fail("transient.damping", "either ratio (with at) or alpha and/or beta",
                values.has("transient.damping.ratio") ? "ratio and " + and_list(coefficients) : "none");
  }
  if (values.has("transient.damping.ratio") && !values.has("transient.damping.at")) {
    values.fail("transient.damping.at", "the frequency of the damping ratio (in Hz or {mode: n})", "nothing");
  }
  if (!values.has("transient.damping.ratio") && values.has("transient.damping.at")) {
    values.fail("transient.damping.at", "no frequency without a damping ratio (alpha and beta are given as they are)",
                "a frequency");
  }
  DampingSection damping;
  read_section(values, "transient.damping", damping);
  return damping;
}

/// `transient.probes`: file-safe distinct names; a crack opening needs a crack and takes no component or side.
std::vector<ProbeSection> probes_from(const Values& values, const Scene& scene) {
  std::vector<ProbeSection> probes;
  for (int i = 0; i < values.count("transient.probes"); ++i) {
    const std::string entry = "transient.probes[" + std::to_string(i) + "]";
    ProbeSection probe;
    read_entry(values, "transient.probes", i, probe);
    check_file_safe_name(values, entry + ".name", probe.name);
    if (values.has(entry + ".crack_opening")) {
      probe.crack_opening = true;
      if (!scene.has_crack()) values.fail(entry + ".crack_opening", "a scene with a crack", "a body without one");
      if (values.has(entry + ".component")) {
        values.fail(entry + ".component", "no component with crack_opening (its normal gap is analysed)",
                    "'" + values.word(entry + ".component") + "'");
      }
      if (values.has(entry + ".side")) {
        values.fail(entry + ".side", "no side with crack_opening (it records both faces)",
                    "'" + values.word(entry + ".side") + "'");
      }
    }
    for (const ProbeSection& earlier : probes) {
      if (earlier.name == probe.name) values.fail(entry + ".name", "a name no other probe has", "'" + probe.name + "' again");
    }
    probes.push_back(probe);
  }
  return probes;
}

/// `transient.release`: a static deflection or a mode shape (exactly one of them: the table's rule).
ReleaseSection release_from(const Values& values, const Scene& scene) {
  ReleaseSection release;
  release.kind = values.has("transient.release.mode") ? ReleaseKind::mode : ReleaseKind::static_deflection;
  read_section(values, "transient.release", release);
  if (release.kind == ReleaseKind::mode && release.variant == mesh::Variant::open && !scene.has_crack()) {
    values.fail("transient.release.mode.variant", "uncracked (the scene has no crack)", "'open'");
  }
  return release;
}

/// `transient.initial`: fields over coordinate ranges.
std::vector<InitialSection> initial_from(const Values& values) {
  std::vector<InitialSection> fields;
  for (int i = 0; i < values.count("transient.initial"); ++i) {
    InitialSection initial;
    read_entry(values, "transient.initial", i, initial);  // the ranges: increasing, bound per axis
    fields.push_back(initial);
  }
  return fields;
}

TransientSection transient_from(const Values& values, const Scene& scene) {
  TransientSection transient;
  read_section(values, "transient", transient);
  read_section(values, "transient.reduced", transient.reduced);
  if (values.has("transient.excitation")) transient.excitation = excitation_from(values, scene);
  if (values.has("transient.damping")) transient.damping = damping_from(values);
  if (transient.periods && !(transient.excitation && transient.excitation->kind == ExcitationKind::harmonic)) {
    values.fail("transient.periods", "duration (periods needs a harmonic excitation)", "periods");
  }
  transient.probes = probes_from(values, scene);
  if (values.has("transient.release")) transient.release = release_from(values, scene);
  transient.initial = initial_from(values);
  if (transient.model == TransientModel::reduced && transient.time_step) {
    values.fail("transient.time_step", "auto with transient.model: reduced (its step is set by "
                "transient.reduced.steps_per_period)", format_number(*transient.time_step));
  }
  if (transient.variant == mesh::Variant::open && !scene.has_crack()) transient.variant = mesh::Variant::uncracked;
  return transient;
}

SpectrumSection spectrum_from(const Values& values, const Scene& scene) {
  if (!scene.transient) values.fail("spectrum", "a transient section to analyse", "none");
  if (scene.transient->probes.empty()) values.fail("transient.probes", "at least one probe for the spectrum", "none");
  SpectrumSection spectrum;
  read_section(values, "spectrum", spectrum);
  return spectrum;
}

SweepFrequencySection sweep_end_from(const Values& values, const Scene& scene, const std::string& key) {
  SweepFrequencySection end;
  read_section(values, key, end);
  if (end.of != ModeOf::uncracked && !scene.has_crack())
    values.fail(key + ".of", "uncracked (the scene has no crack)", mode_of_name(end.of));
  return end;
}

SweepSection sweep_from(const Values& values, const Scene& scene) {
  for (std::size_t i = 0; scene.transient && i < scene.transient->probes.size(); ++i) {
    const ProbeSection& probe = scene.transient->probes[i];
    if (!probe.crack_opening && !probe.side) continue;
    values.fail("transient.probes[" + std::to_string(i) + "]" + (probe.crack_opening ? ".crack_opening" : ".side"),
                "a plain point probe in a scene with sweep: (the sweep's outputs are nearest-node displacements)",
                "this key");
  }
  if (!scene.transient || !scene.transient->excitation || scene.transient->excitation->kind != ExcitationKind::harmonic) {
    values.fail("sweep", "a transient section with a harmonic excitation (its load shape and amplitude are swept)",
                "none");
  }
  if (scene.transient->probes.empty()) values.fail("transient.probes", "at least one probe for the sweep", "none");
  SweepSection sweep;
  sweep.from = sweep_end_from(values, scene, "sweep.frequency.from");
  sweep.to = sweep_end_from(values, scene, "sweep.frequency.to");
  const bool same_reference = sweep.from.mode == sweep.to.mode && sweep.from.of == sweep.to.of;
  const double from_value = sweep.from.hz ? *sweep.from.hz : sweep.from.ratio;
  const double to_value = sweep.to.hz ? *sweep.to.hz : sweep.to.ratio;
  if (same_reference && from_value == to_value) {
    values.fail("sweep.frequency.to", "a frequency other than sweep.frequency.from", "the same");
  }
  read_section(values, "sweep", sweep);
  if (sweep.stability && scene.contact.friction > 0.0) {
    values.fail("sweep.stability", "false with friction (Hill's method is frictionless)", "true");
  }
  if (values.has("sweep.solve_at") && sweep.method != SweepMethod::harmonic_balance) {
    values.fail("sweep.solve_at", "sweep.method: harmonic_balance (stepped_sine runs at its own frequencies)",
                "sweep.method: " + method_name(sweep.method));
  }
  return sweep;
}

/// `mesh:`: the Gmsh file (checked to be a file), or the box and its grading.
void mesh_from(const Values& values, Scene& scene) {
  if (values.has("mesh.gmsh")) {
    scene.gmsh_file = mesh_file_path(values.file(), values.word("mesh.gmsh"));
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(scene.gmsh_file, error);
    if (std::filesystem::is_directory(status))
      values.fail("mesh.gmsh", "a Gmsh mesh file", "a directory, '" + scene.gmsh_file + "'");
    // A device or a pipe (/dev/zero, /dev/stdin) never ends: the reader would fill the memory.
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
      values.fail("mesh.gmsh", "a Gmsh mesh file", "a device or pipe, '" + scene.gmsh_file + "'");
  } else {
    read_section(values, "mesh.box", scene.box);  // with the lines
    read_section(values, "mesh.box.grading", scene.grading);  // the mode
    // layers: auto is the scene's default (mesh::Grading's own, 0, means no grading); ratio: auto
    // keeps mesh::Grading's 0.2.
    scene.grading.grading.layers = mesh::kAutoLayers;
    read_section(values, "mesh.box.grading", scene.grading.grading);
  }
}

/// `boundary:`, each entry on a box face or a mesh group.
std::vector<BoundarySection> boundary_from(const Values& values) {
  std::vector<BoundarySection> boundary;
  for (int i = 0; i < values.count("boundary"); ++i) {
    const std::string entry = "boundary[" + std::to_string(i) + "]";
    BoundarySection section;
    if (values.has(entry + ".face") == values.has(entry + ".group")) {
      values.fail(entry, "face (a box face) or group (a group of the mesh)",
                  values.has(entry + ".face") ? "both" : "neither");
    }
    read_entry(values, "boundary", i, section);
    section.line = std::max(values.line(entry), 0);
    boundary.push_back(section);
  }
  return boundary;
}

/// `crack:` as a mesh group, or as a plane and region (with its reference) of a box.
void crack_section_from(const Values& values, Scene& scene) {
  if (values.has("crack")) {
    if (values.has("crack.group")) {
      if (values.has("crack.plane") || values.has("crack.region") || values.has("crack.reference")) {
        values.fail("crack.group", "either group or plane and region (and reference)", "both");
      }
      if (scene.gmsh_file.empty()) {
        values.fail("crack.group", "plane and region (a box mesh has no groups; group needs mesh.gmsh)",
                    "'" + values.word("crack.group") + "'");
      }
      scene.crack_group = GroupCrackSection{values.word("crack.group"), values.number("crack.gap"),
                                            std::max(values.line("crack.group"), 0)};
    } else if (!scene.gmsh_file.empty()) {
      values.fail("crack", "group (the physical surface of the crack in the Gmsh mesh)", "plane and region");
    } else {
      for (const char* key : {"plane", "region"}) {
        if (!values.has(std::string("crack.") + key)) {
          values.fail(std::string("crack.") + key, describe(*scene_parameters().child("crack")->child(key)),
                      "nothing");
        }
      }
      scene.crack = crack_from(values, scene.box);
      scene.crack_reference = reference_crack_from(values, scene.box, *scene.crack);
    }
  }
}

/// The lines of the keys the pipeline may name after loading (Scene::key_lines).
std::map<std::string, int> key_lines_of(const Values& values, const Scene& scene) {
  std::map<std::string, int> lines;
  std::vector<std::string> named = {"mesh.box.cells", "mesh.box.order", "mesh.gmsh", "transient.periods",
                                    "transient.duration", "transient.time_step", "transient.snapshots.count", "transient.model",
                                    "transient.history.samples_per_period", "transient.excitation.point",
                                    "transient.excitation.frequency", "transient.excitation.frequency.hz",
                                    "spectrum.harmonics"};
  if (scene.transient) {
    for (std::size_t i = 0; i < scene.transient->probes.size(); ++i)
      for (const char* key : {"point", "crack_opening", "side"})
        named.push_back("transient.probes[" + std::to_string(i) + "]." + key);
  }
  for (const std::string& key : named) {
    if (values.has(key)) lines[key] = values.line(key);
  }
  return lines;
}

Scene scene_from(const Values& values) {
  Scene scene;
  scene.file = values.file();
  mesh_from(values, scene);

  const bool has_materials = values.has("materials") && values.count("materials") > 0;
  if (values.has("material") && has_materials) {
    values.fail("materials", "either material (one for the whole body) or materials", "both");
  }
  if (has_materials) {
    scene.materials = materials_from(values, !scene.gmsh_file.empty());
  } else if (!values.has("material")) {
    values.fail("material", describe(*scene_parameters().child("material")), "nothing");
  } else {
    read_section(values, "material", scene.material);
  }

  scene.boundary = boundary_from(values);
  check_boundary(values, scene.boundary);

  crack_section_from(values, scene);

  scene.has_modal_section = values.has("modal");
  read_section(values, "modal", scene.modal);
  for (std::size_t i = 0; i < scene.modal.variants.size(); ++i) {
    if (scene.modal.variants[i] == mesh::Variant::open && !scene.has_crack()) {
      values.fail("modal.variants[" + std::to_string(i) + "]", "uncracked (the scene has no crack)",
                  "'open'");
    }
  }
  if (values.has("crack")) {
    read_section(values, "crack.contact", scene.contact);
  }
  if (values.has("transient")) scene.transient = transient_from(values, scene);
  if (values.has("spectrum")) scene.spectrum = spectrum_from(values, scene);
  if (values.has("sweep")) scene.sweep = sweep_from(values, scene);
  if (values.has("accuracy")) {
    if (!scene.spectrum && !scene.sweep && !values.has("modal")) {
      values.fail("accuracy", "a spectrum:, sweep: or modal: section (the accuracy estimates are of their signatures "
                  "and frequencies)", "none");
    }
    read_section(values, "accuracy", scene.accuracy);
    scene.has_accuracy_section = true;
  }
  scene.key_lines = key_lines_of(values, scene);
  return scene;
}

}  // namespace

std::string reduced_route_refusal(const Scene& scene, int ranks) {
  const TransientSection& transient = *scene.transient;
  if (ranks > 1) return "mpirun -np " + std::to_string(ranks) + " (one transient over several processes is the full model)";
  if (!transient.excitation || transient.excitation->kind != ExcitationKind::harmonic) {
    return "no harmonic excitation (a pulse or free vibration has content above any retained band)";
  }
  if (!scene.spectrum) return "no spectrum: section (no signature to compute)";
  if (!scene.has_crack() || transient.variant != mesh::Variant::open) return "no crack to breathe (a linear run)";
  if (scene.contact.model != ContactModel::penalty) return "crack.contact.model: none (a linear run)";
  if (transient.time_step) return "an explicit transient.time_step";
  if (!transient.initial.empty()) return "transient.initial fields (the full model takes them as given)";
  if (transient.release) return "a transient.release (the full model starts from it as given)";
  return "";
}

bool takes_route_mesh(const Scene& scene, const std::string& command) {
  if (!scene.gmsh_file.empty() || !scene.transient || scene.transient->model != TransientModel::automatic) return false;
  if (command == "sweep") return scene.sweep && scene.has_crack() && scene.contact.model == ContactModel::penalty;
  return command == "run" && reduced_route_refusal(scene, 1).empty();
}

std::string Scene::where(const std::string& key_path) const {
  const auto found = key_lines.find(key_path);
  const int line = found == key_lines.end() ? -1 : found->second;
  return file + (line > 0 ? ":" + std::to_string(line) : "") + ": " + key_path;
}

const Param& scene_parameters() {
  static const Param root = build_parameters();
  return root;
}

Scene parse_scene(const std::string& text, const std::string& name, const std::vector<Override>& overrides) {
  YAML::Node document = parse_yaml(text, name);
  // `study:` belongs to the study driver (src/study), which validates it itself; a single run of a
  // study's base scene ignores it.
  if (document.IsMap() && document["study"]) document.remove("study");
  // `identify:` likewise belongs to `crackle identify` (src/identify).
  if (document.IsMap() && document["identify"]) document.remove("identify");
  // `plan:` belongs to `crackle plan` (src/planning).
  if (document.IsMap() && document["plan"]) document.remove("plan");
  for (const Override& change : overrides) apply_override(document, change.path, change.value, name);
  return scene_from(validate(scene_parameters(), document, name));
}

std::string read_scene_file(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw InputError(path + ": expected a readable scene file, got a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": expected a readable scene file, got " + std::strerror(errno));
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError(path + ": expected a readable scene file, got a read error");
  return text.str();
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
  return parse_scene(read_scene_file(path), path, overrides);
}

const Param& study_parameters() {
  static const Param table = map_of("", "", {map_of("study", "Parameter study run by `crackle study` (check, modal and run ignore it).", {
      map_of("vary", "Scene keys to vary, each by its key path (`crack.region.z`, `boundary[0].value`): a list of "
                     "values, or {from, to, steps} for evenly spaced numbers or number lists.", {}).required(),
      choice("mode", "grid: every combination of the values, the first key slowest; zip: the i-th values of every "
                     "key together (lists of equal length).", kStudyModeWords).defaults_to("grid"),
      choice("outputs", "What each case runs: modal -> `crackle modal`, spectrum -> `crackle run`, sweep -> "
                        "`crackle sweep` (the scene needs a sweep: section); modal with spectrum or sweep and a "
                        "`modal:` section: not run apart, as those write modal.json too.",
             {"modal", "spectrum", "sweep"}).list(1, 2).distinct().defaults_to("[modal]"),
  }).optional_section()});
  return table;
}

const Param& identify_parameters() {
  static const Param table = map_of("", "", {map_of("identify", "Damage identification run by `crackle identify` (check, modal and run ignore it); parsed by src/identify, which accepts exactly these keys.", {
      map_of("unknowns", "Scene keys to identify, each by its key path (a list entry by its index: `crack.region.z[0]`) "
                         "with bounds [low, high]. A crack key moves the crack on a grid made for the middle of the "
                         "bounds (crack.reference).", {}).required(),
      list_of("measured", "The measurements, or the path of a CSV file (relative to the scene) with the header "
                          "quantity,mode,probe,drive_hz,value,sigma and empty cells where a column does not apply.", {
        choice("quantity", "What was measured: modal frequencies per uncracked mode (f_uncracked, f_open, f_bilinear: "
                           "the modal solve), or a probe's harmonics at a drive frequency (A1 [m], A2/A1, A3/A1: "
                           "harmonic balance on the reduced model, a narrow crackle sweep about drive_hz with the "
                           "scene's excitation, damping and sweep settings); damping_ratio per mode: the scene's "
                           "Rayleigh damping (transient.damping, its keys among the unknowns at their values) at the "
                           "mode's bilinear frequency (its ring-down's; the uncracked one for an unpaired mode); "
                           "A1/2/A1: the f/2 sub-harmonic at a drive near 2 f_b, from a sweep with stability over "
                           "drive_hz +- 15 % (the period-two branch from its period doubling), solved at drive_hz: "
                           "its value on the stable period-two branch, 0 where only the period-one response is "
                           "stable there (no sub-harmonic), missing where neither is (frictionless contact only).",
               {"f_uncracked", "f_open", "f_bilinear", "damping_ratio", "A1", "A2/A1", "A3/A1", "A1/2/A1"}).required(),
        integer("mode", "Uncracked mode number (1 = lowest; open modes paired by MAC), for the frequencies.").at_least(1),
        text("probe", "A probe of transient.probes, for the harmonic quantities."),
        number("drive_hz", "Drive frequency of a harmonic quantity.").with_unit("Hz").above(0),
        number("value", "The measured value (Hz for frequencies).").required(),
        number("sigma", "Its standard deviation, same unit.").above(0).required(),
      }).required(),
      map_of("map", "The global map of the misfit.", {
        integer("points", "Grid points per unknown.").at_least(3).defaults_to("7"),
      }),
      choice("sigma", "scaled: covariance s^2 (J^T J)^-1 with s^2 = chi^2/(n - k) and Student's t; trusted: s^2 = 1 and "
                      "the normal quantile.", kScaledSigmaWords).defaults_to("scaled"),
      map_of("truth", "A synthetic test's true value of every unknown {key: value}: identify.json `truth` then gives the "
                      "error, whether each 95 % interval holds the truth, and the Cramer-Rao bound there (the "
                      "Gauss-Newton standard deviation at the truth, sigmas trusted).", {}),
  }).optional_section()});
  return table;
}

const Param& plan_parameters() {
  static const Param table = map_of("", "", {map_of("plan", "Test planning run by `crackle plan` (check, modal and run ignore it); parsed by src/planning, which accepts exactly these keys.", {
      map_of("prior", "The cracks to design for: scene keys with ranges [low, high], in the form of identify.unknowns "
                      "(a list entry by its index: `crack.region.z[0]`). The crack moves on a grid made for the middle.", {}).required(),
      integer("samples", "Prior samples per key: the centres of equal bins (samples^keys points in all).").at_least(2).at_most(9).defaults_to("3"),
      text("size", "The prior key that measures the crack's size, along which the smallest detectable crack is "
                   "interpolated (default: the last key)."),
      map_of("sensors", "Candidate sensor points: a face sampled on a grid, or a list of points.", {
        choice("face", "A face of the box whose grid of points are the candidates.",
               {mesh::box_face_names().begin(), mesh::box_face_names().end()}),
        number("spacing", "Spacing of the face's grid (with face; at most 2000 points).").with_unit("m").above(0),
        map_of("points", "The candidate points [[x, y, z], ...] instead of a face.", {}),
        choice("component", "The displacement component a sensor measures (default: the excitation's direction).",
               kAxisWords),
      }).required(),
      map_of("drives", "Candidate drives: the points of the scene's harmonic excitation (its direction, amplitude and "
                       "damping) and its frequencies.", {
        map_of("points", "Drive points [[x, y, z], ...] inside the body's box.", {}).required(),
        list_of("frequencies", "Drive frequencies as multiples of a mode's bilinear frequency; a ratio >= 1.5 drives "
                               "the f/2 sub-harmonic (a sweep with stability finds its period-two branch).", {
          integer("mode", "Uncracked mode number (1 = lowest), at most modal.modes.").at_least(1).required(),
          number("ratio", "Drive frequency over the mode's bilinear frequency.").above(0).at_most(10).required(),
        }).required(),
      }).required(),
      map_of("noise", "The measurement's noise, relative; the model error (identify's p-refinement estimate in the "
                      "middle of the prior) is added in quadrature.", {
        number("frequency", "Relative sigma of a measured frequency.").above(0).defaults_to("0.0005"),
        number("ratio", "Relative sigma of a measured harmonic ratio.").above(0).defaults_to("0.05"),
        number("floor", "Noise floor of a harmonic amplitude, relative to the largest first harmonic over the sensors "
                        "(the acquisition's dynamic range).").above(0).defaults_to("1.0e-4"),
      }),
      integer("combine", "The best sets of 1..combine sensors (greedy on log det).").at_least(1).at_most(5).defaults_to("3"),
  }).optional_section()});
  return table;
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
         markdown_table(scene_parameters()) +
         "\n## Parameter study\n\n"
         "`crackle study scene.yaml -o DIR` runs one case per combination of the values below, each a full "
         "scene\n(validated like any other) in `DIR/cases/NNNN/`; `study.csv` and `study.json` collect them.\n\n" +
         markdown_table(study_parameters()) +
         "\n## Identification\n\n"
         "`crackle identify scene.yaml -o DIR` fits the unknowns below to the measured signatures "
         "(README, \"Damage identification\").\n\n" +
         markdown_table(identify_parameters()) +
         "\n## Test planning\n\n"
         "`crackle plan scene.yaml -o DIR` ranks candidate sensors, drive points and drive frequencies for the "
         "cracks of the prior (README, \"Test planning\").\n\n" +
         markdown_table(plan_parameters());
}

}  // namespace crackle::scene
