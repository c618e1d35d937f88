// Scenes at the edges: probe names that must become file names and CSV columns, paths that are
// folders, a scalar frequency that keeps its line, and nested YAML aliases.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "scene/scene.hpp"

namespace crackle::scene {
namespace {

/// Lines 1-9; the probe's name on line 9.
std::string with_probe(const std::string& name, const std::string& frequency = "100.0") {
  return "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [8, 1, 1], order: 1}\n"
         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
         "transient:\n"
         "  excitation: {face: x+, amplitude: 1.0, frequency: " + frequency + "}\n"
         "  periods: 2\n"
         "  probes:\n"
         "    - {name: tip, point: [0.2, 0.01, 0.01]}\n"
         "    - {name: " + name + ", point: [0.1, 0.01, 0.01]}\n";
}

std::string error_of(const std::string& text) {
  try {
    parse_scene(text, "edge.yaml");
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(SceneEdges, ProbeNamesAreFileSafe) {
  EXPECT_EQ(error_of(with_probe("tip.z_2-B")), "(no error)");
  const std::string expected = "edge.yaml:9: transient.probes[1].name: expected a name of letters, digits, _ . - "
                               "(it names output files and CSV columns), got ";
  EXPECT_EQ(error_of(with_probe("a/b")), expected + "'a/b'");
  EXPECT_EQ(error_of(with_probe("\"a,b\"")), expected + "'a,b'");
  EXPECT_EQ(error_of(with_probe("'say \"hi\"'")), expected + "'say \"hi\"'");
  EXPECT_EQ(error_of(with_probe("\"two\\nlines\"")), expected + "'two\\nlines'");
  EXPECT_EQ(error_of(with_probe("\"..\"")), expected + "'..'");
}

TEST(SceneEdges, AScalarFrequencyKeepsItsLine) {
  for (const char* bad : {"0", ".nan", ".inf", "-5"}) {
    EXPECT_EQ(error_of(with_probe("mid", bad)),
              std::string("edge.yaml:5: transient.excitation.frequency.hz: expected a positive number, got ") + bad);
  }
  // An override carries no line, as before.
  try {
    parse_scene(with_probe("mid"), "edge.yaml", {{"transient.excitation.frequency", "0"}});
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_STREQ(error.what(), "edge.yaml: transient.excitation.frequency.hz: expected a positive number, got 0");
  }
}

// What an excitation, a damping or a probe gives must be what it uses: exactly one place, a
// frequency only for a harmonic drive and a duration only for a pulse, `at` only with a ratio.
TEST(SceneEdges, KeysTheTransientWouldIgnoreAreRefused) {
  const auto with = [](const std::string& old_text, const std::string& new_text) {
    std::string text = with_probe("mid");
    text.replace(text.find(old_text), old_text.size(), new_text);
    return text;
  };
  const std::string excitation = "{face: x+, amplitude: 1.0, frequency: 100.0}";
  EXPECT_EQ(error_of(with(excitation, "{face: x+, amplitude: 1.0, kind: pulse, duration: 1.0e-4, frequency: 100.0}")),
            "edge.yaml:5: transient.excitation.frequency: expected no frequency with kind: pulse (duration sets its "
            "band), got a frequency");
  EXPECT_EQ(error_of(with(excitation, "{face: x+, amplitude: 1.0, frequency: 100.0, duration: 1.0e-4}")),
            "edge.yaml:5: transient.excitation.duration: expected no duration with kind: harmonic (the run's length "
            "is transient.periods or transient.duration), got 1e-4");
  EXPECT_EQ(error_of(with(excitation, "{face: x+, point: [0.2, 0.01, 0.01], amplitude: 1.0, frequency: 100.0}")),
            "edge.yaml:5: transient.excitation: expected exactly one of face, group, point, got face and point");
  EXPECT_EQ(error_of(with(excitation, "{face: x+, amplitude: 1.0, frequency: {hz: 100.0, mode: 1}}")),
            "edge.yaml:5: transient.excitation.frequency: expected exactly one of hz, mode, got hz and mode");
  EXPECT_EQ(error_of(with("  periods: 2\n", "  periods: 2\n  damping: {alpha: 1.0, at: 100.0}\n")),
            "edge.yaml:7: transient.damping.at: expected no frequency without a damping ratio (alpha and beta are "
            "given as they are), got a frequency");
  EXPECT_EQ(error_of(with("  periods: 2\n", "  periods: 2\n  duration: 0.1\n")),
            "edge.yaml:4: transient: expected exactly one of periods, duration, got periods and duration");
  EXPECT_EQ(error_of(with("{name: mid, point: [0.1, 0.01, 0.01]}", "{name: mid}")),
            "edge.yaml:9: transient.probes[1]: expected exactly one of point, crack_opening, got none");
  // The values given are the ones read.
  const Scene scene = parse_scene(with(excitation, "{point: [0.2, 0.01, 0.01], direction: y, amplitude: 2.5, "
                                                   "frequency: {mode: 2, ratio: 0.5}}"), "edge.yaml");
  const ExcitationSection& read = *scene.transient->excitation;
  EXPECT_EQ(*read.point, Vec3(0.2, 0.01, 0.01));
  EXPECT_TRUE(read.face.empty());
  EXPECT_EQ(read.direction, 1);
  EXPECT_EQ(read.amplitude, 2.5);
  EXPECT_EQ(read.mode, 2);
  EXPECT_EQ(read.ratio, 0.5);
  EXPECT_FALSE(read.frequency_hz);
  EXPECT_EQ(read.of, ModeOf::uncracked);  // no crack
  EXPECT_EQ(scene.transient->probes[1].name, "mid");
  EXPECT_EQ(scene.transient->probes[1].point, Vec3(0.1, 0.01, 0.01));
  EXPECT_FALSE(scene.transient->probes[1].side);
}

TEST(SceneEdges, FoldersAreNotFiles) {
  const std::string folder = std::filesystem::temp_directory_path().string();
  try {
    load_scene(folder);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), folder + ": expected a readable scene file, got a directory");
  }
  EXPECT_EQ(error_of("mesh: {gmsh: " + folder + "}\nmaterial: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"),
            "edge.yaml:1: mesh.gmsh: expected a Gmsh mesh file, got a directory, '" + folder + "'");
}

// Keys read through the table's bindings alone: a coordinate range (an initial field's, a material's
// region) must increase, `history.samples_per_period: all` stands for every step (0), and the
// values land in their fields.
TEST(SceneEdges, RangesIncreaseAndAWordStandsForItsValue) {
  const std::string body = "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [8, 1, 1], order: 1}\n"
                           "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n";
  const std::string transient = "transient:\n  periods: 2\n  excitation: {face: x+, amplitude: 1.0, frequency: 100.0}\n";
  const Scene scene = parse_scene(body + transient + "  initial:\n    - {velocity: [0, 0, 1], x: [0.05, 0.1], z: [0, 0.01]}\n"
                                  "  history: {samples_per_period: all}\n", "edge.yaml");
  ASSERT_EQ(scene.transient->initial.size(), 1u);
  const InitialSection& field = scene.transient->initial[0];
  ASSERT_TRUE(field.range[0] && field.range[2]);
  EXPECT_FALSE(field.range[1]);
  EXPECT_EQ((*field.range[0])[0], 0.05);
  EXPECT_EQ((*field.range[0])[1], 0.1);
  EXPECT_EQ((*field.range[2])[1], 0.01);
  EXPECT_EQ(scene.transient->history_samples_per_period, 0);
  EXPECT_EQ(parse_scene(body + transient, "edge.yaml").transient->history_samples_per_period, 64);
  EXPECT_EQ(parse_scene(body + transient + "  history: {samples_per_period: 16}\n", "edge.yaml")
                .transient->history_samples_per_period, 16);
  EXPECT_EQ(error_of(body + transient + "  initial:\n    - {velocity: [0, 0, 1], y: [0.02, 0.01]}\n"),
            "edge.yaml:8: transient.initial[0].y: expected [low, high] with low < high, got [0.02, 0.01]");
  EXPECT_EQ(error_of(body + transient + "  initial:\n    - {x: [0.1, 0.1]}\n"),
            "edge.yaml:8: transient.initial[0].x: expected [low, high] with low < high, got [0.1, 0.1]");
  const std::string plies = "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [8, 1, 2], order: 1}\nmaterials:\n"
                            "  - {name: a, isotropic: {E: 210.0e9, nu: 0.3}, rho: 7850.0, region: {z: [0.0, 0.005]}}\n"
                            "  - {name: b, isotropic: {E: 70.0e9, nu: 0.3}, rho: 2700.0, region: {z: ";
  const Scene layered = parse_scene(plies + "[0.005, 0.01]}}\n", "edge.yaml");
  ASSERT_EQ(layered.materials.size(), 2u);
  ASSERT_TRUE(layered.materials[1].region.range[2]);
  EXPECT_EQ((*layered.materials[1].region.range[2])[0], 0.005);
  EXPECT_FALSE(layered.materials[1].region.range[0]);
  EXPECT_EQ(error_of(plies + "[0.01, 0.005]}}\n"),
            "edge.yaml:5: materials[1].region.z: expected [low, high] with low < high, got [0.01, 0.005]");
}

TEST(SceneEdges, NestedAliasesAreBounded) {
  std::string text = "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [8, 1, 1], order: 1}\n"
                     "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
                     "transient:\n  initial:\n    - {velocity: &v0 [1, 1, 1]}\n";
  // 9 levels of 9 aliases: 9^9 lists once expanded, in 8 lines, under transient.initial[0].x.
  text += "    - x: [&l1 [*v0, *v0, *v0, *v0, *v0, *v0, *v0, *v0, *v0]";
  for (int level = 2; level <= 9; ++level) {
    const std::string alias = "*l" + std::to_string(level - 1);
    text += ", &l" + std::to_string(level) + " [";
    for (int i = 0; i < 9; ++i) text += (i ? ", " : "") + alias;
    text += "]";
  }
  text += "]\n";
  EXPECT_EQ(error_of(text),
            "edge.yaml:5: transient.initial[1]: expected at most 1000000 YAML nodes with aliases expanded, got "
            "more (nested aliases?)");
}

}  // namespace
}  // namespace crackle::scene
