// Scene files: the beam example, defaults from the table, one exact message per bad input,
// overrides by key path, and the generated docs/scene-format.md.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"
#include "scene/scene.hpp"

namespace crackle::scene {
namespace {

const std::string kBeam = R"(# data/beam.yaml: steel cantilever with an edge crack at a quarter of its length
mesh:
  box:
    size: [0.2, 0.02, 0.01]          # m, along x, y, z
    cells: [40, 4, 2]                # elements per direction; grid lines are added where crack edges need them
    order: 2                         # element order p = 1..4 (GLL nodes)
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {face: x-, fix: [x, y, z]}      # clamp the end x = 0; faces are x-, x+, y-, y+, z-, z+
crack:
  plane: {normal: x, at: 0.05}       # the crack lies in the plane x = 0.05 m
  region: {y: [0.0, 0.02], z: [0.007, 0.01]}   # rectangle on that plane: a 3 mm edge crack from the top face
  gap: 0.0                           # initial normal gap g0 (MODEL.md eq. 9)
modal:                               # optional
  modes: 10                  # lowest modes per variant (>= 1)
  variants: [uncracked, open]  # default: both when the scene has a crack, [uncracked] otherwise; "open" without a crack is an error
  solver: slepc              # auto (default) | slepc | arpack
  mass: consistent           # consistent (default) | lumped
)";

/// Lines 1-5 of the scenes below.
std::string box(const std::string& size = "[0.2, 0.02, 0.01]", const std::string& cells = "[40, 4, 2]",
                const std::string& order = "2") {
  return "mesh:\n  box:\n    size: " + size + "\n    cells: " + cells + "\n    order: " + order + "\n";
}
/// Line 6.
std::string material(const std::string& keys = "E: 210.0e9, nu: 0.3, rho: 7850.0") {
  return "material: {" + keys + "}\n";
}
/// Lines 7-9 after box() and material().
std::string crack(const std::string& plane = "normal: x, at: 0.05",
                  const std::string& region = "y: [0.0, 0.02], z: [0.007, 0.01]") {
  return "crack:\n  plane: {" + plane + "}\n  region: {" + region + "}\n";
}
const std::string kBody = box() + material();

std::string error_of(const std::string& text, const std::vector<Override>& overrides = {}) {
  try {
    parse_scene(text, "beam.yaml", overrides);
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(Scene, BeamLoads) {
  const Scene scene = parse_scene(kBeam, "beam.yaml");
  EXPECT_EQ(scene.file, "beam.yaml");
  EXPECT_EQ(scene.box.origin, Vec3(0, 0, 0));
  EXPECT_EQ(scene.box.size, Vec3(0.2, 0.02, 0.01));
  EXPECT_EQ(scene.box.cells, (std::array<int, 3>{40, 4, 2}));
  EXPECT_EQ(scene.box.order, 2);
  EXPECT_EQ(scene.material.young, 210.0e9);
  EXPECT_EQ(scene.material.poisson, 0.3);
  EXPECT_EQ(scene.material.density, 7850.0);
  ASSERT_EQ(scene.boundary.size(), 1u);
  EXPECT_EQ(scene.boundary[0].face, "x-");
  EXPECT_EQ(scene.boundary[0].components, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(scene.boundary[0].values, (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(scene.boundary[0].line, 9);
  ASSERT_TRUE(scene.crack);
  EXPECT_EQ(scene.crack->normal, kX);
  EXPECT_EQ(scene.crack->at, 0.05);
  EXPECT_EQ(scene.crack->region[kY], (std::array<double, 2>{0.0, 0.02}));
  EXPECT_EQ(scene.crack->region[kZ], (std::array<double, 2>{0.007, 0.01}));
  EXPECT_EQ(scene.crack->gap, 0.0);
  EXPECT_TRUE(scene.has_modal_section);
  EXPECT_EQ(scene.modal.modes, 10);
  EXPECT_EQ(scene.modal.variants, (std::vector<mesh::Variant>{mesh::Variant::uncracked, mesh::Variant::open}));
  EXPECT_EQ(scene.modal.solver, ModalSolver::slepc);
  EXPECT_EQ(scene.modal.mass, MassMatrix::consistent);
}

TEST(Scene, LoadsAFile) {
  const std::string path = ::testing::TempDir() + "/scene_beam.yaml";
  std::ofstream(path) << kBeam;
  const Scene scene = load_scene(path);
  EXPECT_EQ(scene.file, path);
  EXPECT_EQ(scene.box.cells[0], 40);
  EXPECT_EQ(error_of(""),
            "beam.yaml: expected a map with keys mesh, material, materials, boundary, crack, modal, transient, spectrum, accuracy, sweep, "
            "got an empty file");
}

TEST(Scene, DefaultsComeFromTheTable) {
  const Scene bare = parse_scene(kBody, "beam.yaml");
  EXPECT_EQ(bare.box.origin, Vec3(0, 0, 0));
  EXPECT_TRUE(bare.boundary.empty());
  EXPECT_FALSE(bare.crack);
  EXPECT_FALSE(bare.has_modal_section);
  EXPECT_EQ(bare.modal.variants, (std::vector<mesh::Variant>{mesh::Variant::uncracked}));
  // The struct's initial values agree with the table's defaults.
  const ModalSection initial;
  EXPECT_EQ(bare.modal.modes, initial.modes);
  EXPECT_EQ(bare.modal.solver, initial.solver);
  EXPECT_EQ(bare.modal.mass, initial.mass);

  const Scene cracked =
      parse_scene(kBody + crack() + "modal: {modes: 4}\nboundary: [{face: y-, fix: [y, z]}]\n", "beam.yaml");
  EXPECT_EQ(cracked.crack->gap, 0.0);
  EXPECT_EQ(cracked.modal.modes, 4);
  EXPECT_EQ(cracked.modal.variants, (std::vector<mesh::Variant>{mesh::Variant::uncracked, mesh::Variant::open}));
  EXPECT_EQ(cracked.boundary[0].values, (std::vector<double>{0, 0}));
}

TEST(Scene, TheGridsKeysAndTheReferenceCrackLandInTheirOwnFields) {
  // mesh.box.lines and mesh.box.grading: each axis's list in its own entry, the grading's words.
  const Scene graded = parse_scene(
      box() + "    lines: {x: [0.002, 0.004], z: [0.001]}\n"
              "    grading: {mode: always, layers: 3, ratio: 0.3, fronts: {y: [0.005]}}\n" + material(),
      "beam.yaml");
  EXPECT_EQ(graded.box.extra_lines[kX], (std::vector<double>{0.002, 0.004}));
  EXPECT_TRUE(graded.box.extra_lines[kY].empty());
  EXPECT_EQ(graded.box.extra_lines[kZ], (std::vector<double>{0.001}));
  EXPECT_EQ(graded.grading.mode, GradingMode::always);
  EXPECT_EQ(graded.grading.grading.layers, 3);
  EXPECT_EQ(graded.grading.grading.ratio, 0.3);
  EXPECT_TRUE(graded.grading.grading.fronts[kX].empty());
  EXPECT_EQ(graded.grading.grading.fronts[kY], (std::vector<double>{0.005}));
  EXPECT_EQ(graded.box.grading.layers, 0) << "the box's own grading is set per command";
  // auto: the layers from the order (mesh::kAutoLayers), the ratio mesh::Grading's own.
  const Scene plain = parse_scene(kBody, "beam.yaml");
  EXPECT_EQ(plain.grading.mode, GradingMode::automatic);
  EXPECT_EQ(plain.grading.grading.layers, mesh::kAutoLayers);
  EXPECT_EQ(plain.grading.grading.ratio, mesh::Grading{}.ratio);
  EXPECT_EQ(parse_scene(box() + "    grading: none\n" + material(), "beam.yaml").grading.mode, GradingMode::none);

  // crack.reference's at and region are the reference's: the crack keeps its own plane and region,
  // and the reference's axes not given are the crack's.
  const Scene moved = parse_scene(kBody + crack("normal: x, at: 0.0537", "y: [0.0, 0.02], z: [0.0072, 0.01]") +
                                      "  reference: {at: 0.05, region: {z: [0.007, 0.01]}}\n",
                                  "beam.yaml");
  ASSERT_TRUE(moved.crack && moved.crack_reference);
  EXPECT_EQ(moved.crack->at, 0.0537);
  EXPECT_EQ(moved.crack->region[kZ], (std::array<double, 2>{0.0072, 0.01}));
  EXPECT_EQ(moved.crack->region[kY], (std::array<double, 2>{0.0, 0.02}));
  EXPECT_EQ(moved.crack_reference->at, 0.05);
  EXPECT_EQ(moved.crack_reference->region[kZ], (std::array<double, 2>{0.007, 0.01}));
  EXPECT_EQ(moved.crack_reference->region[kY], (std::array<double, 2>{0.0, 0.02}));
  EXPECT_EQ(moved.crack_reference->normal, kX);
  const Scene only_region = parse_scene(kBody + crack("normal: x, at: 0.05", "y: [0.0, 0.02], z: [0.0072, 0.01]") +
                                            "  reference: {region: {z: [0.007, 0.01]}}\n",
                                        "beam.yaml");
  EXPECT_EQ(only_region.crack_reference->at, 0.05);
  EXPECT_EQ(only_region.crack->region[kZ], (std::array<double, 2>{0.0072, 0.01}));
  EXPECT_EQ(error_of(kBody + crack() + "  reference: {region: {x: [0.04, 0.06]}}\n"),
            "beam.yaml:10: crack.reference.region.x: expected the in-plane axes of the crack's region, got x (the crack's normal)");
}

TEST(Scene, ConsistentBoundaryConditionsAreAccepted) {
  const Scene scene =
      parse_scene(kBody +
                      "boundary:\n"
                      "  - {face: x-, fix: [x], value: [0.001]}\n"
                      "  - {face: x+, fix: [x], value: [-0.001]}\n"  // opposite: no shared node
                      "  - {face: y-, fix: [y, z], value: [0, 0.002]}\n"
                      "  - {face: z-, fix: [z], value: [0.002]}\n",  // same z on the edge
                  "beam.yaml");
  ASSERT_EQ(scene.boundary.size(), 4u);
  EXPECT_EQ(scene.boundary[1].values, (std::vector<double>{-0.001}));
  EXPECT_EQ(scene.boundary[3].line, 11);
}

struct BadScene {
  std::string text;
  std::string message;
};

TEST(Scene, BadScenesGiveOneExactLine) {
  const std::string sections = "mesh, material, materials, boundary, crack, modal, transient, spectrum, accuracy, sweep";
  const std::vector<BadScene> cases = {
      // the file as a whole
      {"# only a comment\n", "beam.yaml: expected a map with keys " + sections + ", got an empty file"},
      {"- mesh\n- material\n",
       "beam.yaml:1: expected a map with keys " + sections + ", got a list of 2 entries"},
      {"hello\n", "beam.yaml:1: expected a map with keys " + sections + ", got 'hello'"},
      {box() + "material: {E: 210e9, nu: 0.3\n",
       "beam.yaml:7: expected valid YAML, got a syntax error (end of map flow not found)"},
      {kBody + "modall:\n  modes: 3\n", "beam.yaml:7: modall: expected one of " + sections +
                                            ", got unknown section 'modall' (did you mean 'modal'?)"},
      // required keys
      {box(), "beam.yaml:1: material: expected a map with keys E, nu, rho, got nothing"},
      {material(), "beam.yaml:1: mesh: expected exactly one of: box, gmsh, got nothing"},
      {material() + "mesh: {}\n", "beam.yaml:2: mesh: expected exactly one of: box, gmsh, got none"},
      {material() + "mesh: {stl: part.stl}\n",
       "beam.yaml:2: mesh.stl: expected one of box, gmsh, got unknown key 'stl'"},
      {box() + material("E: 210e9, nu: 0.3"),
       "beam.yaml:6: material.rho: expected a positive number, got nothing"},
      {"mesh:\n  box: {cells: [40, 4, 2], order: 2}\n" + material(),
       "beam.yaml:2: mesh.box.size: expected a list of 3 positive numbers, got nothing"},
      // types
      {box() + "material: 5\n", "beam.yaml:6: material: expected a map with keys E, nu, rho, got 5"},
      {box() + material("E: abc, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got 'abc'"},
      {box() + material("E: \"210e9\", nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got '210e9'"},
      {box() + material("E: true, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got true"},
      {box() + material("E: .nan, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got .nan"},
      {box() + material("E: .inf, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got .inf"},
      {box() + material("E: [1, 2], nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got a list of 2 entries"},
      {box() + material("E: 2e11, E: 2e11, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected each key once, got 'E' again"},
      {box() + material("young: 2e11, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.young: expected one of E, nu, rho, got unknown key 'young'"},
      {box("0.2") + material(), "beam.yaml:3: mesh.box.size: expected a list of 3 positive numbers, got 0.2"},
      {box("[0.2, 0.02]") + material(),
       "beam.yaml:3: mesh.box.size: expected a list of 3 positive numbers, got a list of 2 entries"},
      {box("[0.2, 0.02, abc]") + material(),
       "beam.yaml:3: mesh.box.size[2]: expected a positive number, got 'abc'"},
      {box("[0.2, 0.02, 0.01]", "[40, 4, 2.5]") + material(),
       "beam.yaml:4: mesh.box.cells[2]: expected a positive integer, got 2.5"},
      {box("[0.2, 0.02, 0.01]", "[99999999999, 4, 2]") + material(),
       "beam.yaml:4: mesh.box.cells[0]: expected a positive integer, got 99999999999"},
      // ranges
      {box() + material("E: -2e11, nu: 0.3, rho: 7850"),
       "beam.yaml:6: material.E: expected a positive number, got -2e11"},
      {box() + material("E: 2e11, nu: 0.5, rho: 7850"),
       "beam.yaml:6: material.nu: expected a number in (-1, 0.5), got 0.5"},
      {box() + material("E: 2e11, nu: -1, rho: 7850"),
       "beam.yaml:6: material.nu: expected a number in (-1, 0.5), got -1"},
      {box() + material("E: 2e11, nu: 0.3, rho: 0"),
       "beam.yaml:6: material.rho: expected a positive number, got 0"},
      {box("[0.2, 0.02, 0.01]", "[40, 4, 2]", "0") + material(),
       "beam.yaml:5: mesh.box.order: expected an integer in 1..4, got 0"},
      {box("[0.2, 0.02, 0.01]", "[40, 4, 2]", "9") + material(),
       "beam.yaml:5: mesh.box.order: expected an integer in 1..4, got 9"},
      {box("[0.2, 0.02, 0.01]", "[40, 0, 2]") + material(),
       "beam.yaml:4: mesh.box.cells[1]: expected a positive integer, got 0"},
      {box("[0.2, -0.02, 0.01]") + material(),
       "beam.yaml:3: mesh.box.size[1]: expected a positive number, got -0.02"},
      // boundary conditions
      {kBody + "boundary: {face: x-, fix: [x]}\n",
       "beam.yaml:7: boundary: expected a list of maps with keys face, group, fix, value, got a map"},
      {kBody + "boundary:\n  - {face: top, fix: [x]}\n",
       "beam.yaml:8: boundary[0].face: expected one of x-, x+, y-, y+, z-, z+, got 'top'"},
      {kBody + "boundary:\n  - {face: x-}\n",
       "beam.yaml:8: boundary[0].fix: expected a list of 1 to 3 distinct entries from x, y, z, got nothing"},
      {kBody + "boundary:\n  - {face: x-, fix: [x, y, x]}\n",
       "beam.yaml:8: boundary[0].fix[2]: expected each entry at most once, got 'x' again"},
      {kBody + "boundary:\n  - {face: x-, fix: [w]}\n",
       "beam.yaml:8: boundary[0].fix[0]: expected one of x, y, z, got 'w'"},
      {kBody + "boundary:\n  - {face: x-, fix: [x, y], value: [0.001]}\n",
       "beam.yaml:8: boundary[0].value: expected a list of 2 numbers, one per entry of fix, got a list of 1 "
       "entry"},
      {kBody + "boundary:\n  - {face: x-, fix: [x]}\n  - {face: x-, fix: [y, x], value: [0, 0.001]}\n",
       "beam.yaml:9: boundary[1].value[1]: expected x = 0 as fixed by boundary[0] on the same face, got x = "
       "0.001"},
      {kBody + "boundary:\n  - {face: x-, fix: [x, y, z]}\n  - {face: y-, fix: [x], value: [0.001]}\n",
       "beam.yaml:9: boundary[1].value[0]: expected x = 0 as fixed by boundary[0] on face x-, which shares "
       "an edge "
       "with y-, got x = 0.001"},
      {kBody + "boundary:\n  - {face: z+, fix: [z], value: [0.001]}\n  - {face: x+, fix: [z]}\n",
       "beam.yaml:9: boundary[1].value[0]: expected z = 0.001 as fixed by boundary[0] on face z+, which "
       "shares an "
       "edge with x+, got z = 0"},
      // the crack
      {kBody + crack("normal: x, at: 0.051"),
       "beam.yaml:8: crack.plane.at: expected a grid plane of the mesh, x = 0 + k*0.005 (nearest 0.05 or "
       "0.055), "
       "got 0.051"},
      {kBody + crack("normal: x, at: 0.2"),
       "beam.yaml:8: crack.plane.at: expected a position strictly inside the body, x in (0, 0.2), got 0.2"},
      {kBody + crack("normal: x, at: -0.05"),
       "beam.yaml:8: crack.plane.at: expected a position strictly inside the body, x in (0, 0.2), got -0.05"},
      {kBody + crack("normal: x, at: 0.05", "y: [0.0, 0.02], z: [0.007, 0.02]"),
       "beam.yaml:9: crack.region.z: expected a range inside the body, z in [0, 0.01], got [0.007, 0.02]"},
      {kBody + crack("normal: x, at: 0.05", "y: [0.0, 0.02], z: [0.01, 0.01]"),
       "beam.yaml:9: crack.region.z: expected [low, high] with low < high (a crack of nonzero area), got "
       "[0.01, 0.01]"},
      {kBody + crack("normal: x, at: 0.05", "x: [0.0, 0.2], y: [0.0, 0.02]"),
       "beam.yaml:9: crack.region: expected keys y and z (the in-plane axes of a crack normal to x), got x "
       "and y"},
      {kBody + crack("normal: z, at: 0.005", "x: [0.0, 0.2]"),
       "beam.yaml:9: crack.region: expected keys x and y (the in-plane axes of a crack normal to z), got x"},
      {kBody + crack("normal: w, at: 0.05"),
       "beam.yaml:8: crack.plane.normal: expected one of x, y, z, got 'w'"},
      {kBody + "crack:\n  plane: {normal: x, at: 0.05}\n",
       "beam.yaml:7: crack.region: expected a map with keys x, y, z, got nothing"},
      {kBody + "crack:\n  plane: {normal: x, at: 0.05}\n  regoin: {y: [0, 0.02], z: [0.007, 0.01]}\n",
       "beam.yaml:9: crack.regoin: expected one of plane, region, reference, group, gap, contact, got unknown key 'regoin' "
       "(did you mean 'region'?)"},
      // the modal section
      {kBody + "modal: {modes: 0}\n", "beam.yaml:7: modal.modes: expected a positive integer, got 0"},
      {kBody + "modal: {solver: lapack}\n",
       "beam.yaml:7: modal.solver: expected one of auto, slepc, arpack, got 'lapack' (did you mean 'arpack'?)"},
      {kBody + "modal: {mass: consistant}\n",
       "beam.yaml:7: modal.mass: expected one of consistent, lumped, got 'consistant' (did you mean "
       "'consistent'?)"},
      {kBody + "modal:\n  variants: [uncracked, open]\n",
       "beam.yaml:8: modal.variants[1]: expected uncracked (the scene has no crack), got 'open'"},
      {kBody + "modal: {variants: []}\n",
       "beam.yaml:7: modal.variants: expected a list of 1 to 2 distinct entries from uncracked, open, got an "
       "empty list"},
  };
  EXPECT_GE(cases.size(), 30u);
  for (const BadScene& bad : cases) {
    SCOPED_TRACE(bad.text);
    EXPECT_EQ(error_of(bad.text), bad.message);
  }
}

TEST(Scene, MissingFile) {
  try {
    load_scene("/nonexistent/beam.yaml");
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_STREQ(error.what(),
                 "/nonexistent/beam.yaml: expected a readable scene file, got No such file or directory");
  }
}

TEST(Scene, DidYouMean) {
  EXPECT_EQ(
      error_of(box() + material("E: 2e11, Nu: 0.3, rho: 7850")),
      "beam.yaml:6: material.Nu: expected one of E, nu, rho, got unknown key 'Nu' (did you mean 'nu'?)");
  EXPECT_EQ(error_of("mesh:\n  box: {size: [1, 1, 1], cels: [1, 1, 1], order: 1}\n" + material()),
            "beam.yaml:2: mesh.box.cels: expected one of origin, size, cells, order, lines, grading, got unknown key 'cels' "
            "(did you mean 'cells'?)");
}

TEST(Scene, OverridesByKeyPath) {
  const Scene scene = parse_scene(kBeam, "beam.yaml",
                                  {{"crack.region.z", "[0.005, 0.01]"},
                                   {"boundary[0].value", "[0.001, 0, 0]"},
                                   {"modal.mass", "lumped"},
                                   {"modal.modes", "3"}});
  EXPECT_EQ(scene.crack->region[kZ], (std::array<double, 2>{0.005, 0.01}));
  EXPECT_EQ(scene.boundary[0].values, (std::vector<double>{0.001, 0, 0}));
  EXPECT_EQ(scene.modal.mass, MassMatrix::lumped);
  EXPECT_EQ(scene.modal.modes, 3);

  // An override adds a whole section to a scene without one.
  const Scene cracked = parse_scene(
      kBody, "beam.yaml", {{"crack", "{plane: {normal: y, at: 0.01}, region: {x: [0, 0.1], z: [0, 0.01]}}"}});
  EXPECT_EQ(cracked.crack->normal, kY);

  // Messages name the path, and no line, for overridden values.
  EXPECT_EQ(error_of(kBeam, {{"modal.modes", "0"}}),
            "beam.yaml: modal.modes: expected a positive integer, got 0");
  EXPECT_EQ(error_of(kBeam, {{"crack.plane.at", "0.052"}}),
            "beam.yaml: crack.plane.at: expected a grid plane of the mesh, x = 0 + k*0.005 (nearest 0.05 or "
            "0.055), "
            "got 0.052");
  EXPECT_EQ(error_of(kBeam, {{"crack.regoin.z", "[0, 0.01]"}}),
            "beam.yaml: crack.regoin: expected one of plane, region, reference, group, gap, contact, got unknown key 'regoin' "
            "(did you mean 'region'?)");
  EXPECT_EQ(error_of(kBeam, {{"boundary[3].face", "x+"}}),
            "beam.yaml: boundary: expected a list with an entry 3, got a list of 1 entry");
  EXPECT_EQ(error_of(kBeam, {{"material.E.x", "1"}}), "beam.yaml: material.E: expected a map, got 2.1e11");
  EXPECT_EQ(error_of(kBeam, {{"crack..z", "1"}}),
            "beam.yaml: expected a key path like crack.region.z or boundary[0].face, got 'crack..z'");
  EXPECT_EQ(error_of(kBeam, {{"crack.gap", "[0"}}),
            "beam.yaml: crack.gap: expected a YAML value, got '[0' (end of sequence flow not found)");
}

TEST(Scene, DocsMatchTheTable) {
  const std::string path = std::string(CRACKLE_SOURCE_DIR) + "/docs/scene-format.md";
  const std::string generated = scene_format_markdown();
  const char* update = std::getenv("CRACKLE_UPDATE_DOCS");
  if (update && std::string(update) == "1") std::ofstream(path) << generated;
  std::ifstream file(path);
  ASSERT_TRUE(file) << path << " is missing; regenerate it with CRACKLE_UPDATE_DOCS=1";
  std::ostringstream text;
  text << file.rdbuf();
  EXPECT_EQ(text.str(), generated) << path << " is stale; regenerate it with CRACKLE_UPDATE_DOCS=1";
}

}  // namespace
}  // namespace crackle::scene
