// The generic parameter table and validator, on a small table of their own.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "scene/schema.hpp"

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
