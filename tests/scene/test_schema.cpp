// The generic parameter table and validator, on a small table of their own.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "scene/schema.hpp"

#include <optional>
#include <string>
#include <vector>

namespace crackle::scene {
namespace {

Param toy_table() {
  return map_of(
      "", "Toy.",
      {
          map_of("run", "Run settings.",
                 {
                     boolean("verbose", "Print more.").defaults_to("false"),
                     number("tolerance", "Relative tolerance.").above(0).at_most(1).defaults_to("1e-8"),
                     integer("steps", "Time steps.").at_least(0).required(),
                     number("weights", "Weights.").at_least(0).list(2, 4),
                 }),
      });
}

std::string error_of(const std::string& text) {
  try {
    validate(toy_table(), parse_yaml(text, "toy.yaml"), "toy.yaml");
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(Schema, FillsDefaultsAndReadsBooleans) {
  const Values values = validate(toy_table(), parse_yaml("run: {steps: 5, verbose: true}", "t"), "t");
  EXPECT_TRUE(values.flag("run.verbose"));
  EXPECT_EQ(values.number("run.tolerance"), 1e-8);
  EXPECT_EQ(values.integer("run.steps"), 5);
  EXPECT_FALSE(values.has("run.weights"));
  EXPECT_EQ(values.line("run.steps"), 1);
  EXPECT_EQ(values.line("run.tolerance"), 1);  // defaulted: the line of the enclosing key
}

TEST(Schema, Messages) {
  EXPECT_EQ(error_of("run: {steps: 5, verbose: yes}"),
            "toy.yaml:1: run.verbose: expected true or false, got 'yes'");
  EXPECT_EQ(error_of("run: {steps: 5, verbose: \"true\"}"),
            "toy.yaml:1: run.verbose: expected true or false, got 'true'");
  EXPECT_EQ(error_of("run: {steps: 5, tolerance: 2}"),
            "toy.yaml:1: run.tolerance: expected a number in (0, 1], got 2");
  EXPECT_EQ(error_of("run: {steps: -1}"), "toy.yaml:1: run.steps: expected a non-negative integer, got -1");
  EXPECT_EQ(error_of("run: {steps: 1, weights: [1]}"),
            "toy.yaml:1: run.weights: expected a list of 2 to 4 non-negative numbers, got a list of 1 entry");
  EXPECT_EQ(error_of("run:\n  steps: 1\n  weights:\n    - 1\n    - -2\n"),
            "toy.yaml:5: run.weights[1]: expected a non-negative number, got -2");
  EXPECT_EQ(
      error_of("run:\n  step: 1\n"),
      "toy.yaml:2: run.step: expected one of verbose, tolerance, steps, weights, got unknown key 'step' "
      "(did you mean 'steps'?)");
  EXPECT_EQ(error_of("run: {}\n"), "toy.yaml:1: run.steps: expected a non-negative integer, got nothing");
}

// A declaration bound to a struct field (Param::to) is read by read_bound: scalars, an enum through
// its words, a list of them, a number given as its auto word (left at the struct's default), a
// nested map flattened into the same struct, and fields of another struct left alone.
enum class Shape { round, square };
inline constexpr Words<Shape, 2> kShapeWords{{{"round", Shape::round}, {"square", Shape::square}}};
struct Section {
  int steps = 0;
  double tolerance = 0.0;
  std::optional<double> limit;
  bool verbose = false;
  Shape shape = Shape::round;
  std::vector<Shape> shapes;
  std::string name = "unset";
  int depth = -1;
};
struct Other {
  int depth = -1;
};

TEST(Schema, BoundDeclarationsFillTheirStructFields) {
  const Param table = map_of("", "Bound.", {
      map_of("run", "Run settings.", {
          integer("steps", "Time steps.").at_least(0).required().to(&Section::steps),
          number("tolerance", "Tolerance.").above(0).defaults_to("1e-8").to(&Section::tolerance),
          number("limit", "Limit; auto: none.").above(0).or_word("auto").defaults_to("auto").to(&Section::limit),
          boolean("verbose", "Print more.").defaults_to("false").to(&Section::verbose),
          choice("shape", "Shape.", kShapeWords).defaults_to("round").to(&Section::shape),
          choice("shapes", "Shapes.", kShapeWords).list(1, 2).to(&Section::shapes),
          text("name", "Name.").to(&Section::name),
          map_of("inner", "Nested.", {
              integer("depth", "Depth.").defaults_to("3").to(&Section::depth),
              integer("other", "Of another struct.").defaults_to("7").to(&Other::depth),
          }),
      }),
  });
  const Values values = validate(
      table, parse_yaml("run: {steps: 5, verbose: true, shape: square, shapes: [square, round]}", "t"), "t");
  Section section;
  read_bound(*table.child("run"), values, "run", section);
  EXPECT_EQ(section.steps, 5);
  EXPECT_EQ(section.tolerance, 1e-8);
  EXPECT_FALSE(section.limit);  // auto
  EXPECT_TRUE(section.verbose);
  EXPECT_EQ(section.shape, Shape::square);
  EXPECT_EQ(section.shapes, (std::vector<Shape>{Shape::square, Shape::round}));
  EXPECT_EQ(section.name, "unset");  // not in the document, no default
  EXPECT_EQ(section.depth, 3);
  Other other;
  read_bound(*table.child("run"), values, "run", other);
  EXPECT_EQ(other.depth, 7);
  const Values limited = validate(table, parse_yaml("run: {steps: 1, limit: 0.5, shapes: [round], name: a}", "t"), "t");
  read_bound(*table.child("run"), limited, "run", section);
  EXPECT_EQ(section.limit, 0.5);
  EXPECT_EQ(section.name, "a");
}

// exactly_one_of: a map (or each map of a list) gives exactly one of a group of keys.
TEST(Schema, ExactlyOneOfAGroupOfKeys) {
  const Param table = map_of("", "Groups.", {
      map_of("load", "A load.", {
          text("face", "Face."), text("group", "Group."), number("point", "Point.").list(3),
          number("amplitude", "Amplitude.").defaults_to("1"),
      }).exactly_one_of({"face", "group", "point"}).optional_section(),
      list_of("probes", "Probes.", {number("point", "Point.").list(3), number("gap", "Gap.").list(3)})
          .exactly_one_of({"point", "gap"}).defaults_to("[]"),
  });
  const auto error = [&](const std::string& text) {
    try {
      validate(table, parse_yaml(text, "g.yaml"), "g.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("load: {face: x+}\nprobes: [{point: [0, 0, 0]}]\n"), "");
  EXPECT_EQ(error("load: {amplitude: 2}\n"), "g.yaml:1: load: expected exactly one of face, group, point, got none");
  EXPECT_EQ(error("load: {face: x+, group: g, point: [0, 0, 0]}\n"),
            "g.yaml:1: load: expected exactly one of face, group, point, got face, group and point");
  EXPECT_EQ(error("probes:\n  - {point: [0, 0, 0]}\n  - {point: [0, 0, 0], gap: [0, 0, 0]}\n"),
            "g.yaml:3: probes[1]: expected exactly one of point, gap, got point and gap");
  EXPECT_EQ(error("probes: []\n"), "");  // an absent optional section is not checked
}

TEST(Schema, OverrideReplacesAValueWithoutALine) {
  YAML::Node document = parse_yaml("run:\n  steps: 1\n", "toy.yaml");
  apply_override(document, "run.tolerance", "0.5", "toy.yaml");
  apply_override(document, "run.steps", "4", "toy.yaml");
  const Values values = validate(toy_table(), document, "toy.yaml");
  EXPECT_EQ(values.number("run.tolerance"), 0.5);
  EXPECT_EQ(values.integer("run.steps"), 4);
  EXPECT_EQ(values.line("run.steps"), -1);
}

TEST(Schema, MarkdownRowPerParameter) {
  const std::string table = markdown_table(toy_table());
  EXPECT_NE(table.find("| `run.verbose` | bool | true, false | `false` |  | Print more. |"),
            std::string::npos);
  EXPECT_NE(table.find("| `run.tolerance` | number | (0, 1] | `1e-8` |  | Relative tolerance. |"),
            std::string::npos);
  EXPECT_NE(table.find("| `run.steps` | integer | >= 0 | required |  | Time steps. |"), std::string::npos);
  EXPECT_NE(table.find("| `run.weights` | list of 2 to 4 numbers | >= 0 |  |  | Weights. |"),
            std::string::npos);
}

}  // namespace
}  // namespace crackle::scene
