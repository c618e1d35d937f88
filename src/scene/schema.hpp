#pragma once
/// \file The parameter table: a tree of declared parameters, the generic validator that checks a
/// YAML document against it, and the markdown reference generated from it.
///
/// STYLE.md: each input parameter is declared once (name, type, range, default, unit, doc). A
/// section is a map of parameters; a parameter is a map, a list of maps, or a scalar (number,
/// integer, choice, boolean), the scalars optionally as a list of fixed or bounded length.
#include <yaml-cpp/yaml.h>

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace crackle::scene {

class Values;

/// What a parameter holds.
enum class Kind {
  map,      ///< the keys declared as children
  list,     ///< a list of maps, each with the keys declared as children
  number,   ///< a finite double (YAML integers accepted)
  integer,  ///< an integer
  choice,   ///< one of a fixed set of words
  boolean,  ///< true or false
  text,     ///< any word or quoted string (a file name, a group name)
};

/// Computes a default (YAML text) from the values validated so far; `parent` is the path of the
/// enclosing map, e.g. `boundary[0]`.
using DefaultRule = std::function<std::string(const Values& values, const std::string& parent)>;

/// One declared parameter. Built by the functions below and refined by chained modifiers:
/// `number("E", "Young's modulus.").with_unit("Pa").above(0).required()`.
struct Param {
  std::string name;
  Kind kind = Kind::map;
  std::string doc;
  std::string unit;
  bool is_required = false;
  bool is_one_of = false;  ///< map: exactly one of the children must be present
  bool is_optional_section = false;  ///< map: absent unless given (no defaults filled in when absent)
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false, max_open = false;
  std::vector<std::string> choices;
  int min_length = 0, max_length = 0;  ///< a list of scalars when max_length > 0
  bool is_distinct = false;            ///< list of scalars: no entry twice
  std::string length_of;               ///< list of scalars: as many entries as this sibling list
  std::string default_text;            ///< YAML text of the default; a description with a rule
  DefaultRule default_rule;            ///< computes the default when set
  std::vector<Param> children;         ///< keys of a map, keys of each entry of a list
  std::string word_alternative;        ///< number: a word also accepted instead, e.g. "auto"
  std::string scalar_child;            ///< map: a scalar given for the map stands for this child

  Param& required();
  Param& with_unit(std::string unit_text);
  Param& above(double bound);     ///< value > bound
  Param& at_least(double bound);  ///< value >= bound
  Param& below(double bound);     ///< value < bound
  Param& at_most(double bound);   ///< value <= bound
  Param& list(int length);        ///< a list of exactly `length` scalars
  Param& list(int min_entries, int max_entries);
  Param& distinct();
  Param& same_length_as(std::string sibling);
  Param& defaults_to(std::string yaml);
  Param& defaults_to(std::string description, DefaultRule rule);
  /// A map that stays absent when not given, even without required keys (has() is false then).
  Param& optional_section();
  /// A number that may also be given as this word (read with Values::is_word).
  Param& or_word(std::string word);
  /// A map that may also be given as a plain value, meaning `{child: value}`
  /// (`frequency: 850` for `frequency: {hz: 850}`).
  Param& or_scalar_for(std::string child);

  bool is_list_of_scalars() const { return max_length > 0; }
  /// The child with this name, or nullptr.
  const Param* child(const std::string& child_name) const;
};

Param map_of(std::string name, std::string doc, std::vector<Param> children);
/// A map of alternatives: exactly one of `children` must be given.
Param one_of(std::string name, std::string doc, std::vector<Param> children);
/// A list of maps, each with the keys `entry_keys`.
Param list_of(std::string name, std::string doc, std::vector<Param> entry_keys);
Param number(std::string name, std::string doc);
Param integer(std::string name, std::string doc);
Param choice(std::string name, std::string doc, std::vector<std::string> choices);
Param boolean(std::string name, std::string doc);
/// A free text value: a file name or a mesh group name.
Param text(std::string name, std::string doc);

/// One validated value. Scalars are lists of one entry.
struct Value {
  Kind kind = Kind::map;
  std::vector<double> numbers;     ///< number, integer, boolean (0 or 1)
  std::vector<std::string> words;  ///< choice, text
  int count = 0;                   ///< entries of a list of maps
  int line = -1;                   ///< 1-based line in the file (of the parent when defaulted); -1 unknown
};

/// The validated document with every default filled in, addressed by key path: `material.E`,
/// `boundary[0].face`, `mesh.box.cells[1]`. Getters expect a path the table declares and the
/// document has (see has()).
class Values {
 public:
  explicit Values(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  bool has(const std::string& path) const { return entries_.count(path) > 0; }
  double number(const std::string& path) const { return entries_.at(path).numbers.at(0); }
  int integer(const std::string& path) const { return static_cast<int>(number(path)); }
  bool flag(const std::string& path) const { return number(path) != 0.0; }
  /// True when a number declared with or_word() was given as that word.
  bool is_word(const std::string& path) const { return has(path) && !entries_.at(path).words.empty(); }
  const std::string& word(const std::string& path) const { return entries_.at(path).words.at(0); }
  const std::vector<double>& numbers(const std::string& path) const { return entries_.at(path).numbers; }
  const std::vector<std::string>& words(const std::string& path) const { return entries_.at(path).words; }
  /// Entries of a list of maps.
  int count(const std::string& path) const { return entries_.at(path).count; }

  /// Line of the key, or of its nearest ancestor in the document; -1 if unknown.
  int line(const std::string& path) const;
  /// Throws InputError `file:line: path: expected ..., got ...`.
  [[noreturn]] void fail(const std::string& path, const std::string& expected, const std::string& got) const;
  /// Throws InputError `file:line: message`, with the line of `path`.
  [[noreturn]] void fail(const std::string& path, const std::string& message) const;

  void set(const std::string& path, Value value) { entries_[path] = std::move(value); }

 private:
  std::string file_;
  std::map<std::string, Value> entries_;
};

/// Throws InputError `file:line: path: expected ..., got ...`; the line is left out when <= 0
/// and the path when empty.
[[noreturn]] void fail(const std::string& file, int line, const std::string& path,
                       const std::string& expected, const std::string& got);

/// Parses YAML text; a syntax error becomes InputError `file:line: expected valid YAML, got ...`.
YAML::Node parse_yaml(const std::string& text, const std::string& file);

/// Checks `document` against the table `root`: types, ranges, required and unknown keys (with a
/// "did you mean" suggestion), and fills in every default. Throws InputError on the first problem.
Values validate(const Param& root, const YAML::Node& document, const std::string& file);

/// Sets the value (YAML text) at a dotted key path such as `crack.region.z` or `boundary[0].value`,
/// creating missing maps, for a parameter study to re-validate. The new nodes carry no line, so
/// messages about them name the path only.
void apply_override(YAML::Node& document, const std::string& path, const std::string& value,
                    const std::string& file);

/// Markdown table (key path, type, range, default, unit, doc) of every parameter below `root`.
std::string markdown_table(const Param& root);

/// Expected-value phrase of a parameter, as messages show it: "a positive number".
std::string describe(const Param& param);

}  // namespace crackle::scene
