#include "scene/schema.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>

#include "core/errors.hpp"
#include "scene/yaml_text.hpp"

namespace crackle::scene {

// ---- declaring parameters

Param& Param::required() {
  is_required = true;
  return *this;
}
Param& Param::with_unit(std::string unit_text) {
  unit = std::move(unit_text);
  return *this;
}
Param& Param::above(double bound) {
  min = bound;
  min_open = true;
  return *this;
}
Param& Param::at_least(double bound) {
  min = bound;
  min_open = false;
  return *this;
}
Param& Param::below(double bound) {
  max = bound;
  max_open = true;
  return *this;
}
Param& Param::at_most(double bound) {
  max = bound;
  max_open = false;
  return *this;
}
Param& Param::list(int length) { return list(length, length); }
Param& Param::list(int min_entries, int max_entries) {
  min_length = min_entries;
  max_length = max_entries;
  return *this;
}
Param& Param::distinct() {
  is_distinct = true;
  return *this;
}
Param& Param::increasing() {
  is_increasing = true;
  return *this;
}
Param& Param::same_length_as(std::string sibling) {
  length_of = std::move(sibling);
  return *this;
}
Param& Param::defaults_to(std::string yaml) {
  default_text = std::move(yaml);
  return *this;
}
Param& Param::defaults_to(std::string description, DefaultRule rule) {
  default_text = std::move(description);
  default_rule = std::move(rule);
  return *this;
}

Param& Param::optional_section() {
  is_optional_section = true;
  return *this;
}

Param& Param::or_word(std::string word) {
  word_alternative = std::move(word);
  return *this;
}
Param& Param::or_word(std::string word, double stands_for) {
  word_value = stands_for;
  return or_word(std::move(word));
}

Param& Param::or_scalar_for(std::string child) {
  scalar_child = std::move(child);
  return *this;
}

Param& Param::exactly_one_of(std::vector<std::string> keys) {
  exclusive_keys.push_back(std::move(keys));
  return *this;
}

void assign_bound(const Param& param, const Values& values, const std::string& path, std::type_index section_type,
                  void* section) {
  for (const Param& c : param.children) {
    const std::string key = path.empty() ? c.name : path + "." + c.name;
    if (c.kind == Kind::map) {
      assign_bound(c, values, key, section_type, section);
    } else if (c.binding.assign && c.binding.section == section_type && values.has(key)) {
      const bool word = (c.kind == Kind::number || c.kind == Kind::integer) && values.is_word(key);
      if (!word) {
        c.binding.assign(values, key, section);
      } else if (c.word_value && c.binding.assign_word) {
        c.binding.assign_word(*c.word_value, section);  // the value the word stands for
      }  // else the word (auto): the struct's default
    }
  }
}

const Param* Param::child(const std::string& child_name) const {
  for (const Param& c : children)
    if (c.name == child_name) return &c;
  return nullptr;
}

namespace {

Param make(std::string name, Kind kind, std::string doc) {
  Param param;
  param.name = std::move(name);
  param.kind = kind;
  param.doc = std::move(doc);
  return param;
}

}  // namespace

Param map_of(std::string name, std::string doc, std::vector<Param> children) {
  Param param = make(std::move(name), Kind::map, std::move(doc));
  param.children = std::move(children);
  return param;
}
Param one_of(std::string name, std::string doc, std::vector<Param> children) {
  Param param = map_of(std::move(name), std::move(doc), std::move(children));
  param.is_one_of = true;
  return param;
}
Param list_of(std::string name, std::string doc, std::vector<Param> entry_keys) {
  Param param = make(std::move(name), Kind::list, std::move(doc));
  param.children = std::move(entry_keys);
  return param;
}
Param number(std::string name, std::string doc) {
  return make(std::move(name), Kind::number, std::move(doc));
}
Param integer(std::string name, std::string doc) {
  return make(std::move(name), Kind::integer, std::move(doc));
}
Param choice(std::string name, std::string doc, std::vector<std::string> choices) {
  Param param = make(std::move(name), Kind::choice, std::move(doc));
  param.choices = std::move(choices);
  return param;
}
Param boolean(std::string name, std::string doc) {
  return make(std::move(name), Kind::boolean, std::move(doc));
}
Param text(std::string name, std::string doc) { return make(std::move(name), Kind::text, std::move(doc)); }

// ---- phrases for messages and docs

namespace {


std::vector<std::string> child_names(const Param& param) {
  std::vector<std::string> names;
  for (const Param& c : param.children) names.push_back(c.name);
  return names;
}

std::string child_path(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}

std::string entry_path(const std::string& list, std::size_t index) {
  return list + "[" + std::to_string(index) + "]";
}

std::string parent_of(const std::string& path) {
  const auto cut = path.find_last_of(".[");
  return cut == std::string::npos ? "" : path.substr(0, cut);
}

bool has_lower_bound(const Param& p) { return p.min > -std::numeric_limits<double>::infinity(); }
bool has_upper_bound(const Param& p) { return p.max < std::numeric_limits<double>::infinity(); }

/// "positive", "non-negative" or "" for the lower bounds that have a word.
std::string sign_word(const Param& p) {
  if (has_upper_bound(p) || !has_lower_bound(p)) return "";
  const bool integer = p.kind == Kind::integer;
  if (p.min == 0 && p.min_open) return "positive";
  if (p.min == 0 && !p.min_open) return "non-negative";
  if (integer && p.min == 1 && !p.min_open) return "positive";
  return "";
}

/// Range of a number or integer as the docs show it: "> 0", "(-1, 0.5)", "1..4".
std::string range_text(const Param& p) {
  const bool low = has_lower_bound(p), high = has_upper_bound(p);
  if (low && high) {
    if (p.kind == Kind::integer && !p.min_open && !p.max_open)
      return format_number(p.min) + ".." + format_number(p.max);
    return (p.min_open ? "(" : "[") + format_number(p.min) + ", " + format_number(p.max) +
           (p.max_open ? ")" : "]");
  }
  if (low) return (p.min_open ? "> " : ">= ") + format_number(p.min);
  if (high) return (p.max_open ? "< " : "<= ") + format_number(p.max);
  return "";
}

/// "a positive number", "an integer in 1..4", "one of x, y, z"; plural: "positive numbers".
std::string scalar_phrase(const Param& p, bool plural) {
  switch (p.kind) {
    case Kind::choice:
      return (plural ? "entries from " : "one of ") + join(p.choices);
    case Kind::boolean:
      return plural ? "booleans" : "true or false";
    case Kind::text:
      return plural ? "texts" : "a text";
    default:
      break;
  }
  const std::string noun = std::string(p.kind == Kind::integer ? "integer" : "number") + (plural ? "s" : "");
  const std::string sign = sign_word(p);
  std::string phrase = sign.empty() ? noun : sign + " " + noun;
  if (sign.empty()) {
    const std::string range = range_text(p);
    if (range.find("..") != std::string::npos || range.find(',') != std::string::npos)
      phrase += " in " + range;
    else if (!range.empty())
      phrase += " " + range;
  }
  if (plural) return phrase;
  phrase = (std::string("aeiou").find(phrase[0]) != std::string::npos ? "an " : "a ") + phrase;
  if (!p.word_alternative.empty()) phrase += " or " + p.word_alternative;
  return phrase;
}

std::string count_text(const Param& p) {
  if (p.min_length == p.max_length) return std::to_string(p.min_length);
  return std::to_string(p.min_length) + " to " + std::to_string(p.max_length);
}

/// Expected-value phrase of a list of scalars with `entries` entries.
std::string list_phrase(const Param& p, const std::string& entries) {
  std::string phrase =
      "a list of " + entries + " " + (p.is_distinct ? "distinct " : "") + scalar_phrase(p, true);
  if (!p.length_of.empty()) phrase += ", one per entry of " + p.length_of;
  return phrase;
}


// ---- reading YAML scalars

// ---- the validator

bool has_required_child(const Param& param) {
  return std::any_of(param.children.begin(), param.children.end(),
                     [](const Param& c) { return c.is_required; });
}

class Validator {
 public:
  explicit Validator(Values& values) : values_(values) {}

  /// Checks `node` (undefined when the key is absent) against `param`. `line` is the line of the
  /// key (of the item in a list), or of the enclosing key when the key is absent or defaulted.
  void visit(const Param& param, const YAML::Node& node, const std::string& path, int line, bool defaulted) {
    if (!node.IsDefined()) {
      visit_absent(param, path, line);
      return;
    }
    switch (param.kind) {
      case Kind::map:
        if (!param.scalar_child.empty() && node.IsScalar()) {
          YAML::Node expanded(YAML::NodeType::Map);
          expanded[param.scalar_child] = node;
          // The key made up here has no line: messages about it take the value's.
          visit_map(param, expanded, path, line, defaulted, mark_line(node));
        } else {
          visit_map(param, node, path, line, defaulted);
        }
        break;
      case Kind::list:
        visit_list(param, node, path, line, defaulted);
        break;
      default:
        visit_scalars(param, node, path, line, defaulted);
    }
  }

 private:
  [[noreturn]] void fail(const std::string& path, int line, const std::string& expected,
                         const std::string& got) {
    scene::fail(values_.file(), line, path, expected, got);
  }

  void visit_absent(const Param& param, const std::string& path, int parent_line) {
    if (param.default_rule) {
      visit(param, YAML::Load(param.default_rule(values_, parent_of(path))), path, parent_line, true);
    } else if (!param.default_text.empty()) {
      visit(param, YAML::Load(param.default_text), path, parent_line, true);
    } else if (param.is_required) {
      fail(path, parent_line, describe(param), "nothing");
    } else if (param.kind == Kind::map && !param.is_one_of && !param.is_optional_section &&
               !has_required_child(param)) {
      // An absent optional section without required keys still provides its defaults.
      visit_children(param, YAML::Node(YAML::NodeType::Map), path, parent_line, true);
    }
  }

  /// `unmarked_key_line`: the line of keys that carry none (a map expanded from a scalar).
  void visit_children(const Param& param, const YAML::Node& node, const std::string& path, int line,
                      bool defaulted, int unmarked_key_line = -1) {
    std::map<std::string, int> key_lines;
    for (const auto& entry : node) {
      const int key_line = mark_line(entry.first);
      key_lines[entry.first.Scalar()] = defaulted ? line : key_line > 0 ? key_line : unmarked_key_line;
    }
    for (const Param& c : param.children) {
      const bool present = node[c.name].IsDefined();
      if (param.is_one_of && !present) continue;
      visit(c, node[c.name], child_path(path, c.name), present ? key_lines[c.name] : line, defaulted);
    }
  }

  void visit_map(const Param& param, const YAML::Node& node, const std::string& path, int line,
                 bool defaulted, int unmarked_key_line = -1) {
    const YAML::Node map = node.IsNull() ? YAML::Node(YAML::NodeType::Map) : node;
    if (!map.IsMap()) fail(path, line, describe(param), describe_node(node));
    Value value;
    value.kind = Kind::map;
    value.line = line;
    values_.set(path, value);

    const std::vector<std::string> names = child_names(param);
    std::set<std::string> seen;
    for (const auto& entry : map) {
      const int key_line = defaulted ? line : mark_line(entry.first);
      if (!entry.first.IsScalar()) fail(path, key_line, "keys that are words", describe_node(entry.first));
      const std::string& key = entry.first.Scalar();
      const std::string key_path = child_path(path, key);
      if (!param.child(key)) {
        fail(key_path, key_line, "one of " + join(names),
             std::string("unknown ") + (path.empty() ? "section" : "key") + " '" + key + "'" +
                 suggestion(key, names));
      }
      if (!seen.insert(key).second) fail(key_path, key_line, "each key once", "'" + key + "' again");
    }
    if (param.is_one_of && seen.size() != 1) {
      fail(path, line, describe(param), seen.empty() ? "none" : join({seen.begin(), seen.end()}, " and "));
    }
    for (const std::vector<std::string>& keys : param.exclusive_keys) {
      std::vector<std::string> given;
      for (const std::string& key : keys) {
        if (seen.count(key)) given.push_back(key);
      }
      if (given.size() == 1) continue;
      std::string got = given.empty() ? "none" : given[0];
      for (std::size_t i = 1; i < given.size(); ++i) got += (i + 1 == given.size() ? " and " : ", ") + given[i];
      fail(path, line, "exactly one of " + join(keys), got);
    }
    visit_children(param, map, path, line, defaulted, unmarked_key_line);
  }

  void visit_list(const Param& param, const YAML::Node& node, const std::string& path, int line,
                  bool defaulted) {
    if (!node.IsNull() && !node.IsSequence()) fail(path, line, describe(param), describe_node(node));
    Value value;
    value.kind = Kind::list;
    value.line = line;
    value.count = node.IsNull() ? 0 : static_cast<int>(node.size());
    values_.set(path, value);
    Param entry = map_of("", "", param.children);
    entry.exclusive_keys = param.exclusive_keys;
    for (int i = 0; i < value.count; ++i) {
      const YAML::Node item = node[i];
      visit(entry, item, entry_path(path, i), defaulted ? line : mark_line(item), defaulted);
    }
  }

  void visit_scalars(const Param& param, const YAML::Node& node, const std::string& path, int line,
                     bool defaulted) {
    Value value;
    value.kind = param.kind;
    value.line = line;
    if (!param.is_list_of_scalars()) {
      read_scalar(param, node, path, line, value);
      values_.set(path, value);
      return;
    }
    std::string expected = list_phrase(param, count_text(param));
    bool length_ok = node.IsSequence() && node.size() >= static_cast<std::size_t>(param.min_length) &&
                     node.size() <= static_cast<std::size_t>(param.max_length);
    if (!param.length_of.empty() && node.IsSequence()) {
      const std::size_t wanted = sibling_length(path, param.length_of);
      expected = list_phrase(param, std::to_string(wanted));
      length_ok = node.size() == wanted;
    }
    if (!length_ok) fail(path, line, expected, describe_node(node));
    for (std::size_t i = 0; i < node.size(); ++i) {
      const YAML::Node item = node[i];
      const std::string item_path = entry_path(path, i);
      const int item_line = defaulted ? line : mark_line(item);
      Value single;
      single.kind = param.kind;
      single.line = item_line;
      read_scalar(param, item, item_path, item_line, single);
      if (param.is_distinct) {
        const bool repeated =
            param.kind == Kind::choice || param.kind == Kind::text
                ? std::count(value.words.begin(), value.words.end(), single.words[0]) > 0
                : std::count(value.numbers.begin(), value.numbers.end(), single.numbers[0]) > 0;
        if (repeated) fail(item_path, item_line, "each entry at most once", describe_node(item) + " again");
      }
      value.numbers.insert(value.numbers.end(), single.numbers.begin(), single.numbers.end());
      value.words.insert(value.words.end(), single.words.begin(), single.words.end());
      values_.set(item_path, single);
    }
    if (param.is_increasing) check_increasing(param, value.numbers, path, line);
    values_.set(path, value);
  }

  /// Param::increasing: `[low, high] with low < high` (or the list in increasing order), the list as given.
  void check_increasing(const Param& param, const std::vector<double>& numbers, const std::string& path, int line) {
    for (std::size_t i = 1; i < numbers.size(); ++i) {
      if (numbers[i] > numbers[i - 1]) continue;
      std::string got = "[";
      for (std::size_t k = 0; k < numbers.size(); ++k) got += (k ? ", " : "") + format_number(numbers[k]);
      fail(path, line,
           param.min_length == 2 && param.max_length == 2 ? "[low, high] with low < high"
                                                          : "a list in increasing order",
           got + "]");
    }
  }

  std::size_t sibling_length(const std::string& path, const std::string& sibling) const {
    const std::string sibling_path = child_path(parent_of(path), sibling);
    return std::max(values_.numbers(sibling_path).size(), values_.words(sibling_path).size());
  }

  void read_scalar(const Param& param, const YAML::Node& node, const std::string& path, int line,
                   Value& value) {
    const std::string expected = scalar_phrase(param, false);
    if (!node.IsScalar()) fail(path, line, expected, describe_node(node));
    const std::string& text = node.Scalar();
    double number = 0;
    switch (param.kind) {
      case Kind::number:
        if (!param.word_alternative.empty() && text == param.word_alternative && !is_quoted(node)) {
          value.words.push_back(text);
          break;
        }
        if (is_quoted(node) || !parse_number(text, number)) fail(path, line, expected, describe_node(node));
        check_range(param, number, path, line, format_number(number));
        value.numbers.push_back(number);
        break;
      case Kind::integer: {
        if (!param.word_alternative.empty() && text == param.word_alternative && !is_quoted(node)) {
          value.words.push_back(text);
          break;
        }
        long long whole = 0;
        if (is_quoted(node) || !parse_integer(text, whole)) {
          fail(path, line, expected,
               !is_quoted(node) && parse_number(text, number) ? text : describe_node(node));
        }
        if (whole > std::numeric_limits<int>::max() || whole < std::numeric_limits<int>::min())
          fail(path, line, expected, text);
        check_range(param, static_cast<double>(whole), path, line, std::to_string(whole));
        value.numbers.push_back(static_cast<double>(whole));
        break;
      }
      case Kind::text:
        if (text.empty()) fail(path, line, expected, "an empty text");
        value.words.push_back(text);
        break;
      case Kind::boolean:
        if (is_quoted(node) || (text != "true" && text != "false" && text != "True" && text != "False" &&
                                text != "TRUE" && text != "FALSE")) {
          fail(path, line, expected, describe_node(node));
        }
        value.numbers.push_back(text[0] == 't' || text[0] == 'T' ? 1.0 : 0.0);
        break;
      default:
        if (std::find(param.choices.begin(), param.choices.end(), text) == param.choices.end())
          fail(path, line, expected, describe_node(node) + suggestion(text, param.choices));
        value.words.push_back(text);
    }
  }

  void check_range(const Param& p, double x, const std::string& path, int line, const std::string& got) {
    const bool low_ok = p.min_open ? x > p.min : x >= p.min;
    const bool high_ok = p.max_open ? x < p.max : x <= p.max;
    if (!low_ok || !high_ok) fail(path, line, scalar_phrase(p, false), got);
  }

  Values& values_;
};

// ---- overrides

/// A copy of `node` without marks, so that messages about it name no line.
YAML::Node without_marks(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      YAML::Node copy(node.Scalar());
      copy.SetTag(node.Tag());
      return copy;
    }
    case YAML::NodeType::Sequence: {
      YAML::Node copy(YAML::NodeType::Sequence);
      for (const auto& item : node) copy.push_back(without_marks(item));
      return copy;
    }
    case YAML::NodeType::Map: {
      YAML::Node copy(YAML::NodeType::Map);
      for (const auto& entry : node) copy[without_marks(entry.first)] = without_marks(entry.second);
      return copy;
    }
    default:
      return YAML::Node(YAML::NodeType::Null);
  }
}


}  // namespace

// ---- public functions

std::string describe(const Param& param) {
  switch (param.kind) {
    case Kind::map:
      return (param.is_one_of ? "exactly one of: " : "a map with keys ") + join(child_names(param));
    case Kind::list:
      return "a list of maps with keys " + join(child_names(param));
    default:
      return param.is_list_of_scalars() ? list_phrase(param, count_text(param)) : scalar_phrase(param, false);
  }
}

int Values::line(const std::string& path) const {
  for (std::string p = path;; p = parent_of(p)) {
    const auto found = entries_.find(p);
    if (found != entries_.end()) return found->second.line;
    if (p.empty()) return -1;
  }
}

void Values::fail(const std::string& path, const std::string& expected, const std::string& got) const {
  scene::fail(file_, line(path), path, expected, got);
}

void Values::fail(const std::string& path, const std::string& message) const {
  const int at = line(path);
  throw InputError(file_ + (at > 0 ? ":" + std::to_string(at) : "") + ": " + message);
}

void fail(const std::string& file, int line, const std::string& path, const std::string& expected,
          const std::string& got) {
  throw InputError(file + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                   (path.empty() ? "" : path + ": ") + "expected " + expected + ", got " + got);
}

namespace {

/// InputError when `node` (the document, or a value given for `path`) expands to too many nodes.
void check_node_limit(const YAML::Node& node, const std::string& file, const std::string& path) {
  int line = -1;
  std::string where;
  if (!exceeds_node_limit(node, kMaxDocumentNodes, path, where, line)) return;
  fail(file, line, where, "at most " + std::to_string(kMaxDocumentNodes) + " YAML nodes with aliases expanded",
       "more (nested aliases?)");
}

}  // namespace

YAML::Node parse_yaml(const std::string& text, const std::string& file) {
  YAML::Node document;
  try {
    document = YAML::Load(text);
  } catch (const YAML::ParserException& error) {
    fail(file, error.mark.line >= 0 ? error.mark.line + 1 : -1, "", "valid YAML",
         "a syntax error (" + error.msg + ")");
  }
  check_node_limit(document, file, "");
  return document;
}

Values validate(const Param& root, const YAML::Node& document, const std::string& file) {
  if (!document.IsDefined() || document.IsNull()) fail(file, -1, "", describe(root), "an empty file");
  Values values(file);
  Validator(values).visit(root, document, "", mark_line(document), false);
  return values;
}

void apply_override(YAML::Node& document, const std::string& path, const std::string& value,
                    const std::string& file) {
  std::vector<PathStep> steps;
  if (!split_path(path, steps) || steps.front().key.empty()) {
    fail(file, -1, "", "a key path like crack.region.z or boundary[0].face", "'" + path + "'");
  }
  YAML::Node parsed;
  try {
    parsed = YAML::Load(value);
  } catch (const YAML::ParserException& error) {
    fail(file, -1, path, "a YAML value", "'" + value + "' (" + error.msg + ")");
  }
  check_node_limit(parsed, file, path);
  YAML::Node node = document;  // yaml-cpp nodes are references: `node` walks through `document`
  std::string where;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (step.key.empty()) {
      if (!node.IsSequence()) fail(file, -1, where, "a list to index", describe_node(node));
      if (step.index >= node.size()) {
        fail(file, -1, where, "a list with an entry " + std::to_string(step.index), describe_node(node));
      }
      if (last) {
        node[step.index] = without_marks(parsed);
      } else {
        node.reset(node[step.index]);
      }
    } else {
      if (!node.IsMap() && !node.IsNull()) fail(file, -1, where, "a map", describe_node(node));
      if (last) {
        if (node.IsMap()) node.remove(step.key);  // a fresh key carries no line either
        node[step.key] = without_marks(parsed);
      } else {
        if (!node[step.key].IsDefined() || node[step.key].IsNull())
          node[step.key] = YAML::Node(YAML::NodeType::Map);
        node.reset(node[step.key]);
      }
    }
    where = step.path;
  }
}

std::string markdown_table(const Param& root) {
  std::ostringstream out;
  out << "| Key | Type | Range | Default | Unit | Description |\n";
  out << "|---|---|---|---|---|---|\n";
  std::function<void(const Param&, const std::string&)> rows = [&](const Param& param,
                                                                   const std::string& prefix) {
    for (const Param& p : param.children) {
      const std::string path = prefix + p.name;
      std::string type, range;
      switch (p.kind) {
        case Kind::map:
          type = p.is_one_of ? "one of" : "map";
          if (!p.scalar_child.empty()) type += " (or a value for its `" + p.scalar_child + "`)";
          break;
        case Kind::list:
          type = "list of maps";
          break;
        default: {
          static const std::map<Kind, std::string> nouns = {{Kind::number, "number"},
                                                            {Kind::integer, "integer"},
                                                            {Kind::choice, "choice"},
                                                            {Kind::boolean, "bool"},
                                                            {Kind::text, "text"}};
          type = nouns.at(p.kind);
          range = p.kind == Kind::choice    ? join(p.choices)
                  : p.kind == Kind::boolean ? "true, false"
                  : p.kind == Kind::text    ? ""
                                            : range_text(p);
          if (!p.word_alternative.empty()) range += (range.empty() ? "" : "; ") + std::string("or `") + p.word_alternative + "`";
          if (p.is_list_of_scalars()) {
            type = "list of " + (p.length_of.empty() ? count_text(p) + " " : "") +
                   (p.is_distinct ? "distinct " : "") + (p.is_increasing ? "increasing " : "") + type + "s" +
                   (p.length_of.empty() ? "" : ", one per entry of " + p.length_of);
          }
        }
      }
      std::string default_cell = p.is_required ? "required" : "";
      if (!p.default_text.empty())
        default_cell = p.default_rule ? p.default_text : "`" + p.default_text + "`";
      out << "| `" << path << "` | " << type << " | " << range << " | " << default_cell << " | " << p.unit
          << " | " << p.doc << " |\n";
      if (p.kind == Kind::map) rows(p, path + ".");
      if (p.kind == Kind::list) rows(p, path + "[].");
    }
  };
  rows(root, "");
  return out.str();
}

}  // namespace crackle::scene
