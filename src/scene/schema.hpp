#pragma once
/// \file The parameter table: a tree of declared parameters, the generic validator that checks a
/// YAML document against it, and the markdown reference generated from it.
///
/// STYLE.md: each input parameter is declared once (name, type, range, default, unit, doc). A
/// section is a map of parameters; a parameter is a map, a list of maps, or a scalar (number,
/// integer, choice, boolean), the scalars optionally as a list of fixed or bounded length.
#include <yaml-cpp/yaml.h>

#include <array>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <typeindex>
#include <vector>

#include "core/types.hpp"
#include "core/words.hpp"

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

/// The value at `path` as a field of type T (defined below Values); `choice_value` converts a
/// choice's word to its enum value.
template <class T>
T bound_value(const Values& values, const std::string& path, const std::function<int(const std::string&)>& choice_value);

/// The field of a section struct that a declaration is bound to (Param::to): read_bound() assigns
/// the validated value to it, so a key is spelled in the table and the struct only.
struct Binding {
  std::type_index section = typeid(void);  ///< the struct the field belongs to
  std::function<void(const Values& values, const std::string& path, void* section)> assign;
  /// A number's field set to the value its or_word() word stands for (an arithmetic field only).
  std::function<void(double value, void* section)> assign_word;
};

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
  bool is_increasing = false;          ///< list of numbers: each entry above the one before
  std::string length_of;               ///< list of scalars: as many entries as this sibling list
  std::string default_text;            ///< YAML text of the default; a description with a rule
  DefaultRule default_rule;            ///< computes the default when set
  std::vector<Param> children;         ///< keys of a map, keys of each entry of a list
  std::string word_alternative;        ///< number: a word also accepted instead, e.g. "auto"
  std::optional<double> word_value;    ///< the value that word stands for in the bound field (none: the default)
  std::string scalar_child;            ///< map: a scalar given for the map stands for this child
  /// map, list of maps: groups of keys of which each map must give exactly one
  std::vector<std::vector<std::string>> exclusive_keys;
  /// choice declared with Words: its word's enum value (as int)
  std::function<int(const std::string&)> choice_value;
  Binding binding;  ///< the struct field the value goes to, if bound

  Param& required();
  Param& with_unit(std::string unit_text);
  Param& above(double bound);     ///< value > bound
  Param& at_least(double bound);  ///< value >= bound
  Param& below(double bound);     ///< value < bound
  Param& at_most(double bound);   ///< value <= bound
  Param& list(int length);        ///< a list of exactly `length` scalars
  Param& list(int min_entries, int max_entries);
  Param& distinct();
  /// A list of numbers whose entries increase strictly: a range `[low, high]` with low < high.
  Param& increasing();
  Param& same_length_as(std::string sibling);
  Param& defaults_to(std::string yaml);
  Param& defaults_to(std::string description, DefaultRule rule);
  /// A map that stays absent when not given, even without required keys (has() is false then).
  Param& optional_section();
  /// A number that may also be given as this word (read with Values::is_word).
  Param& or_word(std::string word);
  /// The same, the word standing for `stands_for` in the bound field (`samples_per_period: all` for 0).
  Param& or_word(std::string word, double stands_for);
  /// A map that may also be given as a plain value, meaning `{child: value}`
  /// (`frequency: 850` for `frequency: {hz: 850}`).
  Param& or_scalar_for(std::string child);
  /// A map (or each map of a list) that must give exactly one of `keys` (its children):
  /// `path: expected exactly one of face, group, point, got none` otherwise.
  Param& exactly_one_of(std::vector<std::string> keys);
  /// Binds a scalar (or a list of scalars) to `field` of the section struct S: read_bound(values,
  /// path, section) assigns it where the document has the value (a number given as its or_word()
  /// word is left at the struct's default, auto, or set to the value the word stands for). A choice
  /// declared with Words goes to its enum.
  template <class S, class T>
  Param& to(T S::*field) {
    binding.section = typeid(S);
    binding.assign = [field, convert = choice_value](const Values& values, const std::string& path, void* section) {
      static_cast<S*>(section)->*field = bound_value<T>(values, path, convert);
    };
    if constexpr (std::is_arithmetic_v<T>) {
      binding.assign_word = [field](double value, void* section) {
        static_cast<S*>(section)->*field = static_cast<T>(value);
      };
    }
    return *this;
  }

  /// Binds a scalar list to entry `index` of the std::array `field` of S: the axes' keys of a map
  /// (`crack.region.y` to `region[kY]`, `mesh.box.lines.x` to `extra_lines[kX]`).
  template <class S, class A>
  Param& to(A S::*field, int index) {
    binding.section = typeid(S);
    binding.assign = [field, index, convert = choice_value](const Values& values, const std::string& path, void* section) {
      (static_cast<S*>(section)->*field).at(static_cast<std::size_t>(index)) =
          bound_value<typename A::value_type>(values, path, convert);
    };
    return *this;
  }

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
/// A choice whose words stand for an enum's values (core/words.hpp): read with Values::choice.
template <class E, std::size_t N>
Param choice(std::string name, std::string doc, const Words<E, N>& words) {
  Param param = choice(std::move(name), std::move(doc), texts_of(words));
  param.choice_value = [words](const std::string& text) { return static_cast<int>(parse_word(words, text, "choice")); };
  return param;
}
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
  /// The value of a choice declared with `words` (validated, so every word has one).
  template <class E, std::size_t N>
  E choice(const std::string& path, const Words<E, N>& words) const {
    return parse_word(words, word(path), path);
  }
  /// The values of a list of choices declared with `words`.
  template <class E, std::size_t N>
  std::vector<E> choices(const std::string& path, const Words<E, N>& list_words) const {
    std::vector<E> values;
    for (const std::string& text : words(path)) values.push_back(parse_word(list_words, text, path));
    return values;
  }
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

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
template <class T>
struct IsArray : std::false_type {};
template <class T, std::size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};

template <class T>
T bound_value(const Values& values, const std::string& path, const std::function<int(const std::string&)>& choice_value) {
  if constexpr (IsOptional<T>::value) {
    return bound_value<typename T::value_type>(values, path, choice_value);
  } else if constexpr (std::is_enum_v<T>) {
    return static_cast<T>(choice_value(values.word(path)));
  } else if constexpr (std::is_same_v<T, int>) {  // an integer, or a choice of ints (the axes)
    return choice_value ? choice_value(values.word(path)) : values.integer(path);
  } else if constexpr (std::is_same_v<T, double>) {
    return values.number(path);
  } else if constexpr (std::is_same_v<T, bool>) {
    return values.flag(path);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return values.word(path);
  } else if constexpr (std::is_same_v<T, Vec3>) {
    const std::vector<double>& numbers = values.numbers(path);
    return Vec3(numbers.at(0), numbers.at(1), numbers.at(2));
  } else if constexpr (std::is_same_v<T, std::vector<double>>) {
    return values.numbers(path);
  } else if constexpr (IsArray<T>::value) {  // a list of numbers of the array's length (the table's list(n))
    const std::vector<double>& numbers = values.numbers(path);
    T array{};
    for (std::size_t i = 0; i < array.size(); ++i) array[i] = static_cast<typename T::value_type>(numbers.at(i));
    return array;
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    return values.words(path);
  } else {
    static_assert(IsVector<T>::value, "a field type read_bound can fill");
    T list;  // a list of choices: enums or ints
    for (const std::string& word : values.words(path)) list.push_back(static_cast<typename T::value_type>(choice_value(word)));
    return list;
  }
}

/// Assigns every value below `path` (the keys of `param`, a map, and of its nested maps) whose
/// declaration is bound to a field of `section_type` and that the document has.
void assign_bound(const Param& param, const Values& values, const std::string& path, std::type_index section_type,
                  void* section);

/// Fills the fields of `section` bound in the table below `path` (the table's map `param`).
template <class S>
void read_bound(const Param& param, const Values& values, const std::string& path, S& section) {
  assign_bound(param, values, path, typeid(S), &section);
}

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
